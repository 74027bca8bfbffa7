// Mesh topology shared by the cloth builders: every edge once, with its sides.

#include "particle_sim/core/builders/mesh_topology.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <utility>

using namespace particle_sim::core;

TEST(MeshTopology, TwoTrianglesShareOneInteriorEdgeWithBothOppositeVertices)
{
  // A unit square 0-1-2-3 split along 1-3 into (0, 1, 3) and (1, 2, 3).
  const MeshEdges edges = meshEdges({Eigen::Vector3i(0, 1, 3), Eigen::Vector3i(1, 2, 3)});
  ASSERT_EQ(edges.size(), 5u);  // 4 border edges and the diagonal
  int interior = 0;
  for (const auto& [edge, sides] : edges)
  {
    EXPECT_LT(edge.first, edge.second);
    for (const EdgeSide& side : sides)
      EXPECT_EQ(std::make_pair(std::min(side.a, side.b), std::max(side.a, side.b)), edge)
          << "side of triangle " << side.triangle;
    if (sides.size() == 2) ++interior;
  }
  EXPECT_EQ(interior, 1);
  const std::vector<EdgeSide>& diagonal = edges.at({1, 3});
  ASSERT_EQ(diagonal.size(), 2u);
  // Triangle 0 directs it 1 -> 3 with 0 opposite; triangle 1 directs it 3 -> 1 with 2 opposite.
  EXPECT_EQ(diagonal[0].triangle, 0);
  EXPECT_EQ(diagonal[0].a, 1);
  EXPECT_EQ(diagonal[0].b, 3);
  EXPECT_EQ(diagonal[0].opposite, 0);
  EXPECT_EQ(diagonal[1].triangle, 1);
  EXPECT_EQ(diagonal[1].a, 3);
  EXPECT_EQ(diagonal[1].b, 1);
  EXPECT_EQ(diagonal[1].opposite, 2);
  EXPECT_EQ(edges.at({0, 1}).size(), 1u);
}
