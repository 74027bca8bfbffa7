#include "particle_sim/ros/point_cloud_builder.h"

#include <cstdint>
#include <cstring>
#include <vector>

#include "particle_sim/core/spring_network.h"

namespace particle_sim
{
namespace ros_interface
{
namespace
{
sensor_msgs::PointField field(const char* name, std::uint32_t offset, std::uint8_t datatype)
{
  sensor_msgs::PointField f;
  f.name = name;
  f.offset = offset;
  f.datatype = datatype;
  f.count = 1;
  return f;
}

// Which particles of `body` go into the cloud: all, or with surface_only those its current surface
// triangles use (cloth and jelly; a body built without triangles keeps all, a body whose triangles
// all tore away keeps none). Empty = all.
std::vector<std::uint8_t> selectedParticles(const core::Body& body, bool surface_only)
{
  std::vector<std::uint8_t> selected;
  if (!surface_only || body.kind() != core::BodyKind::SpringNetwork) return selected;
  const auto& spring_body = static_cast<const core::SpringNetworkBody&>(body);
  if (spring_body.definition().triangles.empty()) return selected;
  selected.assign(static_cast<std::size_t>(body.particles().size()), 0);
  for (const Eigen::Vector3i& t : spring_body.surfaceTriangles())
    for (int c = 0; c < 3; ++c)
      selected[static_cast<std::size_t>(t[c])] = 1;
  return selected;
}
}  // namespace

sensor_msgs::PointCloud2 buildPointCloud(const core::World& world, const ros::Time& stamp, const std::string& frame_id,
                                         bool surface_only)
{
  using sensor_msgs::PointField;
  sensor_msgs::PointCloud2 cloud;
  cloud.header.stamp = stamp;
  cloud.header.frame_id = frame_id;
  cloud.height = 1;
  cloud.fields = {field("x", 0, PointField::FLOAT32), field("y", 4, PointField::FLOAT32),
                  field("z", 8, PointField::FLOAT32), field("body", 12, PointField::UINT32),
                  field("particle", 16, PointField::UINT32)};
  cloud.is_bigendian = false;  // every platform ROS 1 builds for on Debian here is little-endian
  cloud.point_step = kPointCloudPointStep;
  cloud.is_dense = true;  // non-finite particles are left out

  std::size_t capacity = 0;
  for (const auto& body : world.bodies())
    capacity += static_cast<std::size_t>(body->particles().size());
  cloud.data.resize(capacity * kPointCloudPointStep);

  // One pass over the bodies: each selected, finite particle becomes 20 bytes.
  std::uint8_t* out = cloud.data.data();
  std::size_t points = 0;
  for (std::size_t b = 0; b < world.bodies().size(); ++b)
  {
    const core::Body& body = *world.bodies()[b];
    const core::ParticlePool& p = body.particles();
    const std::vector<std::uint8_t> selected = selectedParticles(body, surface_only);
    const auto body_index = static_cast<std::uint32_t>(b);
    for (int i = 0; i < p.size(); ++i)
    {
      if (!selected.empty() && !selected[static_cast<std::size_t>(i)]) continue;
      const auto x = p.position.col(i);
      if (!x.allFinite()) continue;
      const float xyz[3] = {static_cast<float>(x.x()), static_cast<float>(x.y()), static_cast<float>(x.z())};
      const auto particle_index = static_cast<std::uint32_t>(i);
      std::memcpy(out, xyz, sizeof(xyz));
      std::memcpy(out + 12, &body_index, 4);
      std::memcpy(out + 16, &particle_index, 4);
      out += kPointCloudPointStep;
      ++points;
    }
  }
  cloud.data.resize(points * kPointCloudPointStep);
  cloud.width = static_cast<std::uint32_t>(points);
  cloud.row_step = cloud.width * cloud.point_step;
  return cloud;
}

}  // namespace ros_interface
}  // namespace particle_sim
