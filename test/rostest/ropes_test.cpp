// rostest: ropes through the node's services: spawn_rope, pin_particle with each target kind
// (current, point, tf frame), unpin_particle and set_spring_constants, good and bad input.

#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/transform_broadcaster.h>

#include <Eigen/Core>
#include <atomic>
#include <cmath>
#include <thread>

#include "node_listener.h"
#include "particle_sim/PinParticle.h"
#include "particle_sim/SetSpringConstants.h"
#include "particle_sim/SpawnRope.h"
#include "particle_sim/Step.h"
#include "particle_sim/UnpinParticle.h"

using particle_sim::PinParticle;
using particle_sim::SetSpringConstants;
using particle_sim::SpawnRope;
using particle_sim::Step;
using particle_sim::UnpinParticle;
using particle_sim_test::call;
using particle_sim_test::Listener;
using visualization_msgs::Marker;

namespace
{
SpawnRope::Request ropeRequest(const std::string& name, double y)
{
  SpawnRope::Request req;
  req.name = name;
  req.particles = 12;
  req.start.y = req.end.y = y;
  req.start.z = req.end.z = 2.0;
  req.end.x = 1.1;
  req.mass = 0.2;
  req.stretch_stiffness = 800.0;
  req.stretch_damping = 0.3;
  req.pins = {0};
  return req;
}

Eigen::Vector3d pointOf(const Marker& m, int index)
{
  const auto& p = m.points.at(index);
  return {p.x, p.y, p.z};
}

// Length of a rope's LINE_STRIP [m].
double stripLength(const Marker& m)
{
  double length = 0.0;
  for (std::size_t i = 1; i < m.points.size(); ++i)
    length += (pointOf(m, i) - pointOf(m, i - 1)).norm();
  return length;
}

PinParticle::Request pinRequest(const std::string& body, int index, std::uint8_t target)
{
  PinParticle::Request req;
  req.body = body;
  req.index = index;
  req.target = target;
  return req;
}

class RopesTest : public ::testing::Test
{
protected:
  static void SetUpTestSuite()
  {
    for (const char* s : {"spawn_rope", "pin_particle", "unpin_particle", "set_spring_constants"})
      ASSERT_TRUE(ros::service::waitForService(std::string("/particle_sim/") + s, ros::Duration(30.0))) << s;
  }

  // Spawns a rope and waits until its LINE_STRIP is published.
  void spawn(const SpawnRope::Request& req)
  {
    const auto res = call<SpawnRope>("spawn_rope", req);
    ASSERT_TRUE(res.success) << res.message;
    ASSERT_TRUE(listener_.waitFor([&] { return listener_.latest(req.name, 1).points.size() == req.particles; }));
  }

  ros::NodeHandle nh_;
  Listener listener_{nh_};
};
}  // namespace

TEST_F(RopesTest, SpawnedRopeIsALineStripWithItsPinnedParticlesDrawnApart)
{
  SpawnRope::Request req = ropeRequest("drawn", 0.5);
  req.pins = {0, -1};
  spawn(req);
  const Marker line = listener_.latest("drawn", 1), free = listener_.latest("drawn", 0),
               pins = listener_.latest("drawn", 2);
  EXPECT_EQ(line.type, Marker::LINE_STRIP);
  EXPECT_GT(line.scale.x, 0.0);
  EXPECT_EQ(free.type, Marker::SPHERE_LIST);
  EXPECT_EQ(free.points.size(), 10u);
  EXPECT_EQ(pins.type, Marker::SPHERE_LIST);
  ASSERT_EQ(pins.points.size(), 2u);
  EXPECT_NEAR(pins.points[1].x, 1.1, 1e-9);  // the last particle, pinned where it started
}

TEST_F(RopesTest, BadSpawnRopeRequestsAreRefusedNamingTheField)
{
  std::vector<std::pair<std::string, SpawnRope::Request>> cases;
  cases.push_back({"particles = 1 is out of range", ropeRequest("bad_count", 1)});
  cases.back().second.particles = 1;
  cases.push_back({"stretch_stiffness = -5 is out of range", ropeRequest("bad_k", 1)});
  cases.back().second.stretch_stiffness = -5.0;
  cases.push_back({"start = [nan, 1, 2] is not finite", ropeRequest("bad_start", 1)});
  cases.back().second.start.x = std::nan("");
  cases.push_back({"pins[0] = 40 is out of range", ropeRequest("bad_pin", 1)});
  cases.back().second.pins = {40};
  cases.push_back({"integrator = 'euler' is not an integrator", ropeRequest("bad_integrator", 1)});
  cases.back().second.integrator = "euler";
  cases.push_back({"name = 'rope' is already taken", ropeRequest("rope", 1)});
  for (const auto& [expected, req] : cases)
  {
    const auto res = call<SpawnRope>("spawn_rope", req);
    EXPECT_FALSE(res.success) << expected;
    EXPECT_NE(res.message.find(expected), std::string::npos) << "message: " << res.message;
  }
  EXPECT_EQ(listener_.latest("bad_k", 1).action, -1);
}

