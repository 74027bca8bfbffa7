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
  // particles), the second-order start on the first step, then the update.
  const double damping = settings.verlet_damping;
  shareLoop(system.workers(), static_cast<int>(x.cols()), kParticlesPerVectorChunk, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
    {
      const Eigen::Vector3d a = force_.col(i) * inverse_mass[i];
      if (start) u.col(i) -= 0.5 * h * a;
      u.col(i) = damping * u.col(i) + h * a;
      x.col(i) += h * u.col(i);
    }
  });
  return SolverReport{};
}

}  // namespace core
}  // namespace particle_sim
