#pragma once
// A body-fitted triangulation of a disc for tests: `rings` concentric rings of equal spacing around a
// centre vertex, ring k (radius k R / rings) with 6k vertices, so that the triangles are near
// equilateral (a hexagon at the centre) and the rim and every ring are circles at any resolution.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <vector>

namespace particle_sim_test
{
struct DiscMesh
{
  std::vector<Eigen::Vector3d> vertices;   // in the plane z = 0, centre first, then ring by ring
  std::vector<Eigen::Vector2d> uvs;        // the same points, as the flat pattern
  std::vector<Eigen::Vector3i> triangles;  // counter-clockwise seen from +z
  std::vector<int> ring_start;             // first vertex of ring k (ring 0 = the centre), and the count at the end
};

// Triangles between two concentric rings whose first vertices lie at angle 0: n_in vertices from
// in0 and n_out from out0 (n_in = 1 is a centre vertex: its fan). Walks both rings by angle, each
// step a triangle that advances the ring whose next vertex comes first; counter-clockwise from +z.
inline void connectRings(DiscMesh& mesh, int in0, int n_in, int out0, int n_out)
{
  if (n_in == 1)
  {
    for (int j = 0; j < n_out; ++j)
      mesh.triangles.emplace_back(in0, out0 + j, out0 + (j + 1) % n_out);
    return;
  }
  int i = 0, j = 0;
  while (i < n_in || j < n_out)
  {
    const int a = in0 + i % n_in, b = out0 + j % n_out;
    const double next_in = static_cast<double>(i + 1) / n_in;
    const double next_out = static_cast<double>(j + 1) / n_out;
    if (j < n_out && (next_out <= next_in || i >= n_in))
    {
      mesh.triangles.emplace_back(a, b, out0 + (j + 1) % n_out);
      ++j;
    }
    else
    {
      mesh.triangles.emplace_back(a, b, in0 + (i + 1) % n_in);
      ++i;
    }
  }
}

// Appends a ring of `count` vertices at `radius`, the first at angle 0.
inline void addRing(DiscMesh& mesh, double radius, int count)
{
  const double kTwoPi = 2.0 * std::acos(-1.0);
  mesh.ring_start.push_back(static_cast<int>(mesh.vertices.size()));
  for (int i = 0; i < count; ++i)
    mesh.vertices.emplace_back(radius * std::cos(kTwoPi * i / count), radius * std::sin(kTwoPi * i / count), 0.0);
}

inline DiscMesh discMesh(double radius, int rings)
{
  DiscMesh mesh;
  mesh.ring_start.push_back(0);
  mesh.vertices.emplace_back(0.0, 0.0, 0.0);
  for (int k = 1; k <= rings; ++k)
    addRing(mesh, radius * k / rings, 6 * k);
  mesh.ring_start.push_back(static_cast<int>(mesh.vertices.size()));
  for (int k = 1; k <= rings; ++k)
    connectRings(mesh, mesh.ring_start[k - 1], mesh.ring_start[k] - mesh.ring_start[k - 1], mesh.ring_start[k],
                 mesh.ring_start[k + 1] - mesh.ring_start[k]);
  for (const Eigen::Vector3d& v : mesh.vertices)
    mesh.uvs.emplace_back(v.x(), v.y());
  return mesh;
}

// An annulus of concentric rings at `radii` (increasing), ring j with 6 round(radii[j] / spacing)
// vertices (at least 6), so that the triangles are near equilateral when the radii are `spacing`
// apart.
inline DiscMesh annulusMesh(const std::vector<double>& radii, double spacing)
{
  DiscMesh mesh;
  for (double r : radii)
    addRing(mesh, r, 6 * std::max(1, static_cast<int>(std::lround(r / spacing))));
  mesh.ring_start.push_back(static_cast<int>(mesh.vertices.size()));
  for (std::size_t k = 1; k < radii.size(); ++k)
    connectRings(mesh, mesh.ring_start[k - 1], mesh.ring_start[k] - mesh.ring_start[k - 1], mesh.ring_start[k],
                 mesh.ring_start[k + 1] - mesh.ring_start[k]);
  for (const Eigen::Vector3d& v : mesh.vertices)
    mesh.uvs.emplace_back(v.x(), v.y());
  return mesh;
}

}  // namespace particle_sim_test
