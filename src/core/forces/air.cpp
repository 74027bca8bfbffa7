#include "particle_sim/core/forces/air.h"

#include <Eigen/Geometry>

namespace particle_sim
{
namespace core
{
void AirForce::addForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                         Eigen::Matrix3Xd& force) const
{
  const AirDef& air = context.air;
  if (air.drag == 0.0) return;
  // Per triangle: f = drag · A · ((wind − v̄)·n) n with A n = (e1 × e2) / 2, shared by the corners.
  for (const Eigen::Vector3i& t : triangles_)
  {
    const Eigen::Vector3d area_normal = 0.5 * (x.col(t[1]) - x.col(t[0])).cross(x.col(t[2]) - x.col(t[0]));
    const double area = area_normal.norm();
    if (area == 0.0) continue;
    const Eigen::Vector3d relative = air.wind - (v.col(t[0]) + v.col(t[1]) + v.col(t[2])) / 3.0;
    // A ((u·n) n) = (u·(A n)) (A n) / A
    const Eigen::Vector3d f = air.drag * relative.dot(area_normal) / area * area_normal;
    for (int c = 0; c < 3; ++c)
      force.col(t[c]) += f / 3.0;
  }
}

}  // namespace core
}  // namespace particle_sim
