#include "particle_sim/core/integrators/symplectic_euler.h"

namespace particle_sim
{
namespace core
{
SolverReport SymplecticEulerMethod::step(double h, DynamicSystem& system, const IntegratorDef& /*settings*/)
{
  Eigen::Matrix3Xd& x = system.positions();
  Eigen::Matrix3Xd& v = system.velocities();
  system.computeForces(x, v, force_);
  const Eigen::VectorXd& inverse_mass = system.inverseMasses();
  // Per particle alone, so shared between threads by chunks of particles: a = f/m (0 for pinned
  // particles), then the update.
  shareLoop(system.workers(), static_cast<int>(x.cols()), kParticlesPerVectorChunk, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
    {
      v.col(i) += h * (force_.col(i) * inverse_mass[i]);
      x.col(i) += h * v.col(i);
    }
  });
  return SolverReport{};
}

}  // namespace core
}  // namespace particle_sim
