#pragma once

#include <ros/time.h>

#include <string>

#include "particle_sim/ClothMesh.h"
#include "particle_sim/core/spring_network.h"

namespace particle_sim
{
namespace ros_interface
{
/// The surface of a cloth or jelly body as a ClothMesh message: the particles its triangles use
/// as vertices [m] (with their particle indices), its triangles renumbered to them, unit
/// area-weighted vertex normals and per-vertex strain. The triangles are the current surface
/// (SpringNetworkBody::surfaceTriangles()): fixed for the body's life unless it tears, when the
/// triangles a tear cut out and the particles left in no triangle drop out.
ClothMesh buildClothMesh(const core::SpringNetworkBody& body, const ros::Time& stamp, const std::string& frame_id);

}  // namespace ros_interface
}  // namespace particle_sim
