#pragma once

#include <dynamic_reconfigure/server.h>
#include <ros/node_handle.h>

#include <boost/thread/recursive_mutex.hpp>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "particle_sim/SimConfig.h"
#include "particle_sim/core/integrator.h"
#include "particle_sim/core/status.h"
#include "particle_sim/core/world.h"
#include "particle_sim/ros/parameters.h"

namespace particle_sim
{
namespace ros_interface
{
/// dynamic_reconfigure (config/Sim.cfg): shows the world's live values (gravity, global damping,
/// wind, spring constants of one body) and the node's (rate, real-time factor, default integrator,
/// default rope and cloth materials), and applies a change from rqt or dynparam. A value the world
/// (or the list of presets) refuses is put back, so that rqt always shows what the simulation uses.
/// Its callback runs in the node's callback queue, between two steps.
class ReconfigureHandler
{
public:
  /// Serves ~set_parameters on `private_node` from the world as built. `world`, `settings` (rate,
  /// real_time_factor, rope_material and cloth_material change here) and `default_integrator` (of
  /// bodies spawned by services) are the node's and outlive the handler; `on_rate_changed` runs
  /// after ~rate changed.
  ReconfigureHandler(const ros::NodeHandle& private_node, core::World& world, NodeSettings& settings,
                     core::IntegratorDef& default_integrator, std::function<void()> on_rate_changed);

  /// Shows the world as it is now (after ~reset: spring constants are back to the built ones).
  void showWorld();
  /// Shows the constants ~set_spring_constants just set.
  void showSpringConstants(const std::string& body, const std::string& spring_class, double stiffness, double damping);
  /// `body` is gone: shows another body (or none) if it was the one shown.
  void forgetBody(const std::string& body);

private:
  // The current state as a config, and a change from rqt or dynparam.
  SimConfig currentConfig() const;
  void reconfigure(SimConfig& config, std::uint32_t level);

  core::World& world_;
  NodeSettings& settings_;
  core::IntegratorDef& default_integrator_;
  std::function<void()> on_rate_changed_;
  boost::recursive_mutex mutex_;
  std::unique_ptr<dynamic_reconfigure::Server<SimConfig>> server_;
  SimConfig config_;  // as last applied
};

}  // namespace ros_interface
}  // namespace particle_sim
