#pragma once
// Shared by the rostest gtest nodes: what the node publishes, and service calls.

#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <visualization_msgs/MarkerArray.h>

#include <map>
#include <mutex>
#include <string>

namespace particle_sim_test
{
using visualization_msgs::Marker;
using visualization_msgs::MarkerArray;

// Keeps what the node publishes: the last marker of each (namespace, id), the number of arrays
// and /clock.
class Listener
{
public:
  explicit Listener(ros::NodeHandle& nh)
  {
    markers_sub_ = nh.subscribe("/particle_sim/markers", 10, &Listener::onMarkers, this);
    clock_sub_ = nh.subscribe("/clock", 10, &Listener::onClock, this);
  }

  int arrays() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return arrays_;
  }
  // The latest marker (ns, id), or one with action -1 if none arrived.
  Marker latest(const std::string& ns, int id = 0) const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = latest_.find({ns, id});
    if (it != latest_.end()) return it->second;
    Marker none;
    none.action = -1;
    return none;
  }
  double clock() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return clock_;
  }
  bool clockWentBack() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return clock_went_back_;
  }

  // Waits up to `seconds` of wall time for `predicate`.
  template <typename Predicate>
  bool waitFor(Predicate predicate, double seconds = 10.0) const
  {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
    while (ros::WallTime::now() < end)
    {
      if (predicate()) return true;
      ros::WallDuration(0.02).sleep();
    }
    return predicate();
  }

private:
  void onMarkers(const MarkerArray::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++arrays_;
    for (const Marker& m : msg->markers)
      latest_[{m.ns, m.id}] = m;
  }
  void onClock(const rosgraph_msgs::Clock::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (msg->clock.toSec() < clock_) clock_went_back_ = true;
    clock_ = msg->clock.toSec();
  }

  mutable std::mutex mutex_;
  int arrays_ = 0;
  std::map<std::pair<std::string, int>, Marker> latest_;
  double clock_ = 0.0;
  bool clock_went_back_ = false;
  // Last, so that they are shut down first, before the state their callbacks write.
  ros::Subscriber markers_sub_, clock_sub_;
};

template <typename Service>
typename Service::Response call(const std::string& name, typename Service::Request req)
{
  Service srv;
  srv.request = req;
  EXPECT_TRUE(ros::service::call("/particle_sim/" + name, srv)) << name;
  return srv.response;
}

}  // namespace particle_sim_test
