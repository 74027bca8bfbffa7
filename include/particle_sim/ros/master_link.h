#pragma once

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace particle_sim
{
namespace ros_interface
{
/// Wall seconds between two checks that the ROS master answers.
constexpr double kMasterCheckPeriod = 1.0;
/// Wall seconds between two warnings while it does not.
constexpr double kMasterWarnPeriod = 5.0;

/// Keeps this process known to the ROS master across a master restart (roscore stopped and
/// started again), which roscpp does not do: it registers a topic or service only when it is
/// advertised or subscribed.
///
/// A thread of its own asks the master for its pid every kMasterCheckPeriod. While the master does
/// not answer it warns in the log every kMasterWarnPeriod; when a master answers again (or with
/// another pid: it restarted between two checks) it registers again, with the same XML-RPC calls
/// roscpp makes, every topic this process publishes and subscribes (as its own XML-RPC server
/// lists them, so /rosout and tf are included) and the given services, and hands each
/// subscription the publishers the master names. Nothing here runs on the simulation loop, so a
/// missing master never stalls it.
class MasterLink
{
public:
  MasterLink() = default;
  ~MasterLink() { stop(); }
  MasterLink(const MasterLink&) = delete;
  MasterLink& operator=(const MasterLink&) = delete;

  /// Starts watching; `services` are the resolved names of services this process serves that
  /// should be registered again (names not served when it happens are skipped).
  void start(std::vector<std::string> services);
  /// Stops watching and joins the thread (idempotent).
  void stop();

  /// False while the master does not answer.
  bool masterReachable() const { return reachable_; }
  /// How many times this process was registered again with a new master.
  int reregistrations() const { return reregistrations_; }

private:
  void watch();
  // Asks the master for its pid; false if it does not answer.
  bool masterPid(int& pid) const;
  // Registers topics, subscriptions and services with the master; false (with `error`) if a call failed.
  bool reregister(int& topics, int& subscriptions, int& services, std::string& error) const;

  std::vector<std::string> services_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_requested_ = false;
  std::atomic<bool> reachable_{true};
  std::atomic<int> reregistrations_{0};
};

}  // namespace ros_interface
}  // namespace particle_sim
