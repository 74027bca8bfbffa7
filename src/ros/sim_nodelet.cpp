// particle_sim as a nodelet: the same SimNode as particle_sim_node, with the same parameters,
// services and topics, in a nodelet manager's process, so that consumers loaded in the same
// manager get markers, meshes and status without a copy.

#include <nodelet/nodelet.h>

#include <memory>
#include <pluginlib/class_list_macros.hpp>
#include <thread>

#include "particle_sim/ros/sim_node.h"

namespace particle_sim
{
namespace ros_interface
{
class SimNodelet : public nodelet::Nodelet
{
public:
  ~SimNodelet() override
  {
    if (sim_) sim_->stop();
    if (thread_.joinable()) thread_.join();
  }

private:
  // Returns at once: the loop runs in a thread of its own and serves the simulator's own callback
  // queue, so that the manager's threads never touch the world.
  void onInit() override
  {
    sim_ = std::make_unique<SimNode>(getNodeHandle(), getPrivateNodeHandle(), getName());
    if (!sim_->initialize())
    {
      NODELET_FATAL("particle_sim nodelet '%s' did not start (see the message above)", getName().c_str());
      sim_.reset();
      return;
    }
    thread_ = std::thread([this] {
      // At shutdown ROS may tear down what the loop uses while it runs (a mutex it locks then
      // throws): end the loop quietly instead of terminating the manager's process.
      try
      {
        sim_->run();
      }
      catch (const std::exception& error)
      {
        if (ros::ok()) NODELET_ERROR("particle_sim loop stopped: %s", error.what());
      }
    });
  }

  std::unique_ptr<SimNode> sim_;
  std::thread thread_;
};

}  // namespace ros_interface
}  // namespace particle_sim

PLUGINLIB_EXPORT_CLASS(particle_sim::ros_interface::SimNodelet, nodelet::Nodelet)
