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
  // particles), then the update, into the arrays the system gives (x and v themselves, or others).
  const DynamicSystem::StateArrays next = system.nextState();
  Eigen::Matrix3Xd& next_x = *next.positions;
  Eigen::Matrix3Xd& next_v = *next.velocities;
  shareLoop(system.workers(), static_cast<int>(x.cols()), kParticlesPerVectorChunk, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
    {
      next_v.col(i) = v.col(i) + h * (force_.col(i) * inverse_mass[i]);
      next_x.col(i) = x.col(i) + h * next_v.col(i);
    }
  });
  system.stateWritten();
  return SolverReport{};
}

}  // namespace core
}  // namespace particle_sim
