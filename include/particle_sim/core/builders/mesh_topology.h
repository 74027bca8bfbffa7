#pragma once

#include <Eigen/Core>
#include <map>
#include <utility>
#include <vector>

namespace particle_sim
{
namespace core
{
/// One side of a mesh edge: the triangle it belongs to, the edge's ends as that triangle directs
/// them (a → b, counter-clockwise order of its corners) and the triangle's vertex opposite it.
struct EdgeSide
{
  int triangle = 0;
  int a = 0;
  int b = 0;
  int opposite = 0;
};

/// Every edge of a triangle surface once, keyed by its ends sorted (ascending, so iteration order
/// is fixed), with its sides in triangle order: one side for a border edge, two for an interior
/// edge (the bending hinges of cloth), more for a non-manifold edge.
using MeshEdges = std::map<std::pair<int, int>, std::vector<EdgeSide>>;
MeshEdges meshEdges(const std::vector<Eigen::Vector3i>& triangles);

}  // namespace core
}  // namespace particle_sim
