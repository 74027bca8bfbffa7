#include "particle_sim/core/integrators/implicit_euler.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "particle_sim/core/integrators/stability_guard.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
ImplicitEulerMethod::ImplicitEulerMethod(int particles, const std::vector<std::pair<int, int>>& coupled_pairs)
{
  solver_.setPattern(particles, coupled_pairs);
  force_.setZero(3, particles);
  x0_.setZero(3, particles);
  v0_.setZero(3, particles);
}

SolverReport ImplicitEulerMethod::step(double h, DynamicSystem& system, const IntegratorDef& settings)
{
  Eigen::Matrix3Xd& x = system.positions();
  Eigen::Matrix3Xd& v = system.velocities();
  const Eigen::VectorXd& mass = system.masses();
  const std::vector<char>& pinned = system.pinned();
  const int n = static_cast<int>(x.cols());

  // Without moving pins or wind nothing does work on the body, so its energy must not grow.
  const bool conservative = system.nothingDoesWork();
  const double energy_before = conservative ? system.mechanicalEnergy() : 0.0;
  x0_ = x;
  v0_ = v;

  // 1. Baraff & Witkin's step: one linearisation at (x0, v0).
  system.computeForces(x, v, force_);
  solver_.begin(h, mass, force_, &v0_);
  system.addJacobians(x, solver_);
  SolverReport report = solver_.solve(pinned, settings, x, v);
  if (!conservative || report.breakdown) return report;

  // 2. If that one linearisation gained energy (large rotations or stretches in one step), Newton
  //    iterations of full backward Euler: solve (M − h ∂f/∂v − h² ∂f/∂x) δ = h f(x_k, v_k) − M (v_k − v0)
  //    at x_k = x0 + h v_k, then v_{k+1} = v_k + δ.
  const double tolerance = 1e-12 * (1.0 + std::abs(energy_before));
  int newton = 0;
  for (; newton < kNewtonIterations && system.mechanicalEnergy() > energy_before + tolerance; ++newton)
  {
    system.computeForces(x, v, force_);
    for (int i = 0; i < n; ++i)
      force_.col(i) -= mass[i] * (v.col(i) - v0_.col(i)) / h;
    solver_.begin(h, mass, force_, nullptr);
    system.addJacobians(x, solver_);
    x = x0_;  // the solve sets x = x0 + h v_{k+1}
    report = solver_.solve(pinned, settings, x, v);
    if (report.breakdown) return report;
  }

  // 3. Still more energy than before (a non-convex energy can do that even to backward Euler): the
  //    excess is taken out of the kinetic energy, and reported.
  const double energy_after = system.mechanicalEnergy();
  if (energy_after > energy_before + tolerance)
  {
    const double kinetic = system.kineticEnergy();
    const double allowed = std::max(0.0, kinetic - (energy_after - energy_before));
    const double scale = kinetic > 0.0 ? std::sqrt(allowed / kinetic) : 0.0;
    for (int i = 0; i < n; ++i)
    {
      if (!pinned[i]) v.col(i) *= scale;
    }
    char event[StabilityGuard::kEventCapacity];
    std::snprintf(
        event, sizeof event,
        "implicit_euler would have gained %.6g J in one step (%d Newton iterations); velocities scaled by %.6g",
        energy_after - energy_before, newton, scale);
    system.recordEvent(event);
  }
  return report;
}

}  // namespace core
}  // namespace particle_sim
