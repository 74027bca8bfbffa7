#include "particle_sim/core/integrators/verlet.h"

namespace particle_sim
{
namespace core
{
SolverReport VerletMethod::step(double h, DynamicSystem& system, const IntegratorDef& settings)
{
  Eigen::Matrix3Xd& x = system.positions();
  Eigen::Matrix3Xd& u = system.velocities();  // the displacement over h
  system.computeForces(x, u, force_);
  const Eigen::VectorXd& inverse_mass = system.inverseMasses();
  const bool start = !started_;
  started_ = true;
  // Per particle alone, so shared between threads by chunks of particles: a = f/m (0 for pinned
  // particles), the second-order start on the first step, then the update, into the arrays the
  // system gives (x and u themselves, or others).
  const double damping = settings.verlet_damping;
  const DynamicSystem::StateArrays next = system.nextState();
  Eigen::Matrix3Xd& next_x = *next.positions;
  Eigen::Matrix3Xd& next_u = *next.velocities;
  // Number by number on the arrays: a = f m⁻¹, u0 = u − (h/2) a on the first step (else u),
  // u' = damping u0 + h a, x' = x + h u'.
  const double* const xs = x.data();
  const double* const us = u.data();
  const double* const fs = force_.data();
  const double* const inverse = inverse_mass.data();
  double* const next_xs = next_x.data();
  double* const next_us = next_u.data();
  const double half_step = 0.5 * h;
  shareLoop(system.workers(), static_cast<int>(x.cols()), kParticlesPerVectorChunk, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
    {
      const double w = inverse[i];
      for (long k = 3L * i; k < 3L * i + 3; ++k)
      {
        const double a = fs[k] * w;
        const double u0 = start ? us[k] - half_step * a : us[k];
        const double displacement = damping * u0 + h * a;
        next_us[k] = displacement;
        next_xs[k] = xs[k] + h * displacement;
      }
    }
  });
  system.stateWritten();
  return SolverReport{};
}

}  // namespace core
}  // namespace particle_sim
