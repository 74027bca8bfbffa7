// rostest: /clock and tf from sim time, with /use_sim_time true (README "Time").

#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <std_srvs/Trigger.h>
#include <tf2_msgs/TFMessage.h>

#include <mutex>
#include <vector>

#include "particle_sim/Step.h"

namespace
{
constexpr double kDt = 0.002;  // world.dt of test_ropes.yaml

// Everything received on /clock and the stamps of the node's own transform (map -> world) on /tf.
class TimeRecorder
{
public:
  explicit TimeRecorder(ros::NodeHandle& nh)
  {
    clock_sub_ = nh.subscribe("/clock", 1000, &TimeRecorder::onClock, this);
    tf_sub_ = nh.subscribe("/tf", 1000, &TimeRecorder::onTf, this);
  }
  std::vector<double> clocks() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return clocks_;
  }
  std::vector<double> tfStamps() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return tf_stamps_;
  }

private:
  void onClock(const rosgraph_msgs::Clock::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    clocks_.push_back(msg->clock.toSec());
  }
  void onTf(const tf2_msgs::TFMessage::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& t : msg->transforms)
      if (t.header.frame_id == "map" && t.child_frame_id == "world") tf_stamps_.push_back(t.header.stamp.toSec());
  }
  mutable std::mutex mutex_;
  std::vector<double> clocks_, tf_stamps_;
  ros::Subscriber clock_sub_, tf_sub_;
};

// Waits on wall time: ROS time is the node's /clock, which stands still while paused.
template <typename Predicate>
bool waitFor(Predicate predicate, double seconds = 20.0)
{
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::WallTime::now() < end)
  {
    if (predicate()) return true;
    ros::WallDuration(0.02).sleep();
  }
  return predicate();
}

bool trigger(const std::string& name, std::string* message = nullptr)
{
  std_srvs::Trigger srv;
  EXPECT_TRUE(ros::service::call("/particle_sim/" + name, srv)) << name;
  if (message) *message = srv.response.message;
  return srv.response.success;
}

double stepN(std::uint32_t steps)
{
  particle_sim::Step srv;
  srv.request.steps = steps;
  EXPECT_TRUE(ros::service::call("/particle_sim/step", srv));
  EXPECT_TRUE(srv.response.success) << srv.response.message;
  return srv.response.sim_time;
}

void expectStrictlyIncreasingAndPositive(const std::vector<double>& values, const char* what)
{
  ASSERT_FALSE(values.empty()) << what;
  EXPECT_GT(values.front(), 0.0) << what << " starts at 0";
  for (std::size_t i = 1; i < values.size(); ++i)
    EXPECT_GT(values[i], values[i - 1]) << what << " " << i << ": " << values[i - 1] << " then " << values[i];
}
}  // namespace

TEST(Time, ClockAndTfAreMonotonicAcrossPauseStepResetAndNotRepeatedWhilePaused)
{
  ros::NodeHandle nh;
  bool use_sim_time = false;
  ASSERT_TRUE(ros::param::get("/use_sim_time", use_sim_time));
  ASSERT_TRUE(use_sim_time) << "the launch file sets /use_sim_time";
  for (const char* s : {"pause_physics", "unpause_physics", "step", "reset"})
    ASSERT_TRUE(ros::service::waitForService(std::string("/particle_sim/") + s, ros::Duration(30.0))) << s;

  TimeRecorder recorder(nh);
  ASSERT_TRUE(waitFor([&] { return recorder.clocks().size() >= 10 && recorder.tfStamps().size() >= 10; }))
      << "no /clock or tf from the running node";
  // Our own ROS time follows the node's /clock.
  ASSERT_TRUE(waitFor([] { return ros::Time::now().toSec() > 0.0; }));

  // Paused: nothing new on /clock, no tf re-sent with the same stamp. The node still serves its
  // services, although ROS time stands still.
  ASSERT_TRUE(trigger("pause_physics"));
  ros::WallDuration(0.3).sleep();  // what was on its way arrives
  const std::size_t clocks_paused = recorder.clocks().size();
  const std::size_t tf_paused = recorder.tfStamps().size();
  const double time_paused = recorder.clocks().back();
  ros::WallDuration(1.0).sleep();
  EXPECT_EQ(recorder.clocks().size(), clocks_paused) << "/clock published while paused";
  EXPECT_EQ(recorder.tfStamps().size(), tf_paused) << "tf re-sent while paused";

  // ~step advances exactly N steps: one new /clock and one new tf at that time.
  const double stepped = stepN(10);
  EXPECT_NEAR(stepped, time_paused + 10 * kDt, 1e-9);
  ASSERT_TRUE(waitFor([&] { return recorder.clocks().size() == clocks_paused + 1; }));
  EXPECT_NEAR(recorder.clocks().back(), stepped, 1e-9);
  ASSERT_TRUE(waitFor([&] { return recorder.tfStamps().size() == tf_paused + 1; }));
  EXPECT_NEAR(recorder.tfStamps().back(), stepped, 1e-9);

  // Reset while paused: the bodies go back, time does not; stepping goes on from there.
  ASSERT_TRUE(trigger("reset"));
  const double after_reset = stepN(1);
  EXPECT_NEAR(after_reset, stepped + kDt, 1e-9);

  // Unpaused: time runs on, forward.
  ASSERT_TRUE(trigger("unpause_physics"));
  ASSERT_TRUE(waitFor([&] { return recorder.clocks().back() > after_reset + 0.5; }));
  ASSERT_TRUE(trigger("reset"));
  const double at_reset = recorder.clocks().back();
  ASSERT_TRUE(waitFor([&] { return recorder.clocks().back() > at_reset + 0.2; }));

  expectStrictlyIncreasingAndPositive(recorder.clocks(), "/clock");
  expectStrictlyIncreasingAndPositive(recorder.tfStamps(), "tf map -> world");
  // The node never writes /use_sim_time.
  ASSERT_TRUE(ros::param::get("/use_sim_time", use_sim_time));
  EXPECT_TRUE(use_sim_time);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "time_test");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
