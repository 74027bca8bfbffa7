#pragma once

#include <ros/time.h>
#include <visualization_msgs/MarkerArray.h>

#include <string>
#include <vector>

#include "particle_sim/core/world.h"

namespace particle_sim
{
namespace ros_interface
{
/// How markers look.
struct MarkerStyle
{
  std::string frame_id = "world";
  double particle_size = 0.05;  ///< [m] side of a POINTS square
};

/// Turns the world's state into one MarkerArray: one namespace per body (the body name) with
/// stable ids, so each array overwrites the last in place.
///   - `delete_all`: a DELETEALL (ns "") goes first, as at start and after reset;
///   - `removed`: bodies removed since the last array get a DELETE for each of their ids;
///   - an emitter with no live particle gets a DELETE instead of an empty POINTS list;
///   - sphere colliders are drawn in the namespace "_colliders".
/// Every marker passes rviz's checks: unit quaternion, non-zero scale, alpha > 0, one colour per
/// point, finite values (non-finite particles are left out).
visualization_msgs::MarkerArray buildMarkers(const core::World& world, const ros::Time& stamp,
                                              const MarkerStyle& style, bool delete_all,
                                              const std::vector<std::string>& removed);

/// Marker ids used inside a body's namespace.
constexpr int kParticlesMarkerId = 0;
/// Namespace of the collider markers (one SPHERE per sphere collider, id = its index). Body names
/// cannot start with '_', so no body takes it.
constexpr const char* kCollidersNamespace = "_colliders";

}  // namespace ros_interface
}  // namespace particle_sim
