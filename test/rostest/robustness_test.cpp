// rostest: what the node keeps and says about bodies and frames: dynamic_reconfigure's ranges are
// the core's limits, a removed body leaves dynamic_reconfigure, a frozen body says so (status,
// diagnostics, log) with the integrator that ran, and a pin whose tf frame stops holds still and
// warns.

#include <dynamic_reconfigure/ConfigDescription.h>
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <tf2_ros/transform_broadcaster.h>

#include <Eigen/Core>
#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "node_listener.h"
#include "particle_sim/PinParticle.h"
#include "particle_sim/RemoveBody.h"
#include "particle_sim/SetSpringConstants.h"
#include "particle_sim/SpawnRope.h"
#include "particle_sim/core/limits.h"
#include "sim_probe.h"

using diagnostic_msgs::DiagnosticStatus;
using particle_sim::PinParticle;
using particle_sim::RemoveBody;
using particle_sim::SetSpringConstants;
using particle_sim::SpawnRope;
using particle_sim_test::call;
using particle_sim_test::Listener;
using particle_sim_test::SimProbe;
using particle_sim_test::waitForWall;
namespace limits = particle_sim::core::limits;

namespace
{
SpawnRope::Request rope(const std::string& name, double y)
{
  SpawnRope::Request req;
  req.name = name;
  req.particles = 6;
  req.start.y = y;
  req.start.z = 2.0;
  req.end.x = 1.0;
  req.end.y = y;
  req.end.z = 2.0;
  req.mass = 0.1;
  req.stretch_stiffness = 200.0;
  req.stretch_damping = 0.1;
  req.pins = {0};
  req.integrator = "implicit_euler";
  return req;
}

// Keeps /rosout messages and the latest ~parameter_descriptions.
class RosoutAndDescriptions
{
public:
  explicit RosoutAndDescriptions(ros::NodeHandle& nh)
  {
    rosout_sub_ = nh.subscribe("/rosout", 1000, &RosoutAndDescriptions::onLog, this);
    descriptions_sub_ =
        nh.subscribe("/particle_sim/parameter_descriptions", 1, &RosoutAndDescriptions::onDescriptions, this);
  }
  // True if some log line of the node at `level` contains every one of `parts`.
  bool logged(std::uint8_t level, const std::vector<std::string>& parts) const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& log : logs_)
    {
      if (log.level != level || log.name != "/particle_sim") continue;
      bool all = true;
      for (const std::string& part : parts)
        all = all && log.msg.find(part) != std::string::npos;
      if (all) return true;
    }
    return false;
  }
  // {name: (min, max)} of every double parameter described, empty before the first description.
  std::map<std::string, std::pair<double, double>> ranges() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return ranges_;
  }

private:
  void onLog(const rosgraph_msgs::Log::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    logs_.push_back(*msg);
  }
  void onDescriptions(const dynamic_reconfigure::ConfigDescription::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& min : msg->min.doubles)
      ranges_[min.name].first = min.value;
    for (const auto& max : msg->max.doubles)
      ranges_[max.name].second = max.value;
  }

public:
  // True once both subscriptions are connected to the node (/rosout: to this test and the node).
  bool connected() const { return rosout_sub_.getNumPublishers() >= 2 && descriptions_sub_.getNumPublishers() > 0; }

private:
  mutable std::mutex mutex_;
  std::vector<rosgraph_msgs::Log> logs_;
  std::map<std::string, std::pair<double, double>> ranges_;
  ros::Subscriber rosout_sub_, descriptions_sub_;
};

class RobustnessTest : public ::testing::Test
{
protected:
  static void SetUpTestSuite()
  {
    for (const char* s : {"spawn_rope", "remove_body", "set_spring_constants", "pin_particle", "set_parameters"})
      ASSERT_TRUE(ros::service::waitForService(std::string("/particle_sim/") + s, ros::Duration(30.0))) << s;
    // One subscription for the whole suite, connected before any test: a log line published
    // before a subscriber connects is lost to it.
    ros::NodeHandle nh;
    rosout_ = std::make_unique<RosoutAndDescriptions>(nh);
    ASSERT_TRUE(waitForWall([] { return rosout_->connected(); }));
  }
  static void TearDownTestSuite() { rosout_.reset(); }
  ros::NodeHandle nh_;
  SimProbe probe_{nh_};
  Listener listener_{nh_};
  static std::unique_ptr<RosoutAndDescriptions> rosout_;
};
std::unique_ptr<RosoutAndDescriptions> RobustnessTest::rosout_;
}  // namespace

TEST_F(RobustnessTest, DynamicReconfigureRangesAreTheCoreLimits)
{
  ASSERT_TRUE(waitForWall([&] { return !rosout_->ranges().empty(); }));
  const auto ranges = rosout_->ranges();
  const std::map<std::string, limits::Range> expected = {{"gravity_x", limits::kGravityComponent},
                                                         {"gravity_y", limits::kGravityComponent},
                                                         {"gravity_z", limits::kGravityComponent},
                                                         {"global_damping", limits::kGlobalDamping},
                                                         {"wind_x", limits::kWindComponent},
                                                         {"wind_y", limits::kWindComponent},
                                                         {"wind_z", limits::kWindComponent},
                                                         {"real_time_factor", limits::kRealTimeFactor},
                                                         {"rate", limits::kPublishRate},
                                                         {"stiffness", limits::kStiffness},
                                                         {"damping", limits::kDamping}};
  for (const auto& [name, range] : expected)
  {
    ASSERT_EQ(ranges.count(name), 1u) << name;
    EXPECT_EQ(ranges.at(name).first, range.min) << name;
    EXPECT_EQ(ranges.at(name).second, range.max) << name;
  }
  EXPECT_EQ(ranges.at("real_time_factor").first, 0.0);  // 0 = as fast as possible; nothing below
}

