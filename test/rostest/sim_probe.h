#pragma once
// Shared by the rostest gtest nodes that watch ~status, dynamic_reconfigure and /diagnostics.

#include <diagnostic_msgs/DiagnosticArray.h>
#include <dynamic_reconfigure/Config.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "particle_sim/SimStatus.h"

namespace particle_sim_test
{
// Waits up to `seconds` of wall time for `predicate`.
template <typename Predicate>
bool waitForWall(Predicate predicate, double seconds = 20.0)
{
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::WallTime::now() < end)
  {
    if (predicate()) return true;
    ros::WallDuration(0.02).sleep();
  }
  return predicate();
}

// A dynamic_reconfigure config as plain maps.
struct ConfigValues
{
  std::map<std::string, double> doubles;
  std::map<std::string, std::string> strs;
  explicit ConfigValues(const dynamic_reconfigure::Config& config = {})
  {
    for (const auto& p : config.doubles)
      doubles[p.name] = p.value;
    for (const auto& p : config.strs)
      strs[p.name] = p.value;
  }
};

// Watches ~status, ~parameter_updates and /diagnostics of the node in namespace `ns`.
class SimProbe
{
public:
  SimProbe(ros::NodeHandle& nh, const std::string& ns = "/particle_sim") : ns_(ns)
  {
    status_sub_ = nh.subscribe(ns + "/status", 100, &SimProbe::onStatus, this);
    updates_sub_ = nh.subscribe(ns + "/parameter_updates", 10, &SimProbe::onUpdate, this);
    diagnostics_sub_ = nh.subscribe("/diagnostics", 100, &SimProbe::onDiagnostics, this);
  }

  // The latest status, or one with no body and sim_time −1 if none arrived.
  particle_sim::SimStatus status() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (statuses_.empty())
    {
      particle_sim::SimStatus none;
      none.sim_time = -1.0;
      return none;
    }
    return statuses_.back();
  }
  // Every status received so far.
  std::vector<particle_sim::SimStatus> statuses() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return statuses_;
  }
  // The latest status of `body`; its name is empty if it was not in the latest status.
  particle_sim::BodyStatus body(const std::string& name) const
  {
    for (const auto& b : status().bodies)
      if (b.name == name) return b;
    return {};
  }
  ConfigValues config() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return config_;
  }
  int updates() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return updates_;
  }
  // The node's diagnostic statuses received so far (name ends in ": simulation").
  std::vector<diagnostic_msgs::DiagnosticStatus> diagnostics() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return diagnostics_;
  }

  // Calls ~set_parameters and returns the config the node answers with.
  ConfigValues reconfigure(const std::map<std::string, double>& doubles,
                           const std::map<std::string, std::string>& strs = {}) const
  {
    dynamic_reconfigure::Reconfigure srv;
    for (const auto& [name, value] : doubles)
    {
      dynamic_reconfigure::DoubleParameter p;
      p.name = name;
      p.value = value;
      srv.request.config.doubles.push_back(p);
    }
    for (const auto& [name, value] : strs)
    {
      dynamic_reconfigure::StrParameter p;
      p.name = name;
      p.value = value;
      srv.request.config.strs.push_back(p);
    }
    EXPECT_TRUE(ros::service::call(ns_ + "/set_parameters", srv));
    return ConfigValues(srv.response.config);
  }

private:
  void onStatus(const particle_sim::SimStatus::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    statuses_.push_back(*msg);
  }
  void onUpdate(const dynamic_reconfigure::Config::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    config_ = ConfigValues(*msg);
    ++updates_;
  }
  void onDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const std::string suffix = ": simulation";
    for (const auto& s : msg->status)
      if (s.name.size() >= suffix.size() && s.name.compare(s.name.size() - suffix.size(), suffix.size(), suffix) == 0)
        diagnostics_.push_back(s);
  }

  std::string ns_;
  mutable std::mutex mutex_;
  std::vector<particle_sim::SimStatus> statuses_;
  ConfigValues config_;
  int updates_ = 0;
  std::vector<diagnostic_msgs::DiagnosticStatus> diagnostics_;
  // Last, so that they are shut down first, before the state their callbacks write.
  ros::Subscriber status_sub_, updates_sub_, diagnostics_sub_;
};

}  // namespace particle_sim_test
