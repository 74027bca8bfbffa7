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
  // Per particle alone, so shared between threads by chunks of particles.
  const double damping = settings.verlet_damping;
  shareLoop(system.workers(), static_cast<int>(x.cols()), kParticlesPerVectorChunk, [&](int begin, int end) {
    const int count = end - begin;
    u.middleCols(begin, count) = damping * u.middleCols(begin, count) + h * acceleration_.middleCols(begin, count);
    x.middleCols(begin, count) += h * u.middleCols(begin, count);
  });
  return SolverReport{};
}

}  // namespace core
}  // namespace particle_sim
