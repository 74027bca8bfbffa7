// rostest: the node's diagnostics (README "Diagnostics"): levels and values.

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <atomic>

#include "node_listener.h"
#include "particle_sim/SetSpringConstants.h"
#include "particle_sim/SpawnRope.h"
#include "sim_probe.h"

using diagnostic_msgs::DiagnosticStatus;
using particle_sim_test::call;
using particle_sim_test::SimProbe;
using particle_sim_test::waitForWall;

namespace
{
std::string value(const DiagnosticStatus& status, const std::string& key)
{
  for (const auto& kv : status.values)
    if (kv.key == key) return kv.value;
  return "";
}

class DiagnosticsTest : public ::testing::Test
{
protected:
  static void SetUpTestSuite()
  {
    for (const char* s : {"set_parameters", "set_spring_constants", "spawn_rope"})
      ASSERT_TRUE(ros::service::waitForService(std::string("/particle_sim/") + s, ros::Duration(30.0))) << s;
  }
  // Waits for a diagnostic status, received after this call, that satisfies `predicate`; returns it
  // (or the last one received if none did).
  template <typename Predicate>
  DiagnosticStatus waitForDiagnostic(Predicate predicate, double seconds = 30.0)
  {
    const std::size_t first = probe_.diagnostics().size();
    DiagnosticStatus found;
    found.level = 255;
    waitForWall(
        [&] {
          const auto all = probe_.diagnostics();
          for (std::size_t i = first; i < all.size(); ++i)
          {
            found = all[i];
            if (predicate(all[i])) return true;
          }
          return false;
        },
        seconds);
    return found;
  }
  ros::NodeHandle nh_;
  SimProbe probe_{nh_};
};
}  // namespace

TEST_F(DiagnosticsTest, OkWhenKeepingUpThenWarnUnderLoadThenErrorAfterAFrozenBody)
{
  // Keeping up with the node's target real-time factor, ~keep_up_real_time_factor (1, or less for a
  // sanitizer build), allowing for a loaded machine: one OK update is enough.
  double keep_up = 1.0;
  ros::NodeHandle("~").param("keep_up_real_time_factor", keep_up, keep_up);
  DiagnosticStatus status =
      waitForDiagnostic([](const DiagnosticStatus& s) { return s.level == DiagnosticStatus::OK; });
  ASSERT_EQ(status.level, DiagnosticStatus::OK) << status.message;
  EXPECT_EQ(status.message, "running");
  EXPECT_EQ(value(status, "live particles"), "64");  // the 8 x 8 cloth
  EXPECT_EQ(value(status, "frozen bodies"), "0");
  // The cloth steps by implicit Euler, and linear_solver auto solves a body this small directly.
  EXPECT_EQ(value(status, "implicit solves (last step)"), "1");
  EXPECT_EQ(value(status, "direct solves (last step)"), "1");
  EXPECT_EQ(value(status, "solver iterations (max, last step)"), "0");
  EXPECT_NE(value(status, "step time [us]"), "");
  EXPECT_NE(value(status, "max strain"), "");
  EXPECT_NE(value(status, "solver residual (max, last step)"), "");

  // Under load: 1000 times real time is out of reach for an implicit 8 x 8 cloth at dt = 2 ms
  // (500 000 steps per second).
  probe_.reconfigure({{"real_time_factor", 1000.0}});
  status = waitForDiagnostic([](const DiagnosticStatus& s) { return s.level == DiagnosticStatus::WARN; });
  ASSERT_EQ(status.level, DiagnosticStatus::WARN) << status.message;
  EXPECT_NE(status.message.find("real-time factor"), std::string::npos) << status.message;
  EXPECT_EQ(value(status, "target real-time factor"), "1000");

  // Back to the reachable target: OK again.
  probe_.reconfigure({{"real_time_factor", keep_up}});
  status = waitForDiagnostic([](const DiagnosticStatus& s) { return s.level == DiagnosticStatus::OK; });
  ASSERT_EQ(status.level, DiagnosticStatus::OK) << status.message;

  // A rope stepped by symplectic Euler far beyond its stability limit turns non-finite and freezes:
  // ERROR, naming the body, for as long as it is frozen.
  particle_sim::SpawnRope::Request rope;
  rope.name = "doomed";
  rope.particles = 6;
  rope.start.z = 1.0;
  rope.end.x = 1.0;
  rope.end.z = 1.0;
  rope.mass = 0.1;
  rope.stretch_stiffness = 100.0;
  rope.pins = {0};
  rope.integrator = "symplectic_euler";
  const auto spawned = call<particle_sim::SpawnRope>("spawn_rope", rope);
  ASSERT_TRUE(spawned.success) << spawned.message;
  particle_sim::SetSpringConstants::Request stiff;
  stiff.body = "doomed";
  stiff.spring_class = "all";
  stiff.stiffness = 1e9;  // the largest allowed (core/limits.h)
  const auto set = call<particle_sim::SetSpringConstants>("set_spring_constants", stiff);
  ASSERT_TRUE(set.success) << set.message;

  status = waitForDiagnostic([](const DiagnosticStatus& s) { return s.level == DiagnosticStatus::ERROR; });
  ASSERT_EQ(status.level, DiagnosticStatus::ERROR) << status.message;
  EXPECT_NE(status.message.find("frozen bodies: doomed"), std::string::npos) << status.message;
  EXPECT_EQ(value(status, "frozen bodies"), "1");
  EXPECT_TRUE(waitForWall([&] { return probe_.body("doomed").frozen; }));
  EXPECT_FALSE(probe_.body("doomed").frozen_reason.empty());
  EXPECT_FALSE(probe_.body("sheet").frozen);  // the rest of the world goes on
  status = waitForDiagnostic([](const DiagnosticStatus&) { return true; });
  EXPECT_EQ(status.level, DiagnosticStatus::ERROR) << "a frozen body stays an ERROR";
}

TEST_F(DiagnosticsTest, CountTheTicksWhoseMarkersWereSentAndOnlyWhileSomeoneSubscribes)
{
  // Nobody subscribes to markers, meshes or clouds: no tick sends them, none skips them.
  const auto count = [](const DiagnosticStatus& s, const char* what) {
    const std::string text = value(s, std::string("ticks of markers, meshes and clouds ") + what);
    return text.empty() ? -1LL : std::stoll(text);
  };
  DiagnosticStatus status = waitForDiagnostic([](const DiagnosticStatus&) { return true; });
  EXPECT_EQ(count(status, "sent since last report"), 0);
  EXPECT_EQ(count(status, "skipped since last report (publishing thread busy)"), 0);

  // A marker subscriber: the ticks of a report send them (the 8 x 8 cloth is light enough for the
  // publishing thread to keep up), and arrays arrive.
  std::atomic<int> arrays{0};
  ros::Subscriber markers = nh_.subscribe<visualization_msgs::MarkerArray>(
      "/particle_sim/markers", 10, [&arrays](const visualization_msgs::MarkerArray::ConstPtr&) { ++arrays; });
  status = waitForDiagnostic([&](const DiagnosticStatus& s) { return count(s, "sent since last report") > 0; });
  EXPECT_GT(count(status, "sent since last report"), 0);
  EXPECT_GE(count(status, "skipped since last report (publishing thread busy)"), 0);
  EXPECT_TRUE(waitForWall([&] { return arrays.load() > 0; }));
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "diagnostics_test");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
