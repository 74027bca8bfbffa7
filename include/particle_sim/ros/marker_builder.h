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
  double particle_size = 0.05;  ///< [m] side of a POINTS square, diameter of a spring body's particle
  double line_width = 0.02;     ///< [m] rope and spring lines
};

/// Turns the world's state into one MarkerArray: one namespace per body (the body name) with
/// stable ids, so each array overwrites the last in place.
///   - `delete_all`: a DELETEALL (ns "") goes first, as at start and after reset;
///   - `removed`: bodies removed since the last array get a DELETE for each of their ids;
///   - spring bodies: free particles as a SPHERE_LIST, a rope as a LINE_STRIP and a network's
///     springs as a LINE_LIST, pinned particles as a separate, larger SPHERE_LIST (DELETE if none);
///   - an emitter with no live particle gets a DELETE instead of an empty POINTS list;
///   - sphere colliders are drawn in the namespace "_colliders".
/// Every marker passes rviz's checks: unit quaternion, non-zero scale, alpha > 0, one colour per
/// point, finite values (non-finite particles are left out).
visualization_msgs::MarkerArray buildMarkers(const core::World& world, const ros::Time& stamp,
                                              const MarkerStyle& style, bool delete_all,
                                              const std::vector<std::string>& removed);

/// Marker ids used inside a body's namespace.
constexpr int kParticlesMarkerId = 0;  ///< POINTS (emitters) or SPHERE_LIST (free particles of spring bodies)
constexpr int kLinesMarkerId = 1;      ///< LINE_STRIP (ropes) or LINE_LIST (springs of a network)
constexpr int kPinsMarkerId = 2;       ///< SPHERE_LIST of pinned particles, drawn apart
constexpr int kMarkerIdsPerBody = 3;
/// Namespace of the collider markers (one SPHERE per sphere collider, id = its index). Body names
/// cannot start with '_', so no body takes it.
constexpr const char* kCollidersNamespace = "_colliders";

}  // namespace ros_interface
}  // namespace particle_sim
