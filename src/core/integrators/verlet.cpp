#include "particle_sim/core/integrators/verlet.h"

namespace particle_sim
{
namespace core
{
SolverReport VerletMethod::step(double h, DynamicSystem& system, const IntegratorDef& settings)
{
  Eigen::Matrix3Xd& x = system.positions();
  Eigen::Matrix3Xd& u = system.velocities();  // the displacement over h
  system.accelerations(x, u, acceleration_);
  if (!started_)
  {
    u -= 0.5 * h * acceleration_;
    started_ = true;
  }
  u = settings.verlet_damping * u + h * acceleration_;
  x += h * u;
  return SolverReport{};
}

}  // namespace core
}  // namespace particle_sim
