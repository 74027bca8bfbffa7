#pragma once

#include <ros/node_handle.h>

#include <string>
#include <vector>

#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace ros_interface
{
/// The node's settings, read once from private parameters (README "Parameters").
struct NodeSettings
{
  std::string scene_path;                              ///< ~scene, YAML scene file; empty = an empty world
  double rate = 50.0;                                  ///< ~rate [Hz] publish rate (and physics ticks)
  double dt = 0.0;                                     ///< ~dt [s] physics step; 0 = the scene's world.dt
  double real_time_factor = 1.0;                       ///< ~real_time_factor [-]; 0 = as fast as possible
  double max_lag = 0.5;                                ///< ~max_lag [s] of wall time the loop makes up when late
  bool paused = false;                                 ///< ~paused: start paused
  std::string frame_id = "world";                      ///< ~frame_id: frame of every marker
  std::string parent_frame_id = "map";                 ///< ~parent_frame_id: tf parent of frame_id
  std::vector<double> frame_offset = {0.0, 0.0, 0.0};  ///< ~frame_offset [m]: frame_id's origin in parent_frame_id
  bool publish_clock = true;                           ///< ~publish_clock: publish /clock from sim time
  double particle_size = 0.05;                         ///< ~particle_size [m]
  int max_marker_points = 200000;                      ///< ~max_marker_points: most points of one particle marker
  bool publishing_thread = true;     ///< ~publishing_thread: send markers, meshes and clouds from a thread of their own
  bool drag_markers = true;          ///< ~drag_markers: drag particles in rviz (~drag)
  bool points_surface_only = false;  ///< ~points_surface_only: ~points without a jelly's interior
  int max_particles_per_body = 0;    ///< ~max_particles_per_body; 0 = the scene's value
  int max_particles_per_world = 0;   ///< ~max_particles_per_world; 0 = the scene's value
  int threads = -1;  ///< ~threads: threads of the physics step, 0 = one per core; -1 = the scene's world.threads
  double status_period = 1.0;          ///< ~status_period [s] of wall time between status lines; 0 = none
  bool color_by_strain = false;        ///< ~color_by_strain: colour cloth and jelly by strain
  double strain_color_max = 0.1;       ///< ~strain_color_max [-]: strain drawn fully red
  double diagnostic_period = 1.0;      ///< ~diagnostic_period [s] of wall time between /diagnostics updates
  double diagnostic_max_strain = 0.5;  ///< ~diagnostic_max_strain [-]: a larger max strain is a WARN
  std::string rope_material;   ///< ~rope_material: preset of spawned ropes without material or constants; empty = none
  std::string cloth_material;  ///< ~cloth_material: the same for cloth (live: dynamic_reconfigure)
};

/// The settings from the private parameters of `private_node`; a parameter that is not set keeps
/// the default above.
NodeSettings readNodeSettings(const ros::NodeHandle& private_node);

/// Checks every setting before anything starts; a refusal names the parameter, its value as
/// received and what is allowed (the ranges of core/limits.h where there is one).
core::Status validate(const NodeSettings& settings);

}  // namespace ros_interface
}  // namespace particle_sim
