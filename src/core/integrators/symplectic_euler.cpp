#include "particle_sim/core/integrators/symplectic_euler.h"

namespace particle_sim
{
namespace core
{
SolverReport SymplecticEulerMethod::step(double h, DynamicSystem& system, const IntegratorDef& /*settings*/)
{
  Eigen::Matrix3Xd& x = system.positions();
  Eigen::Matrix3Xd& v = system.velocities();
  system.accelerations(x, v, acceleration_);
  v += h * acceleration_;
  x += h * v;
  return SolverReport{};
}

}  // namespace core
}  // namespace particle_sim
