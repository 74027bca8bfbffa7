#include "particle_sim/core/forces/global_damping.h"

namespace particle_sim
{
namespace core
{
void GlobalDampingForce::addForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                                   Eigen::Matrix3Xd& force) const
{
  if (context.damping == 0.0) return;
  for (int i = 0; i < x.cols(); ++i)
    force.col(i) -= context.damping * context.mass[i] * v.col(i);
}

void GlobalDampingForce::addJacobians(const ForceContext& context, const Eigen::Matrix3Xd& x,
                                      ImplicitEulerSolver& solver) const
{
  if (context.damping == 0.0) return;
  for (int i = 0; i < x.cols(); ++i)
    solver.addToDiagonal(i, Eigen::Matrix3d::Zero(), -context.damping * context.mass[i] * Eigen::Matrix3d::Identity());
}

}  // namespace core
}  // namespace particle_sim
