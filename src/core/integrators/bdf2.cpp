#include "particle_sim/core/integrators/bdf2.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "particle_sim/core/integrators/stability_guard.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
Bdf2Method::Bdf2Method(int particles, const std::vector<std::pair<int, int>>& coupled_pairs)
    : first_step_(particles, coupled_pairs)
{
  solver_.setPattern(particles, coupled_pairs);
  x_previous_.setZero(3, particles);
  v_previous_.setZero(3, particles);
  force_.setZero(3, particles);
  x0_.setZero(3, particles);
  v0_.setZero(3, particles);
  x_hat_.setZero(3, particles);
  x_predicted_.setZero(3, particles);
  w_.setZero(3, particles);
  x_left_.setZero(3, particles);
  v_left_.setZero(3, particles);
}

void Bdf2Method::restart()
{
  has_history_ = false;
  first_step_.restart();
  solver_.clearWarmStart();
}

SolverReport Bdf2Method::step(double h, DynamicSystem& system, const IntegratorDef& settings)
{
  solver_.setWorkers(system.workers());
  if (has_history_ && h == previous_h_) restartEditedParticles(h, system);
  const SolverReport report = advance(h, system, settings);
  x_left_ = system.positions();
  v_left_ = system.velocities();
  return report;
}

void Bdf2Method::restartEditedParticles(double h, DynamicSystem& system)
{
  // A free particle whose state is not the one the last step left (a collision, Provot's strain
  // limit or a caller changed it) had its history (x_{n−1}, v_{n−1}) taken before that change,
  // and BDF2 would carry the old motion on (into the surface it touched). Its history restarts
  // from the changed state (x', v') so that the next step is a consistent first-order step:
  //  - the velocity history keeps the last step's change of velocity, since the forces did not
  //    change, only the state: v_{n−1} = v' − (v_n − v_{n−1}), so v̂ = v' + (v_n − v_{n−1}) / 3;
  //  - the position history is that of a particle arriving at x' with v': x_{n−1} = x' − h v',
  //    so x̂ = x' + h v' / 3.
  // No force is evaluated (an explicit one would cost BDF2 its stability at large steps).
  const Eigen::Matrix3Xd& x = system.positions();
  const Eigen::Matrix3Xd& v = system.velocities();
  const std::vector<char>& pinned = system.pinned();
  for (int i = 0; i < static_cast<int>(x.cols()); ++i)
  {
    if (pinned[i] || (x.col(i) == x_left_.col(i) && v.col(i) == v_left_.col(i))) continue;
    v_previous_.col(i) = v.col(i) - (v_left_.col(i) - v_previous_.col(i));
    x_previous_.col(i) = x.col(i) - h * v.col(i);
  }
}

