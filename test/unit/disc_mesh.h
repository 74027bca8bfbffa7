#pragma once
// A body-fitted triangulation of a disc for tests: `rings` concentric rings of equal spacing around a
// centre vertex, ring k (radius k R / rings) with 6k vertices, so that the triangles are near
// equilateral (a hexagon at the centre) and the rim and every ring are circles at any resolution.

#include <Eigen/Core>

#include <cmath>
#include <vector>

namespace particle_sim_test
{
struct DiscMesh
{
  std::vector<Eigen::Vector3d> vertices;  // in the plane z = 0, centre first, then ring by ring
  std::vector<Eigen::Vector2d> uvs;       // the same points, as the flat pattern
  std::vector<Eigen::Vector3i> triangles;  // counter-clockwise seen from +z
  std::vector<int> ring_start;            // first vertex of ring k (ring 0 = the centre), and the count at the end
};

inline DiscMesh discMesh(double radius, int rings)
{
  const double kTwoPi = 2.0 * std::acos(-1.0);
  DiscMesh mesh;
  mesh.ring_start.push_back(0);
  mesh.vertices.emplace_back(0.0, 0.0, 0.0);
  for (int k = 1; k <= rings; ++k)
  {
    mesh.ring_start.push_back(static_cast<int>(mesh.vertices.size()));
    const double r = radius * k / rings;
    for (int i = 0; i < 6 * k; ++i)
    {
      const double angle = kTwoPi * i / (6 * k);
      mesh.vertices.emplace_back(r * std::cos(angle), r * std::sin(angle), 0.0);
    }
  }
  mesh.ring_start.push_back(static_cast<int>(mesh.vertices.size()));
  // Between ring k − 1 (n_in vertices) and ring k (n_out): walk both by angle, each step a triangle
  // that advances the ring whose next vertex comes first.
  for (int k = 1; k <= rings; ++k)
  {
    const int n_in = 6 * (k - 1), n_out = 6 * k;
    const int in0 = mesh.ring_start[k - 1], out0 = mesh.ring_start[k];
    if (k == 1)  // the centre's fan
    {
      for (int j = 0; j < n_out; ++j)
        mesh.triangles.emplace_back(0, out0 + j, out0 + (j + 1) % n_out);
      continue;
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
  for (const Eigen::Vector3d& v : mesh.vertices)
    mesh.uvs.emplace_back(v.x(), v.y());
  return mesh;
}

}  // namespace particle_sim_test
