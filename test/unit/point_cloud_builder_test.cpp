// ~points: every body's particles as one PointCloud2, decoded here field by field and compared
// with the world it came from; surface_only drops exactly a jelly's interior lattice points.

#include "particle_sim/ros/point_cloud_builder.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <map>

#include "particle_sim/core/world.h"
#include "torn_square.h"

using namespace particle_sim;

namespace
{
struct CloudPoint
{
  float x, y, z;
  std::uint32_t body, particle;
};

// Decodes the cloud by its own field descriptions, not by the builder's layout constants.
std::vector<CloudPoint> decode(const sensor_msgs::PointCloud2& cloud)
{
  std::map<std::string, std::uint32_t> offset;
  for (const auto& f : cloud.fields)
    offset[f.name] = f.offset;
  std::vector<CloudPoint> points(cloud.width);
  for (std::uint32_t k = 0; k < cloud.width; ++k)
  {
    const std::uint8_t* p = cloud.data.data() + static_cast<std::size_t>(k) * cloud.point_step;
    std::memcpy(&points[k].x, p + offset.at("x"), 4);
    std::memcpy(&points[k].y, p + offset.at("y"), 4);
    std::memcpy(&points[k].z, p + offset.at("z"), 4);
    std::memcpy(&points[k].body, p + offset.at("body"), 4);
    std::memcpy(&points[k].particle, p + offset.at("particle"), 4);
  }
  return points;
}

// An emitter burst, a rope, a cloth and a 4 x 4 x 4 jelly, stepped a little.
core::World makeWorld()
{
  core::World world{core::WorldDef{}};
  core::EmitterDef fountain;
  fountain.name = "fountain";
  fountain.origin = {0.0, 0.0, 1.0};
  fountain.rate = 0.0;
  fountain.burst_count = 7;
  fountain.lifetime = 100.0;
  EXPECT_TRUE(world.addEmitter(fountain).ok);
  core::RopeDef rope;
  rope.name = "rope";
  rope.particles = 9;
  rope.start = {0.0, 1.0, 2.0};
  rope.end = {1.0, 1.0, 2.0};
  rope.pins = {0};
  EXPECT_TRUE(world.addRope(rope).ok);
  core::ClothGridDef cloth;
  cloth.name = "cloth";
  cloth.nu = 5;
  cloth.nv = 4;
  EXPECT_TRUE(world.addClothGrid(cloth).ok);
  core::JellyDef jelly;
  jelly.name = "jelly";
  jelly.nx = jelly.ny = jelly.nz = 4;
  jelly.origin = {3.0, 0.0, 1.0};
  EXPECT_TRUE(world.addJelly(jelly).ok);
  for (int k = 0; k < 5; ++k)
    world.step();
  return world;
}
}  // namespace

TEST(PointCloudBuilder, EveryParticleOfEveryBodyWithItsBodyAndParticleIndex)
{
  const core::World world = makeWorld();
  const sensor_msgs::PointCloud2 cloud = ros_interface::buildPointCloud(world, ros::Time(3.0), "world", false);
  EXPECT_EQ(cloud.header.frame_id, "world");
  EXPECT_EQ(cloud.header.stamp, ros::Time(3.0));
  ASSERT_EQ(cloud.fields.size(), 5u);
  const char* names[] = {"x", "y", "z", "body", "particle"};
  for (std::size_t f = 0; f < 5; ++f)
  {
    EXPECT_EQ(cloud.fields[f].name, names[f]);
    EXPECT_EQ(cloud.fields[f].count, 1u);
    EXPECT_EQ(cloud.fields[f].datatype, f < 3 ? sensor_msgs::PointField::FLOAT32 : sensor_msgs::PointField::UINT32);
  }
  EXPECT_EQ(cloud.height, 1u);
  EXPECT_TRUE(cloud.is_dense);
  EXPECT_FALSE(cloud.is_bigendian);
  EXPECT_EQ(cloud.row_step, cloud.width * cloud.point_step);
  EXPECT_EQ(cloud.data.size(), static_cast<std::size_t>(cloud.row_step));

  // 7 + 9 + 20 + 64 points, body by body in world order, particles in index order, each at its
  // particle's position rounded to float.
  ASSERT_EQ(cloud.width, 7u + 9u + 20u + 64u);
  const std::vector<CloudPoint> points = decode(cloud);
  std::size_t k = 0;
  for (std::size_t b = 0; b < world.bodies().size(); ++b)
  {
    const core::ParticlePool& p = world.bodies()[b]->particles();
    for (int i = 0; i < p.size(); ++i, ++k)
    {
      ASSERT_EQ(points[k].body, b);
      ASSERT_EQ(points[k].particle, static_cast<std::uint32_t>(i));
      EXPECT_EQ(points[k].x, static_cast<float>(p.position(0, i)));
      EXPECT_EQ(points[k].y, static_cast<float>(p.position(1, i)));
      EXPECT_EQ(points[k].z, static_cast<float>(p.position(2, i)));
    }
  }
}

TEST(PointCloudBuilder, SurfaceOnlyDropsTheJellysInteriorAndKeepsEveryOtherBody)
{
  const core::World world = makeWorld();
  const std::vector<CloudPoint> all = decode(ros_interface::buildPointCloud(world, ros::Time(0.0), "w", false));
  const sensor_msgs::PointCloud2 cloud = ros_interface::buildPointCloud(world, ros::Time(0.0), "w", true);
  const std::vector<CloudPoint> surface = decode(cloud);
  // A 4 x 4 x 4 lattice has 4^3 - 2^3 = 56 points on its boundary; the emitter, rope and cloth keep all.
  ASSERT_EQ(cloud.width, 7u + 9u + 20u + 56u);
  std::map<std::uint32_t, int> per_body;
  for (const CloudPoint& p : surface)
    ++per_body[p.body];
  EXPECT_EQ(per_body[0], 7);
  EXPECT_EQ(per_body[1], 9);
  EXPECT_EQ(per_body[2], 20);
  EXPECT_EQ(per_body[3], 56);
  // Lattice index (i, j, k) of jelly particle n, x fastest (as buildJelly lays them out): on the
  // boundary iff some index is 0 or 3.
  const core::ParticlePool& jelly = world.bodies()[3]->particles();
  for (const CloudPoint& p : surface)
  {
    if (p.body != 3) continue;
    const int n = static_cast<int>(p.particle);
    const int i = n % 4, j = (n / 4) % 4, k = n / 16;
    EXPECT_TRUE(i == 0 || i == 3 || j == 0 || j == 3 || k == 0 || k == 3) << "interior particle " << n;
    EXPECT_EQ(p.x, static_cast<float>(jelly.position(0, n)));
  }
  // The other bodies' points are identical to the full cloud's.
  for (std::size_t k = 0; k < 36; ++k)
  {
    EXPECT_EQ(surface[k].body, all[k].body);
    EXPECT_EQ(surface[k].particle, all[k].particle);
    EXPECT_EQ(surface[k].z, all[k].z);
  }
}

TEST(PointCloudBuilder, SurfaceOnlyDropsTheParticlesATearLeftInNoTriangle)
{
  const core::World world = particle_sim_test::tornSquareWorld();
  EXPECT_EQ(ros_interface::buildPointCloud(world, ros::Time(0.0), "w", false).width, 4u);
  const std::vector<CloudPoint> surface = decode(ros_interface::buildPointCloud(world, ros::Time(0.0), "w", true));
  ASSERT_EQ(surface.size(), 3u);  // particle 3 is in no triangle left
  for (std::uint32_t k = 0; k < 3; ++k)
    EXPECT_EQ(surface[k].particle, k);
}
