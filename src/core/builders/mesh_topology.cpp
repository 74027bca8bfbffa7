#include "particle_sim/core/builders/mesh_topology.h"

#include <algorithm>

namespace particle_sim
{
namespace core
{
MeshEdges meshEdges(const std::vector<Eigen::Vector3i>& triangles)
{
  MeshEdges edges;
  for (std::size_t k = 0; k < triangles.size(); ++k)
  {
    const Eigen::Vector3i& t = triangles[k];
    for (int c = 0; c < 3; ++c)
    {
      const int a = t[c], b = t[(c + 1) % 3], opposite = t[(c + 2) % 3];
      edges[{std::min(a, b), std::max(a, b)}].push_back({static_cast<int>(k), a, b, opposite});
    }
  }
  return edges;
}

}  // namespace core
}  // namespace particle_sim