TEST_F(RobustnessTest, ARemovedBodyLeavesDynamicReconfigure)
{
  ASSERT_TRUE(call<SpawnRope>("spawn_rope", rope("shown", 1.0)).success);
  SetSpringConstants::Request set;
  set.body = "shown";
  set.spring_class = "stretch";
  set.stiffness = 300.0;
  set.damping = 0.2;
  ASSERT_TRUE(call<SetSpringConstants>("set_spring_constants", set).success);
  ASSERT_TRUE(waitForWall([&] { return probe_.config().strs["body"] == "shown"; }));

  RemoveBody::Request removal;
  removal.name = "shown";
  ASSERT_TRUE(call<RemoveBody>("remove_body", removal).success);
  EXPECT_TRUE(waitForWall([&] { return probe_.config().strs["body"] != "shown"; }, 5.0))
      << "dynamic_reconfigure still shows the removed body";
  // It shows a body that exists (the scene's rope), with that body's constants.
  EXPECT_EQ(probe_.config().strs["body"], "rope");
  EXPECT_EQ(probe_.config().doubles["stiffness"], 800.0);
}

TEST_F(RobustnessTest, AFrozenBodySaysSoWithTheIntegratorThatRan)
{
  // Symplectic Euler at the largest stiffness allowed, on 1/60 kg beads: it would need hundreds of
  // substeps (max_substeps is 64), blows up and is frozen at its first step.
  SpawnRope::Request req = rope("brittle", -1.0);
  req.integrator = "symplectic_euler";
  req.stretch_stiffness = limits::kStiffness.max;
  const auto spawned = call<SpawnRope>("spawn_rope", req);
  ASSERT_TRUE(spawned.success) << spawned.message;

  ASSERT_TRUE(waitForWall([&] { return probe_.body("brittle").frozen; }, 10.0)) << "not frozen";
  const auto body = probe_.body("brittle");
  EXPECT_NE(body.frozen_reason.find("symplectic_euler"), std::string::npos) << body.frozen_reason;
  EXPECT_EQ(body.integrator, "symplectic_euler");
  EXPECT_EQ(body.last_integrator, "symplectic_euler") << "status reports an integrator that did not run";
  EXPECT_FALSE(probe_.body("rope").frozen);  // the rest of the world goes on

  // /diagnostics: ERROR naming the body, the integrator and the reason.
  EXPECT_TRUE(waitForWall([&] {
    for (const auto& d : probe_.diagnostics())
      if (d.level == DiagnosticStatus::ERROR &&
          d.message.find("brittle (symplectic_euler: " + body.frozen_reason + ")") != std::string::npos)
        return true;
    return false;
  })) << "no ERROR diagnostic naming 'brittle', symplectic_euler and the reason";
  // The log: once, as an ERROR naming the body, the integrator and the reason.
  EXPECT_TRUE(waitForWall([&] {
    return rosout_->logged(rosgraph_msgs::Log::ERROR,
                           {"'brittle' is frozen", "last ran symplectic_euler", body.frozen_reason});
  })) << "no ERROR in the log";
}

TEST_F(RobustnessTest, APinWhoseFrameStopsHoldsStillAndWarns)
{
  // A frame 'hand' moving along x at 0.2 m/s, broadcast at 50 Hz, then no more.
  std::atomic<bool> broadcasting{true};
  std::thread hand([&] {
    tf2_ros::TransformBroadcaster broadcaster;
    const ros::WallTime start = ros::WallTime::now();
    while (broadcasting)
    {
      geometry_msgs::TransformStamped tf;
      tf.header.stamp = ros::Time::now();
      tf.header.frame_id = "world";
      tf.child_frame_id = "hand";
      tf.transform.translation.x = 0.2 * (ros::WallTime::now() - start).toSec();
      tf.transform.translation.y = 3.0;
      tf.transform.translation.z = 2.0;
      tf.transform.rotation.w = 1.0;
      broadcaster.sendTransform(tf);
      ros::WallDuration(0.02).sleep();
    }
  });
  ASSERT_TRUE(call<SpawnRope>("spawn_rope", rope("held", 3.0)).success);
  PinParticle::Request pin;
  pin.body = "held";
  pin.index = 5;
  pin.target = PinParticle::Request::TARGET_FRAME;
  pin.frame = "hand";
  ASSERT_TRUE(waitForWall([&] { return call<PinParticle>("pin_particle", pin).success; }, 5.0));
  const auto particle = [&] {
    const auto& p = listener_.latest("held", 2).points;  // the pinned particles: 0 and 5
    return p.size() == 2 ? Eigen::Vector3d(p[1].x, p[1].y, p[1].z) : Eigen::Vector3d::Constant(1e9);
  };
  ros::WallDuration(0.5).sleep();
  const Eigen::Vector3d moving = particle();
  ros::WallDuration(0.3).sleep();
  EXPECT_GT((particle() - moving).norm(), 0.02) << "the pin does not follow the frame";

  // The frame stops: after the timeout the pin holds still, and the node warns.
  broadcasting = false;
  hand.join();
  ros::WallDuration(1.5).sleep();
  const Eigen::Vector3d held = particle();
  ros::WallDuration(0.5).sleep();
  EXPECT_LT((particle() - held).norm(), 1e-12);
  EXPECT_TRUE(waitForWall(
      [&] {
        return rosout_->logged(rosgraph_msgs::Log::WARN,
                               {"particle 5 of 'held' follows frame 'hand'", "not available", "holds still"});
      },
      10.0))
      << "no warning that the frame is gone";
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "robustness_test");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
