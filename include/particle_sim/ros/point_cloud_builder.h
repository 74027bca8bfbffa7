#pragma once

#include <ros/time.h>
#include <sensor_msgs/PointCloud2.h>

#include <string>

#include "particle_sim/core/world.h"

namespace particle_sim
{
namespace ros_interface
{
/// The fields of one point of ~points, 20 bytes, little-endian, in this order.
constexpr int kPointCloudPointStep = 20;

/// Every body's particles as one sensor_msgs/PointCloud2 (height 1, dense): per point x, y, z
/// (float32, [m] in frame_id), body (uint32: the body's index in the world, the same as in
/// ~status's bodies) and particle (uint32: the particle's index in its body, the index that pins and
/// ClothMesh use). Bodies in world order, particles in index order; a non-finite particle is left
/// out. With `surface_only`, a cloth or jelly gives only the particles its current surface
/// triangles use (a jelly's interior is dropped, and so are particles a tear left in no triangle);
/// emitters, ropes and networks without triangles give all.
sensor_msgs::PointCloud2 buildPointCloud(const core::World& world, const ros::Time& stamp, const std::string& frame_id,
                                         bool surface_only);

}  // namespace ros_interface
}  // namespace particle_sim
