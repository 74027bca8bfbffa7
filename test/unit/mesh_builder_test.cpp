// ClothMesh messages: vertices are the surface particles with their indices, triangles are
// renumbered to them and stay fixed until the body tears, normals are unit and strains match the
// springs.

#include "particle_sim/ros/mesh_builder.h"

#include <gtest/gtest.h>

#include <cmath>

#include "particle_sim/core/world.h"
#include "torn_square.h"

using namespace particle_sim;

TEST(MeshBuilder, FlatClothHasEveryParticleAsAVertexWithTheSheetNormal)
{
  core::World world{core::WorldDef{}};
  core::ClothGridDef cloth;
  cloth.name = "c";
  cloth.nu = 5;
  cloth.nv = 4;
  cloth.edge_u = {2, 0, 0};
  cloth.edge_v = {0, 0, -1};  // hanging in the xz plane: normal u x v = +y
  ASSERT_TRUE(world.addClothGrid(cloth).ok);
  const auto& body = *world.findSpringBody("c");
  const ClothMesh msg = ros_interface::buildClothMesh(body, ros::Time(2.0), "world");
  EXPECT_EQ(msg.body, "c");
  EXPECT_EQ(msg.header.frame_id, "world");
  ASSERT_EQ(msg.mesh.vertices.size(), 20u);
  ASSERT_EQ(msg.mesh.triangles.size(), 24u);
  for (std::size_t i = 0; i < 20; ++i)
  {
    EXPECT_EQ(msg.particles[i], i);
    EXPECT_EQ(msg.mesh.vertices[i].x, body.particles().position(0, i));
    EXPECT_NEAR(msg.normals[i].y, 1.0, 1e-12);
    EXPECT_EQ(msg.strain[i], 0.0);  // at rest
  }
  for (std::size_t k = 0; k < 24; ++k)
  {
    const auto& t = body.definition().triangles[k];
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(msg.mesh.triangles[k].vertex_indices[c], static_cast<std::uint32_t>(t[c]));
  }
}

TEST(MeshBuilder, JellyLeavesItsInsideParticlesOutAndRenumbersItsTriangles)
{
  core::World world{core::WorldDef{}};
  core::JellyDef jelly;
  jelly.name = "j";
  jelly.nx = jelly.ny = jelly.nz = 4;
  ASSERT_TRUE(world.addJelly(jelly).ok);
  const auto& body = *world.findSpringBody("j");
  const ClothMesh msg = ros_interface::buildClothMesh(body, ros::Time(1.0), "world");
  ASSERT_EQ(msg.mesh.vertices.size(), 56u);  // 64 particles, 8 inside
  ASSERT_EQ(msg.particles.size(), 56u);
  const Eigen::Vector3d centre = jelly.origin + 0.5 * jelly.size;
  for (std::size_t v = 0; v < msg.particles.size(); ++v)
  {
    // Each vertex is the particle it names, and its normal points out of the block.
    const auto x = body.particles().position.col(msg.particles[v]);
    EXPECT_EQ(msg.mesh.vertices[v].x, x.x());
    const Eigen::Vector3d n(msg.normals[v].x, msg.normals[v].y, msg.normals[v].z);
    EXPECT_NEAR(n.norm(), 1.0, 1e-12);
    EXPECT_GT(n.dot(x - centre), 0.0);
  }
  for (const auto& t : msg.mesh.triangles)
  {
    for (std::uint32_t v : t.vertex_indices)
      EXPECT_LT(v, 56u);
  }
}

TEST(MeshBuilder, ATornSurfaceLosesItsCutTrianglesAndTheParticlesLeftInNone)
{
  const core::World world = particle_sim_test::tornSquareWorld();
  const auto& body = static_cast<const core::SpringNetworkBody&>(*world.bodies()[0]);
  const ClothMesh msg = ros_interface::buildClothMesh(body, ros::Time(1.0), "world");
  // Triangle (0, 1, 2) is left; particle 3 is in none.
  ASSERT_EQ(msg.mesh.triangles.size(), 1u);
  ASSERT_EQ(msg.particles.size(), 3u);
  ASSERT_EQ(msg.mesh.vertices.size(), 3u);
  ASSERT_EQ(msg.normals.size(), 3u);
  ASSERT_EQ(msg.strain.size(), 3u);
  for (std::uint32_t v = 0; v < 3; ++v)
  {
    EXPECT_EQ(msg.particles[v], v);
    EXPECT_EQ(msg.mesh.triangles[0].vertex_indices[v], v);
    EXPECT_EQ(msg.mesh.vertices[v].z, body.particles().position(2, v));
    EXPECT_NEAR(std::hypot(msg.normals[v].x, msg.normals[v].y, msg.normals[v].z), 1.0, 1e-12);
  }
}