TEST_F(RopesTest, PinWhereItIsHoldsTheParticleStill)
{
  spawn(ropeRequest("held", -0.5));
  ros::WallDuration(0.3).sleep();  // let it swing
  const auto res = call<PinParticle>("pin_particle", pinRequest("held", 11, PinParticle::Request::TARGET_CURRENT));
  ASSERT_TRUE(res.success) << res.message;
  ros::WallDuration(0.1).sleep();
  const Eigen::Vector3d first = pointOf(listener_.latest("held", 1), 11);
  ros::WallDuration(0.5).sleep();
  EXPECT_LT((pointOf(listener_.latest("held", 1), 11) - first).norm(), 1e-9);
  EXPECT_EQ(listener_.latest("held", 2).points.size(), 2u);
}

TEST_F(RopesTest, PinAtAPointTakesTheNearestParticleThere)
{
  spawn(ropeRequest("moved", -1.0));
  PinParticle::Request req = pinRequest("moved", -1, PinParticle::Request::TARGET_POINT);
  req.point.x = 1.0;  // nearest: particle 11 at x = 1.1 (the rope has not fallen far yet)
  req.point.y = -1.0;
  req.point.z = 2.5;
  const auto res = call<PinParticle>("pin_particle", req);
  ASSERT_TRUE(res.success) << res.message;
  EXPECT_GE(res.index, 9);
  EXPECT_TRUE(listener_.waitFor([&] {
    return (pointOf(listener_.latest("moved", 1), res.index) - Eigen::Vector3d(1.0, -1.0, 2.5)).norm() < 1e-9;
  }));
}

TEST_F(RopesTest, PinToAMovingTfFrameFollowsItAndUnpinReleasesIt)
{
  // A gripper frame circling at radius 0.5 m, 1 rad/s, 2 m up, broadcast at 100 Hz.
  std::atomic<bool> running{true};
  std::thread gripper([&] {
    tf2_ros::TransformBroadcaster broadcaster;
    const ros::WallTime start = ros::WallTime::now();
    while (running)
    {
      const double t = (ros::WallTime::now() - start).toSec();
      geometry_msgs::TransformStamped tf;
      tf.header.stamp = ros::Time::now();
      tf.header.frame_id = "world";
      tf.child_frame_id = "gripper";
      tf.transform.translation.x = 0.5 * std::cos(t);
      tf.transform.translation.y = 2.0 + 0.5 * std::sin(t);
      tf.transform.translation.z = 2.0;
      tf.transform.rotation.w = 1.0;
      broadcaster.sendTransform(tf);
      ros::WallDuration(0.01).sleep();
    }
  });

  spawn(ropeRequest("carried", 2.0));
  PinParticle::Request req = pinRequest("carried", 6, PinParticle::Request::TARGET_FRAME);
  req.frame = "gripper";
  req.offset.z = -0.25;  // held 25 cm below the frame's origin
  // The node answers at once from what tf has heard (a frame it has not heard of yet is refused):
  // ask again until the gripper's first transforms have reached it.
  PinParticle::Response res;
  listener_.waitFor([&] {
    res = call<PinParticle>("pin_particle", req);
    return res.success;
  });
  ASSERT_TRUE(res.success) << res.message;

  // The particle stays on the circle the offset point draws, and goes round it.
  double min_angle = 10.0, max_angle = -10.0;
  for (int k = 0; k < 30; ++k)
  {
    ros::WallDuration(0.05).sleep();
    const Eigen::Vector3d x = pointOf(listener_.latest("carried", 1), 6);
    const Eigen::Vector3d from_centre = x - Eigen::Vector3d(0.0, 2.0, 1.75);
    if (k < 4) continue;  // it first travels from where it was to the frame
    EXPECT_NEAR(from_centre.z(), 0.0, 1e-9);
    EXPECT_NEAR(from_centre.head<2>().norm(), 0.5, 0.01) << "particle at " << x.transpose();
    const double angle = std::atan2(from_centre.y(), from_centre.x());
    min_angle = std::min(min_angle, angle);
    max_angle = std::max(max_angle, angle);
  }
  EXPECT_GT(max_angle - min_angle, 0.8);  // about 1.3 s at 1 rad/s

  UnpinParticle::Request unpin;
  unpin.body = "carried";
  unpin.index = 6;
  const auto released = call<UnpinParticle>("unpin_particle", unpin);
  ASSERT_TRUE(released.success) << released.message;
  running = false;
  gripper.join();
  EXPECT_TRUE(listener_.waitFor([&] { return pointOf(listener_.latest("carried", 1), 6).z() < 1.5; }))
      << "the released particle did not fall";
  EXPECT_EQ(listener_.latest("carried", 2).points.size(), 1u);  // only particle 0 is still pinned

  const auto again = call<UnpinParticle>("unpin_particle", unpin);
  EXPECT_FALSE(again.success);
  EXPECT_NE(again.message.find("index = 6 is not pinned"), std::string::npos) << again.message;
}

