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
  // Per particle alone, so shared between threads by chunks of particles.
  shareLoop(system.workers(), static_cast<int>(x.cols()), kParticlesPerVectorChunk, [&](int begin, int end) {
    const int count = end - begin;
    v.middleCols(begin, count) += h * acceleration_.middleCols(begin, count);
    x.middleCols(begin, count) += h * v.middleCols(begin, count);
  });
  return SolverReport{};
}

}  // namespace core
}  // namespace particle_sim
