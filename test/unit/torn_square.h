#pragma once
// A torn surface for the tests of what the node draws and publishes: a unit square of mesh cloth
// (triangles (0, 1, 2) and (0, 2, 3), corners 0, 1 and 3 pinned) that tears past 10 % strain, whose
// corner 3 its pin lifts by 0.6 m in one step. The springs 0-3 and 2-3 stretch by about 17 % and
// break (the bend spring 1-3 by about 9 %, and stays), so the triangle (0, 2, 3) goes and particle 3
// is left in no triangle.

#include <gtest/gtest.h>

#include "particle_sim/core/world.h"

namespace particle_sim_test
{
inline particle_sim::core::World tornSquareWorld()
{
  namespace core = particle_sim::core;
  core::World world{core::WorldDef{}};
  core::MeshClothDef square;
  square.name = "square";
  square.vertices = {{0.0, 0.0, 1.0}, {1.0, 0.0, 1.0}, {1.0, 1.0, 1.0}, {0.0, 1.0, 1.0}};
  square.triangles = {{0, 1, 2}, {0, 2, 3}};
  square.pins = {0, 1, 3};
  square.tear_strain = 0.1;
  EXPECT_TRUE(world.addMeshCloth(square).ok);
  core::SpringNetworkBody& body = *world.findSpringBody("square");
  EXPECT_TRUE(body.setPinTarget(3, {0.0, 1.0, 1.6}).ok);
  world.step();
  EXPECT_EQ(body.tornSprings(), 2);
  EXPECT_EQ(body.surfaceTriangles().size(), 1u);
  return world;
}
}  // namespace particle_sim_test
