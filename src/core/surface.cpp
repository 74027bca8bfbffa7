#include "particle_sim/core/surface.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "particle_sim/core/limits.h"

namespace particle_sim
{
namespace core
{
double clothContactThickness(const std::vector<Eigen::Vector3d>& positions,
                             const std::vector<Eigen::Vector3i>& triangles,
                             const std::vector<SphereColliderDef>& spheres)
{
  if (spheres.empty()) return 0.0;
  double radius = spheres.front().radius;
  for (const SphereColliderDef& sphere : spheres)
    radius = std::min(radius, sphere.radius);
  double longest = 0.0;
  for (const Eigen::Vector3i& t : triangles)
    for (int c = 0; c < 3; ++c)
      longest = std::max(longest, (positions[t[(c + 1) % 3]] - positions[t[c]]).norm());
  // Depth of the circumcentre of a triangle of circumradius ρ ≤ L/√3 inscribed in the sphere.
  const double rho_squared = longest * longest / 3.0;
  const double depth = rho_squared / (radius + std::sqrt(std::max(0.0, radius * radius - rho_squared)));
  return std::min(depth, limits::kContactThickness.max);
}

void vertexNormals(const Eigen::Matrix3Xd& positions, int count, const std::vector<Eigen::Vector3i>& triangles,
                   std::vector<Eigen::Vector3d>& normals)
{
  normals.assign(count, Eigen::Vector3d::Zero());
  // The cross product of two edges is the normal times twice the area: summing it weights by area.
  for (const Eigen::Vector3i& t : triangles)
  {
    const Eigen::Vector3d e1 = positions.col(t[1]) - positions.col(t[0]);
    const Eigen::Vector3d e2 = positions.col(t[2]) - positions.col(t[0]);
    const Eigen::Vector3d area_normal = e1.cross(e2);
    for (int c = 0; c < 3; ++c)
      normals[t[c]] += area_normal;
  }
  for (Eigen::Vector3d& normal : normals)
  {
    const double length = normal.norm();
    if (length > 0.0) normal /= length;
  }
}

void vertexStrains(const SpringNetworkBody& body, std::vector<double>& strains)
{
  const ParticlePool& p = body.particles();
  strains.assign(p.size(), 0.0);
  if (body.baraffWitkin()) body.baraffWitkin()->vertexStrains(p.position, strains);
  for (const Spring& s : body.springs())
  {
    if (s.spring_class == SpringClass::Bend || s.rest_length == 0.0) continue;
    const double strain = ((p.position.col(s.j) - p.position.col(s.i)).norm() - s.rest_length) / s.rest_length;
    strains[s.i] = std::max(strains[s.i], strain);
    strains[s.j] = std::max(strains[s.j], strain);
  }
}

}  // namespace core
}  // namespace particle_sim