TEST_F(RopesTest, BadPinRequestsAreRefused)
{
  PinParticle::Request req = pinRequest("nobody", 0, PinParticle::Request::TARGET_CURRENT);
  auto res = call<PinParticle>("pin_particle", req);
  EXPECT_FALSE(res.success);
  EXPECT_NE(res.message.find("body = 'nobody'"), std::string::npos) << res.message;

  req.body = "rope";
  req.index = 10;
  res = call<PinParticle>("pin_particle", req);
  EXPECT_FALSE(res.success);
  EXPECT_NE(res.message.find("index = 10 is out of range: must be in [0, 9]"), std::string::npos) << res.message;

  req.index = 3;
  req.target = 7;
  res = call<PinParticle>("pin_particle", req);
  EXPECT_FALSE(res.success);
  EXPECT_NE(res.message.find("target = 7 is out of range"), std::string::npos) << res.message;

  req.target = PinParticle::Request::TARGET_FRAME;
  req.frame = "no_such_frame";
  res = call<PinParticle>("pin_particle", req);
  EXPECT_FALSE(res.success);
  EXPECT_NE(res.message.find("frame = 'no_such_frame'"), std::string::npos) << res.message;
  // Nothing new was pinned: the scene's rope still has only particle 0 pinned.
  EXPECT_TRUE(listener_.waitFor([&] { return listener_.latest("rope", 2).action == Marker::ADD; }));
  EXPECT_EQ(listener_.latest("rope", 2).points.size(), 1u);
}

TEST_F(RopesTest, SetSpringConstantsChangesTheRopeAndRefusesBadValues)
{
  spawn(ropeRequest("soft", -2.0));
  ASSERT_TRUE(listener_.waitFor([&] { return stripLength(listener_.latest("soft", 1)) > 0.0; }));
  ros::WallDuration(1.0).sleep();
  const double stiff_length = stripLength(listener_.latest("soft", 1));

  SetSpringConstants::Request req;
  req.body = "soft";
  req.spring_class = "stretch";
  req.stiffness = 4.0;  // 200 times softer: the hanging rope stretches a lot
  req.damping = 0.3;
  const auto res = call<SetSpringConstants>("set_spring_constants", req);
  ASSERT_TRUE(res.success) << res.message;
  EXPECT_TRUE(listener_.waitFor([&] { return stripLength(listener_.latest("soft", 1)) > 1.3 * stiff_length; }))
      << "length stayed " << stripLength(listener_.latest("soft", 1)) << " m";

  std::vector<std::pair<std::string, SetSpringConstants::Request>> bad(5, {"", req});
  bad[0].first = "stiffness = -1 is out of range";
  bad[0].second.stiffness = -1.0;
  bad[1].first = "damping = nan is not a finite number";
  bad[1].second.damping = std::nan("");
  bad[2].first = "spring_class = 'twist' is not a spring class";
  bad[2].second.spring_class = "twist";
  bad[3].first = "has no such springs";
  bad[3].second.spring_class = "shear";
  bad[4].first = "body = 'ghost'";
  bad[4].second.body = "ghost";
  for (const auto& [expected, r] : bad)
  {
    const auto refused = call<SetSpringConstants>("set_spring_constants", r);
    EXPECT_FALSE(refused.success) << expected;
    EXPECT_NE(refused.message.find(expected), std::string::npos) << "message: " << refused.message;
  }
}

TEST_F(RopesTest, StiffnessJumpOnAnExplicitRopeIsReportedByTheServices)
{
  // A symplectic Euler rope made 10^4 times stiffer: set_spring_constants says how many substeps
  // it will now take, and ~step reports the stability event when it happens.
  SpawnRope::Request req = ropeRequest("explicit", -3.0);
  req.integrator = "symplectic_euler";
  req.stretch_stiffness = 100.0;
  spawn(req);
  std_srvs::Trigger pause;
  ASSERT_TRUE(ros::service::call("/particle_sim/pause_physics", pause));
  SetSpringConstants::Request k;
  k.body = "explicit";
  k.spring_class = "stretch";
  k.stiffness = 1e6;
  k.damping = 0.0;
  const auto set = call<SetSpringConstants>("set_spring_constants", k);
  ASSERT_TRUE(set.success) << set.message;
  EXPECT_NE(set.message.find("substep(s) per step"), std::string::npos) << set.message;

  Step::Request steps;
  steps.steps = 5;
  const auto stepped = call<Step>("step", steps);
  EXPECT_TRUE(stepped.success) << stepped.message;
  EXPECT_NE(stepped.message.find("stability events"), std::string::npos) << stepped.message;
  EXPECT_NE(stepped.message.find("'explicit'"), std::string::npos) << stepped.message;
  std_srvs::Trigger unpause;
  ASSERT_TRUE(ros::service::call("/particle_sim/unpause_physics", unpause));
  // It stays finite: its markers keep coming with the rope near its pin.
  ros::WallDuration(0.3).sleep();
  const Marker line = listener_.latest("explicit", 1);
  ASSERT_EQ(line.points.size(), 12u);
  EXPECT_LT((pointOf(line, 11) - pointOf(line, 0)).norm(), 1.5);
}

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "particle_sim_ropes_test");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}
