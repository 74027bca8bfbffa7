// rostest: the node's services, called like a user would, checked against what it publishes.

#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <std_srvs/Trigger.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>

#include "node_listener.h"
#include "particle_sim/RemoveBody.h"
#include "particle_sim/SpawnEmitter.h"
#include "particle_sim/Step.h"

using particle_sim::RemoveBody;
using particle_sim::SpawnEmitter;
using particle_sim::Step;
using particle_sim_test::call;
using particle_sim_test::Listener;
using visualization_msgs::Marker;

namespace
{
constexpr double kDt = 0.002;  // world.dt of test_services.yaml

SpawnEmitter::Request emitterRequest(const std::string& name, const std::string& type)
{
  SpawnEmitter::Request req;
  req.name = name;
  req.type = type;
  req.origin.x = 1.0;
  req.rate = 100.0;
  req.speed = 5.0;
  req.spread = 1.0;
  return req;
}

std_srvs::Trigger::Response trigger(const std::string& name)
{
  return call<std_srvs::Trigger>(name, {});
}

class ServicesTest : public ::testing::Test
{
protected:
  static void SetUpTestSuite()
  {
    for (const char* s : {"spawn_emitter", "remove_body", "reset", "pause_physics", "unpause_physics", "step"})
      ASSERT_TRUE(ros::service::waitForService(std::string("/particle_sim/") + s, ros::Duration(30.0))) << s;
  }
  ros::NodeHandle nh_;
  Listener listener_{nh_};
};
}  // namespace

TEST_F(ServicesTest, SpawnEmitterAddsParticlesToTheMarkersAndRemoveBodyTakesThemAway)
{
  const auto spawned = call<SpawnEmitter>("spawn_emitter", emitterRequest("spray", "semi_sphere"));
  ASSERT_TRUE(spawned.success) << spawned.message;
  ASSERT_TRUE(listener_.waitFor([&] {
    const Marker m = listener_.latest("spray");
    return m.action == Marker::ADD && m.points.size() > 10;
  })) << "no particles of 'spray' in ~markers";
  const Marker m = listener_.latest("spray");
  EXPECT_EQ(m.type, Marker::POINTS);
  EXPECT_EQ(m.colors.size(), m.points.size());
  EXPECT_EQ(m.header.frame_id, "world");

  const auto removed = call<RemoveBody>("remove_body", [] {
    RemoveBody::Request r;
    r.name = "spray";
    return r;
  }());
  ASSERT_TRUE(removed.success) << removed.message;
  EXPECT_TRUE(listener_.waitFor([&] { return listener_.latest("spray").action == Marker::DELETE; }))
      << "no DELETE for 'spray' after remove_body";

  RemoveBody::Request again;
  again.name = "spray";
  const auto missing = call<RemoveBody>("remove_body", again);
  EXPECT_FALSE(missing.success);
  EXPECT_NE(missing.message.find("spray"), std::string::npos) << missing.message;
}

TEST_F(ServicesTest, BadSpawnRequestsAreRefusedWithAMessageAndTheNodeKeepsPublishing)
{
  struct Case
  {
    std::string expected;  // part of the message
    SpawnEmitter::Request req;
  };
  std::vector<Case> cases;
  cases.push_back({"type = 'geyser' is not an emitter type", emitterRequest("bad1", "geyser")});
  cases.push_back({"rate = -5 is out of range", emitterRequest("bad2", "fountain")});
  cases.back().req.rate = -5.0;
  cases.push_back({"origin = [nan, 0, 0] is not finite", emitterRequest("bad3", "fountain")});
  cases.back().req.origin.x = std::nan("");
  cases.push_back({"name = 'fountain' is already taken", emitterRequest("fountain", "fountain")});
  cases.push_back({"max_particles = 4000 is out of range: must be in [1, 3000]", emitterRequest("bad5", "fountain")});
  cases.back().req.max_particles = 4000;
  cases.push_back({"name is empty", emitterRequest("", "fountain")});

  for (const Case& c : cases)
  {
    const auto res = call<SpawnEmitter>("spawn_emitter", c.req);
    EXPECT_FALSE(res.success) << c.expected;
    EXPECT_NE(res.message.find(c.expected), std::string::npos) << "message: " << res.message;
  }
  // Nothing was added and the node still publishes.
  EXPECT_EQ(listener_.latest("bad2").action, -1);
  const int before = listener_.arrays();
  EXPECT_TRUE(listener_.waitFor([&] { return listener_.arrays() > before + 5; }));
  EXPECT_EQ(listener_.latest("fountain").action, Marker::ADD);
}

TEST_F(ServicesTest, PauseStepAndUnpauseAdvanceSimTimeByExactlyNStepsOfDt)
{
  const auto paused = trigger("pause_physics");
  ASSERT_TRUE(paused.success) << paused.message;

  Step::Request one;
  one.steps = 1;
  const double t0 = call<Step>("step", one).sim_time;
  ros::WallDuration(0.3).sleep();  // paused: time must not move by itself

  Step::Request n;
  n.steps = 250;
  const auto stepped = call<Step>("step", n);
  ASSERT_TRUE(stepped.success) << stepped.message;
  EXPECT_NEAR(stepped.sim_time - t0, 250 * kDt, 1e-9);
  EXPECT_TRUE(listener_.waitFor([&] { return std::abs(listener_.clock() - stepped.sim_time) < 1e-9; }))
      << "/clock " << listener_.clock() << " != " << stepped.sim_time;

  Step::Request zero;
  zero.steps = 0;
  const auto refused = call<Step>("step", zero);
  EXPECT_FALSE(refused.success);
  EXPECT_NE(refused.message.find("steps = 0 is out of range"), std::string::npos) << refused.message;

  ASSERT_TRUE(trigger("unpause_physics").success);
  EXPECT_TRUE(listener_.waitFor([&] { return listener_.clock() > stepped.sim_time + 0.1; }));
  const auto running = call<Step>("step", one);
  EXPECT_FALSE(running.success);
  EXPECT_NE(running.message.find("pause_physics"), std::string::npos) << running.message;
}

TEST_F(ServicesTest, ResetRestartsBodiesAndKeepsSimTimeMonotonic)
{
  ASSERT_TRUE(listener_.waitFor([&] { return listener_.clock() > 0.5; }));
  // The fountain (200 particles/s, 1 s lifetime) is full by now; right after reset it is nearly empty.
  ASSERT_TRUE(listener_.waitFor([&] { return listener_.latest("fountain").points.size() > 150; }));
  const double before = listener_.clock();
  const auto res = trigger("reset");
  ASSERT_TRUE(res.success) << res.message;
  EXPECT_TRUE(listener_.waitFor([&] { return listener_.latest("fountain").points.size() < 60; }))
      << "the fountain did not restart";
  EXPECT_TRUE(listener_.waitFor([&] { return listener_.clock() > before + 0.2; }));
  EXPECT_FALSE(listener_.clockWentBack()) << "/clock went backwards";
}

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "particle_sim_services_test");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}
