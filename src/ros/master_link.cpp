#include "particle_sim/ros/master_link.h"

#include <ros/connection_manager.h>
#include <ros/master.h>
#include <ros/network.h>
#include <ros/ros.h>
#include <ros/service_manager.h>
#include <ros/this_node.h>
#include <ros/xmlrpc_manager.h>
#include <xmlrpcpp/XmlRpc.h>

#include <chrono>

namespace particle_sim
{
namespace ros_interface
{
namespace
{
using SteadyClock = std::chrono::steady_clock;

// Calls `method` on this process's own XML-RPC server (the ROS slave API) and returns its payload
// (the third element of [code, status message, payload]).
bool callSelf(const std::string& method, XmlRpc::XmlRpcValue& params, XmlRpc::XmlRpcValue& payload)
{
  std::string host;
  std::uint32_t port = 0;
  if (!ros::network::splitURI(ros::XMLRPCManager::instance()->getServerURI(), host, port)) return false;
  XmlRpc::XmlRpcClient client(host.c_str(), static_cast<int>(port), "/");
  XmlRpc::XmlRpcValue result;
  const bool ok = client.execute(method.c_str(), params, result);
  client.close();
  if (!ok || result.getType() != XmlRpc::XmlRpcValue::TypeArray || result.size() != 3 ||
      static_cast<int>(result[0]) != 1)
    return false;
  payload = result[2];
  return true;
}

// The [topic, type] pairs that this process's slave API lists for `method` (getPublications or
// getSubscriptions).
bool listTopics(const std::string& method, std::vector<std::pair<std::string, std::string>>& topics)
{
  XmlRpc::XmlRpcValue params, payload;
  params[0] = ros::this_node::getName();
  if (!callSelf(method, params, payload) || payload.getType() != XmlRpc::XmlRpcValue::TypeArray) return false;
  for (int i = 0; i < payload.size(); ++i)
    topics.emplace_back(static_cast<std::string>(payload[i][0]), static_cast<std::string>(payload[i][1]));
  return true;
}
}  // namespace

void MasterLink::start(std::vector<std::string> services)
{
  stop();
  services_ = std::move(services);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_requested_ = false;
  }
  thread_ = std::thread([this] { watch(); });
}

void MasterLink::stop()
{
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_requested_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

bool MasterLink::masterPid(int& pid) const
{
  XmlRpc::XmlRpcValue params, result, payload;
  params[0] = ros::this_node::getName();
  // wait_for_master = false: one attempt, no retry loop and no error log of roscpp's own.
  if (!ros::master::execute("getPid", params, result, payload, false)) return false;
  pid = payload.getType() == XmlRpc::XmlRpcValue::TypeInt ? static_cast<int>(payload) : -1;
  return true;
}

void MasterLink::watch()
{
  int known_pid = -1;
  masterPid(known_pid);
  bool registered = true;  // roscpp registered everything with the master we started with
  auto gone_since = SteadyClock::now();
  auto last_warning = SteadyClock::now();
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_requested_)
  {
    lock.unlock();
    int pid = -1;
    const bool answered = masterPid(pid);
    const auto now = SteadyClock::now();
    if (!answered)
    {
      if (reachable_)
      {
        gone_since = now;
        last_warning = now - std::chrono::hours(1);
      }
      reachable_ = false;
      registered = false;
      if (now - last_warning >= std::chrono::duration<double>(kMasterWarnPeriod))
      {
        ROS_WARN_NAMED("master",
                       "the ROS master at %s does not answer (for %.0f s); the simulation goes on, and topics and "
                       "services will be registered again when it is back",
                       ros::master::getURI().c_str(), std::chrono::duration<double>(now - gone_since).count());
        last_warning = now;
      }
    }
    else
    {
      reachable_ = true;
      if (pid != known_pid) registered = false;  // a new master, even if we never saw it gone
      if (!registered)
      {
        int topics = 0, subscriptions = 0, services = 0;
        std::string error;
        if (reregister(topics, subscriptions, services, error))
        {
          registered = true;
          known_pid = pid;
          ++reregistrations_;
          ROS_WARN_NAMED("master",
                         "the ROS master at %s is back (pid %d): registered again %d published topics, %d "
                         "subscriptions and %d services",
                         ros::master::getURI().c_str(), pid, topics, subscriptions, services);
        }
        else
          ROS_WARN_NAMED("master", "registering again with the ROS master at %s failed (%s); retrying",
                         ros::master::getURI().c_str(), error.c_str());
      }
    }
    lock.lock();
    wake_.wait_for(lock, std::chrono::duration<double>(kMasterCheckPeriod), [this] { return stop_requested_; });
  }
}

bool MasterLink::reregister(int& topics, int& subscriptions, int& services, std::string& error) const
{
  const std::string caller_id = ros::this_node::getName();
  const std::string caller_api = ros::XMLRPCManager::instance()->getServerURI();

  // Published topics: registerPublisher, as TopicManager::advertise does.
  std::vector<std::pair<std::string, std::string>> published, subscribed;
  if (!listTopics("getPublications", published) || !listTopics("getSubscriptions", subscribed))
  {
    error = "could not list this node's own topics";
    return false;
  }
  for (const auto& [topic, type] : published)
  {
    XmlRpc::XmlRpcValue params, result, payload;
    params[0] = caller_id, params[1] = topic, params[2] = type, params[3] = caller_api;
    if (!ros::master::execute("registerPublisher", params, result, payload, false))
    {
      error = "registerPublisher " + topic;
      return false;
    }
    ++topics;
  }

  // Subscriptions: registerSubscriber, then hand the publishers it names to the subscription, as
  // the master's publisherUpdate would.
  for (const auto& [topic, type] : subscribed)
  {
    XmlRpc::XmlRpcValue params, result, publishers;
    params[0] = caller_id, params[1] = topic, params[2] = type, params[3] = caller_api;
    if (!ros::master::execute("registerSubscriber", params, result, publishers, false))
    {
      error = "registerSubscriber " + topic;
      return false;
    }
    XmlRpc::XmlRpcValue update, ignored;
    update[0] = caller_id, update[1] = topic, update[2] = publishers;
    callSelf("publisherUpdate", update, ignored);
    ++subscriptions;
  }

  // Services: registerService with this process's service URI, as ServiceManager does.
  const std::string service_api =
      "rosrpc://" + ros::network::getHost() + ":" + std::to_string(ros::ConnectionManager::instance()->getTCPPort());
  for (const std::string& service : services_)
  {
    if (!ros::ServiceManager::instance()->lookupServicePublication(service)) continue;
    XmlRpc::XmlRpcValue params, result, payload;
    params[0] = caller_id, params[1] = service, params[2] = service_api, params[3] = caller_api;
    if (!ros::master::execute("registerService", params, result, payload, false))
    {
      error = "registerService " + service;
      return false;
    }
    ++services;
  }
  return true;
}

}  // namespace ros_interface
}  // namespace particle_sim
