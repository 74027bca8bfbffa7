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
  // v' = v + h (f m⁻¹), x' = x + h v', number by number on the arrays.
  const double* const xs = x.data();
  const double* const vs = v.data();
  const double* const fs = force_.data();
  const double* const inverse = inverse_mass.data();
  double* const next_xs = next_x.data();
  double* const next_vs = next_v.data();
  shareLoop(system.workers(), static_cast<int>(x.cols()), kParticlesPerVectorChunk, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
    {
      const double w = inverse[i];
      for (long k = 3L * i; k < 3L * i + 3; ++k)
      {
        const double velocity = vs[k] + h * (fs[k] * w);
        next_vs[k] = velocity;
        next_xs[k] = xs[k] + h * velocity;
      }
    }
  });
  system.stateWritten();
  return SolverReport{};
}

}  // namespace core
}  // namespace particle_sim
