#include "particle_sim/core/integrators/implicit_euler.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

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
  v_newton_.setZero(3, particles);
  delta_.setZero(3, particles);
}

SolverReport ImplicitEulerMethod::step(double h, DynamicSystem& system, const IntegratorDef& settings)
{
  solver_.setWorkers(system.workers());
  Eigen::Matrix3Xd& x = system.positions();
  Eigen::Matrix3Xd& v = system.velocities();
  const Eigen::VectorXd& mass = system.masses();
  const std::vector<char>& pinned = system.pinned();
  const int n = static_cast<int>(x.cols());

  // Without moving pins or wind nothing does work on the body, so its energy must not grow: its
  // energy at (x0, v0) comes from the pass that computes the forces there.
  const bool conservative = system.nothingDoesWork();
  double energy_before = 0.0;
  if (conservative)
    energy_before = system.computeForcesAndEnergy(force_);
  else
    system.computeForces(x, v, force_);
  x0_ = x;
  v0_ = v;

  // 1. Baraff & Witkin's step: one linearisation at (x0, v0).
  solver_.begin(h, mass, force_, &v0_);
  system.addJacobians(x, solver_);
  SolverReport report = solver_.solve(pinned, system.restingContacts(), settings, x, v);
  if (!conservative || report.breakdown) return report;

  // 2. If that one linearisation gained energy (large rotations or stretches in one step), Newton
  //    iterations of full backward Euler: solve (M − h ∂f/∂v − h² ∂f/∂x) δ = h f(x_k, v_k) − M (v_k − v0)
  //    at x_k = x0 + h v_k, then v_{k+1} = v_k + δ, until the energy is no longer above its value
  //    before the step.
  //    The energy is measured once per state the step reaches (a pass over every element).
  const double tolerance = 1e-12 * (1.0 + std::abs(energy_before));
  double energy_after = system.mechanicalEnergy();
  int newton = 0;
  for (; newton < kNewtonIterations && energy_after > energy_before + tolerance; ++newton)
  {
    system.computeForces(x, v, force_);
    for (int i = 0; i < n; ++i)
      force_.col(i) -= mass[i] * (v.col(i) - v0_.col(i)) / h;
    solver_.begin(h, mass, force_, nullptr);
    system.addJacobians(x, solver_);
    x = x0_;  // the solve sets x = x0 + h v_{k+1}
    report = solver_.solve(pinned, system.restingContacts(), settings, x, v);
    if (report.breakdown) return report;
    energy_after = system.mechanicalEnergy();
  }
  if (energy_after > energy_before + tolerance)
  {
    convergedBackwardEuler(h, system, settings, newton, report);
    if (report.breakdown) return report;
    energy_after = system.mechanicalEnergy();
  }

  // 3. Still more energy than before (a non-convex energy can do that even to backward Euler): the
  //    excess is taken out of the kinetic energy, and reported.
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

void ImplicitEulerMethod::convergedBackwardEuler(double h, DynamicSystem& system, const IntegratorDef& settings,
                                                 int& newton, SolverReport& report)
{
  // Newton iterations that converge where those of step() diverge: on stiff springs that turn far in
  // one step, the linearised step stretches them along their tangents and each correction overshoots.
  // Each iteration moves v_{k+1} = v_k + α δ, α halved until the step lowers backward Euler's
  // incremental potential Φ(v) = ½ (v − v0)ᵀ M (v − v0) + U(x0 + h v), whose minimum is the
  // conservative part of the step (a line search). They start from v0 or from where step() left v,
  // whichever has the lower Φ, and stop when the residual force f − M (v − v0) / h of the free
  // particles is below kNewtonTolerance of the force at v0, or when no α lowers Φ.
  Eigen::Matrix3Xd& x = system.positions();
  Eigen::Matrix3Xd& v = system.velocities();
  const Eigen::VectorXd& mass = system.masses();
  const std::vector<char>& pinned = system.pinned();
  const int n = static_cast<int>(x.cols());
  auto incrementalPotential = [&]() {  // Φ at the current (x, v)
    double phi = system.mechanicalEnergy() - system.kineticEnergy();
    for (int i = 0; i < n; ++i)
    {
      if (!pinned[i]) phi += 0.5 * mass[i] * (v.col(i) - v0_.col(i)).squaredNorm();
    }
    return phi;
  };
  auto freeNorm = [&pinned, n](const Eigen::Matrix3Xd& f) {
    double sum = 0.0;
    for (int i = 0; i < n; ++i)
    {
      if (!pinned[i]) sum += f.col(i).squaredNorm();
    }
    return std::sqrt(sum);
  };

  double phi = incrementalPotential();
  v_newton_ = v;
  v = v0_;
  x = x0_ + h * v;
  system.computeForces(x, v, force_);
  const double force_scale = freeNorm(force_) + std::numeric_limits<double>::min();
  if (const double phi0 = incrementalPotential(); phi0 < phi)
    phi = phi0;
  else
  {
    v = v_newton_;
    x = x0_ + h * v;
  }
  for (int iteration = 0; iteration < kConvergedNewtonIterations; ++iteration, ++newton)
  {
    system.computeForces(x, v, force_);
    for (int i = 0; i < n; ++i)
      force_.col(i) -= mass[i] * (v.col(i) - v0_.col(i)) / h;
    if (freeNorm(force_) <= kNewtonTolerance * force_scale) break;
    solver_.begin(h, mass, force_, nullptr);
    system.addJacobians(x, solver_);
    v_newton_ = v;  // v_k
    x = x0_;        // the solve sets x = x0 + h v_{k+1}
    report = solver_.solve(pinned, system.restingContacts(), settings, x, v);
    if (report.breakdown) return;
    delta_ = v - v_newton_;
    double alpha = 1.0, trial = incrementalPotential();
    for (int halving = 0; halving < kLineSearchHalvings && !(trial <= phi); ++halving)
    {
      alpha *= 0.5;
      v = v_newton_ + alpha * delta_;
      x = x0_ + h * v;
      trial = incrementalPotential();
    }
    if (!(trial <= phi))  // no α lowers Φ: keep v_k and stop
    {
      v = v_newton_;
      x = x0_ + h * v;
      break;
    }
    phi = trial;
  }
}

}  // namespace core
}  // namespace particle_sim
