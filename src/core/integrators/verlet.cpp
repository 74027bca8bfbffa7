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
  shareLoop(system.workers(), static_cast<int>(x.cols()), kParticlesPerVectorChunk, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
    {
      const Eigen::Vector3d a = force_.col(i) * inverse_mass[i];
      const Eigen::Vector3d u0 = start ? Eigen::Vector3d(u.col(i) - 0.5 * h * a) : Eigen::Vector3d(u.col(i));
      next_u.col(i) = damping * u0 + h * a;
      next_x.col(i) = x.col(i) + h * next_u.col(i);
    }
  });
  system.stateWritten();
  return SolverReport{};
}

}  // namespace core
}  // namespace particle_sim
