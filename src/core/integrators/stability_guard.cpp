#include "particle_sim/core/integrators/stability_guard.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/verlet.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
double StabilityGuard::implicitStepCost(double direct_in_cg_iterations, bool supernodal)
{
  return kImplicitFixedCost +
         kCgIterationCost * (supernodal ? kSupernodalFlopCost : kDirectFlopCost) * direct_in_cg_iterations;
}

IntegratorType StabilityGuard::chooseAuto(double dt, double omega_max, double c_max, double implicit_cost,
                                          int max_substeps)
{
  // Verlet with the substeps it needs to stay within 90 % of its limit, when they all fit and cost
  // no more than one implicit step; implicit Euler otherwise.
  const SubstepPlan verlet = planSubsteps(kVerletIntegrator, dt, omega_max, c_max, max_substeps);
  const bool fits = verlet.needed_substeps <= max_substeps;
  return fits && verlet.substeps <= implicit_cost ? kVerletIntegrator : kImplicitEulerIntegrator;
}

SubstepPlan StabilityGuard::planSubsteps(IntegratorType type, double dt, double omega_max, double c_max,
                                         int max_substeps)
{
  SubstepPlan plan;
  plan.method = type;
  if (isImplicit(type)) return plan;
  // See instability coming: enough substeps for h (ω_max + c_max) to stay within 90 % of the limit.
  const double needed = std::ceil(dt * (omega_max + c_max) / (0.9 * stabilityLimit(type)));
  // Compared before any conversion: a count beyond int (or NaN) is capped, never cast.
  plan.substeps = std::max(needed < max_substeps ? static_cast<int>(needed) : max_substeps, 1);
  constexpr double kSaturated = 9.2e18;  // below the largest long long, 2^63 − 1
  plan.needed_substeps =
      needed < kSaturated ? std::max(static_cast<long long>(needed), 1LL) : std::numeric_limits<long long>::max();
  return plan;
}

IntegratorType StabilityGuard::resolve(IntegratorType requested, double dt, double omega_max, double c_max,
                                       double implicit_cost, int max_substeps, IntegratorType last, bool& switched)
{
  switched = false;
  if (requested != kAutoIntegrator) return requested;
  const IntegratorType choice = chooseAuto(dt, omega_max, c_max, implicit_cost, max_substeps);
  if (auto_choice_.empty() || choice != last)
  {
    switched = choice != last;
    const SubstepPlan verlet = planSubsteps(kVerletIntegrator, dt, omega_max, c_max, max_substeps);
    const std::string why = " (h (omega_max + c_max) = " + formatValue(dt * (omega_max + c_max)) +
                            " against Verlet's limit 2 with 10 % " + "margin; omega_max = " + formatValue(omega_max) +
                            " 1/s, c_max = " + formatValue(c_max) + " 1/s, dt = " + formatValue(dt) + " s)";
    const std::string implicit = "an implicit Euler step, estimated at " + formatValue(implicit_cost) + " substeps";
    if (choice == kVerletIntegrator)
      auto_choice_ = std::string(toString(choice)) + ": " + std::to_string(verlet.substeps) +
                     (verlet.substeps == 1 ? " substep costs" : " substeps cost") + " no more than " + implicit + why;
    else if (verlet.needed_substeps > max_substeps)
      auto_choice_ = std::string(toString(choice)) + ": Verlet would need " + std::to_string(verlet.needed_substeps) +
                     " substeps, more than max_substeps = " + std::to_string(max_substeps) + why;
    else
      auto_choice_ = std::string(toString(choice)) + ": Verlet would need " + std::to_string(verlet.substeps) +
                     " substeps, more than " + implicit + why;
  }
  return choice;
}

int StabilityGuard::substeps(IntegratorType type, double dt, double omega_max, double c_max, int max_substeps,
                             int last_substeps)
{
  const int substeps = planSubsteps(type, dt, omega_max, c_max, max_substeps).substeps;
  if (substeps > 1 && substeps != last_substeps)
  {
    char event[kEventCapacity];
    std::snprintf(event, sizeof event,
                  "%s needs h (omega + c) <= %.6g: dt = %.6g s split into %d substeps (omega_max = %.6g 1/s)",
                  toString(type), stabilityLimit(type), dt, substeps, omega_max);
    record(event);
  }
  return substeps;
}

void StabilityGuard::beginStep(bool explicit_method, double energy_before, double energy_scale, double gravity_norm)
{
  explicit_method_ = explicit_method;
  energy_before_ = explicit_method ? energy_before : 0.0;
  allowed_growth_ = 100.0 * (std::abs(energy_before_) + energy_scale * (gravity_norm + 1.0));
}

bool StabilityGuard::blewUp(bool finite, double energy_after) const
{
  return explicit_method_ && (!finite || energy_after > energy_before_ + allowed_growth_);
}

int StabilityGuard::retrySubsteps(IntegratorType type, double dt, int substeps, int max_substeps,
                                  std::string& frozen_reason)
{
  if (substeps >= max_substeps)
  {
    frozen_reason = std::string(toString(type)) + " blew up at dt = " + formatValue(dt) + " s even with " +
                    std::to_string(substeps) + " substeps (integrator.max_substeps); the body is frozen at its " +
                    "last good state";
    record(frozen_reason);
    return 0;
  }
  const int retry = std::min(2 * substeps, max_substeps);
  record(std::string(toString(type)) + " blew up at dt = " + formatValue(dt) + " s; step rolled back and " +
         "retried with " + std::to_string(retry) + " substeps");
  return retry;
}

std::string StabilityGuard::freezeReason(IntegratorType type, double dt, bool solve_failed)
{
  std::string reason =
      std::string(solve_failed ? "the implicit solve failed (CG breakdown)" : "state became non-finite") + " under " +
      toString(type) + " at dt = " + formatValue(dt) + " s; the body is frozen at its last good state";
  record(reason);
  return reason;
}

void StabilityGuard::record(std::string_view event)
{
  ++events_;
  last_event_.assign(event.data(), event.size());  // within the capacity reserved at construction
}

void StabilityGuard::clear()
{
  auto_choice_.clear();
  events_ = 0;
  last_event_.clear();
}

}  // namespace core
}  // namespace particle_sim
