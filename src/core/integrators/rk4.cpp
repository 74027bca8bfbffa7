#include "particle_sim/core/integrators/rk4.h"

namespace particle_sim
{
namespace core
{
Rk4Method::Rk4Method(int particles)
{
  stage_x_.setZero(3, particles);
  stage_v_.setZero(3, particles);
  for (int k = 0; k < 4; ++k)
  {
    kx_[k].setZero(3, particles);
    kv_[k].setZero(3, particles);
  }
}

SolverReport Rk4Method::step(double h, DynamicSystem& system, const IntegratorDef& /*settings*/)
{
  Eigen::Matrix3Xd& x = system.positions();
  Eigen::Matrix3Xd& v = system.velocities();
  // Every stage starts from (x, v), the state this (sub)step starts from.
  kx_[0] = v;
  system.accelerations(x, v, kv_[0]);
  const double stage_offset[3] = {0.5 * h, 0.5 * h, h};
  for (int k = 1; k < 4; ++k)
  {
    stage_x_ = x + stage_offset[k - 1] * kx_[k - 1];
    stage_v_ = v + stage_offset[k - 1] * kv_[k - 1];
    kx_[k] = stage_v_;
    system.accelerations(stage_x_, stage_v_, kv_[k]);
  }
  x += (h / 6.0) * (kx_[0] + 2.0 * kx_[1] + 2.0 * kx_[2] + kx_[3]);
  v += (h / 6.0) * (kv_[0] + 2.0 * kv_[1] + 2.0 * kv_[2] + kv_[3]);
  return SolverReport{};
}

}  // namespace core
}  // namespace particle_sim