SolverReport Bdf2Method::advance(double h, DynamicSystem& system, const IntegratorDef& settings)
{
  Eigen::Matrix3Xd& x = system.positions();
  Eigen::Matrix3Xd& v = system.velocities();

  // No history, or one taken with another step length: an implicit Euler step starts it.
  if (!has_history_ || h != previous_h_)
  {
    x_previous_ = x;
    v_previous_ = v;
    const SolverReport report = first_step_.step(h, system, settings);
    has_history_ = !report.breakdown;
    previous_h_ = h;
    solver_.clearWarmStart();
    return report;
  }

  const Eigen::VectorXd& mass = system.masses();
  const std::vector<char>& pinned = system.pinned();
  const int n = static_cast<int>(x.cols());

  // Without moving pins or wind nothing does work on the body, so its energy must not grow.
  const bool conservative = system.nothingDoesWork();
  const double energy_before = conservative ? system.mechanicalEnergy() : 0.0;
  x0_ = x;
  v0_ = v;

  // The BDF2 step as one Newton step of an implicit Euler solve with h' = 2h/3, linearised at the
  // extrapolated state (x_p, v_p) = (2 x_n − x_{n−1}, 2 v_n − v_{n−1}), which is O(h²) from the
  // answer: the Jacobian the force elements give is not the exact one (the definite form; no
  // ∂f_damping/∂x), and linearising at (x_n, v_n), O(h) away, would make that error first order.
  // Unknown Δv = v_{n+1} − v_p; the history enters the right-hand side through M (v̂ − v_p) / h'
  // (added to the force) and w = (x̂ + h' v_p − x_p) / h' (whose h'² ∂f/∂x w term the solver adds).
  // Pinned particles: x_p = x_n + h v_n, v_p = v_n, x̂ = x_n + h v_n / 3, so they move x_n + h v_n.
  const double h_bdf = 2.0 * h / 3.0;
  for (int i = 0; i < n; ++i)
  {
    if (pinned[i])
    {
      x_predicted_.col(i) = x0_.col(i) + h * v0_.col(i);
      v.col(i) = v0_.col(i);
      x_hat_.col(i) = x0_.col(i) + (h / 3.0) * v0_.col(i);
    }
    else
    {
      x_predicted_.col(i) = 2.0 * x0_.col(i) - x_previous_.col(i);
      v.col(i) = 2.0 * v0_.col(i) - v_previous_.col(i);
      x_hat_.col(i) = (4.0 * x0_.col(i) - x_previous_.col(i)) / 3.0;
    }
  }
  system.computeForces(x_predicted_, v, force_);
  for (int i = 0; i < n; ++i)
  {
    if (!pinned[i]) force_.col(i) += mass[i] * ((4.0 * v0_.col(i) - v_previous_.col(i)) / 3.0 - v.col(i)) / h_bdf;
    w_.col(i) = (x_hat_.col(i) + h_bdf * v.col(i) - x_predicted_.col(i)) / h_bdf;
  }
  solver_.begin(h_bdf, mass, force_, &w_);
  system.addJacobians(x_predicted_, solver_);
  x = x_hat_;  // the solve sets v = v_p + Δv, x = x̂ + h' v
  SolverReport report = solver_.solve(pinned, system.restingContacts(), settings, x, v);
  x_previous_ = x0_;
  v_previous_ = v0_;
  if (!conservative || report.breakdown) return report;

  // Energy gained (a 2-step method's energy may rise in one step; large rotations or stretches
  // in one step can make the linearisation gain more): taken out of the kinetic energy of the
  // motion relative to the free particles' centre of mass (so momentum is kept) when that
  // suffices, else the step is redone with implicit Euler, which never gains energy.
  const double tolerance = 1e-12 * (1.0 + std::abs(energy_before));
  const double gained = system.mechanicalEnergy() - energy_before;
  if (gained <= tolerance) return report;
  double free_mass = 0.0;
  Eigen::Vector3d momentum = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i)
  {
    if (pinned[i]) continue;
    free_mass += mass[i];
    momentum += mass[i] * v.col(i);
  }
  const Eigen::Vector3d centre_velocity =
      free_mass > 0.0 ? Eigen::Vector3d(momentum / free_mass) : Eigen::Vector3d::Zero();
  double relative_kinetic = 0.0;
  for (int i = 0; i < n; ++i)
  {
    if (!pinned[i]) relative_kinetic += 0.5 * mass[i] * (v.col(i) - centre_velocity).squaredNorm();
  }
  if (gained < relative_kinetic)
  {
    const double scale = std::sqrt((relative_kinetic - gained) / relative_kinetic);
    for (int i = 0; i < n; ++i)
    {
      if (!pinned[i]) v.col(i) = centre_velocity + scale * (v.col(i) - centre_velocity);
    }
    char event[StabilityGuard::kEventCapacity];
    std::snprintf(event, sizeof event,
                  "bdf2 would have gained %.6g J in one step; velocities relative to the centre of mass scaled by %.6g",
                  gained, scale);
    system.recordEvent(event);
    return report;
  }
  x = x0_;
  v = v0_;
  char event[StabilityGuard::kEventCapacity];
  std::snprintf(event, sizeof event,
                "bdf2 would have gained %.6g J in one step, more than the kinetic energy of the relative motion; step "
                "redone with implicit_euler",
                gained);
  system.recordEvent(event);
  return first_step_.step(h, system, settings);
}

}  // namespace core
}  // namespace particle_sim
