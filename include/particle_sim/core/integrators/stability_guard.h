#pragma once

#include <string>
#include <string_view>

#include "particle_sim/core/integrator.h"
#include "particle_sim/core/integrators/implicit_euler.h"

namespace particle_sim
{
namespace core
{
/// How one step will be taken, decided before it is: the method that runs and its substeps.
struct SubstepPlan
{
  IntegratorType method = kImplicitEulerIntegrator;  ///< the method that runs (never auto)
  int substeps = 1;  ///< substeps of the step, 1 ≤ substeps ≤ max_substeps (1 for an implicit method)
  /// Substeps the method's stability limit asks for before the max_substeps cap (saturated at the
  /// largest long long); above `substeps` when the cap cuts them, and the step may then blow up.
  long long needed_substeps = 1;
};

/// The stability guard of a body's time integration, `auto` included: the policy and its
/// explanations, while the body keeps the state it saves and restores.
///
///  - `auto` picks, per step, the cheaper of two methods that are stable with margin: Verlet with
///    the substeps its stability needs (as below), or implicit Euler, whose cost the body estimates
///    in substeps (implicitStepCost()); it re-decides when the bound or the step change and says
///    what it picked and why.
///  - Substeps: an explicit method gets enough substeps for h (ω_max + c_max) to stay within 90 %
///    of its stability limit, up to IntegratorDef::max_substeps.
///  - Blow-up: after an explicit step, a non-finite state or mechanical energy grown past
///    100 (|E| + scale (|g| + 1 m/s²)) is rolled back and retried with twice the substeps; at
///    max_substeps the body freezes.
///  - Freeze: a non-finite end state or a failed implicit solve restores the last good state.
///
/// Every such event is counted and the last one described.
class StabilityGuard
{
public:
  StabilityGuard() { last_event_.reserve(kEventCapacity); }

  /// `auto`'s estimate of one implicit Euler step, in explicit substeps (a force evaluation and an
  /// update each): a fixed part (forces, Jacobians, the energy checks) and the linear solve, taken as
  /// the direct solver's, `direct_in_cg_iterations` CG iterations of flops (the `auto` linear
  /// solver does no worse: it turns to the direct solver once CG needs more). The constants were
  /// measured on hang64 (docs/performance.md): a substep of Verlet took 0.18 ms, an implicit step's
  /// fixed part about 11 substeps, a CG iteration 0.6 substeps, and the direct solve's flops ran 1.5
  /// times slower than CG's on 3×3 blocks. By supernodes (`supernodal`, SparseBlockLdlt) they ran
  /// at 0.65 of CG's on hang64 (2026-12-02, one run of particle_sim_perf: the step 5.48 ms, a Verlet
  /// substep 0.121 ms, so 45 substeps, 34 of them the solve's 89 CG iterations of flops); but where
  /// the `auto` linear solver keeps CG the estimate stands for CG's iterations, which cost more
  /// (config/scenes/cloth_pile.yaml at dt = 0.005 s: about 70 a step, so a step is dearer than its
  /// 40 Verlet substeps, 7.9 against 6.7–7.4 s for 2 s). 1.0 picks right in both: implicit Euler on
  /// hang64 (64.6 against 82 substeps), Verlet on cloth_pile (46.2 against 40).
  static double implicitStepCost(double direct_in_cg_iterations, bool supernodal);
  static constexpr double kImplicitFixedCost = 11.0;  ///< [substeps]
  static constexpr double kCgIterationCost = 0.6;     ///< [substeps per CG iteration]
  static constexpr double kDirectFlopCost = 1.5;      ///< a direct solve's flop against a CG iteration's
  static constexpr double kSupernodalFlopCost = 1.0;  ///< the same, by supernodes

  /// What `auto` runs at step dt [s] with the bounds ω_max and c_max [1/s]: Verlet when the
  /// substeps its stability needs (planSubsteps) fit in max_substeps and cost no more than
  /// `implicit_cost` substeps (implicitStepCost()), else implicit Euler.
  static IntegratorType chooseAuto(double dt, double omega_max, double c_max, double implicit_cost, int max_substeps);
  /// The substeps of a step of dt [s] with the method `type` (not auto) and the bounds ω_max and
  /// c_max [1/s]: what substeps() will answer, without recording anything.
  static SubstepPlan planSubsteps(IntegratorType type, double dt, double omega_max, double c_max, int max_substeps);

  /// The method to run for `requested` at step dt [s], with the body's bounds ω_max and c_max
  /// [1/s]; `last` is the method of the previous step. Sets `switched` when `auto` picks another
  /// method than `last` (the caller then restarts the methods' histories).
  IntegratorType resolve(IntegratorType requested, double dt, double omega_max, double c_max, double implicit_cost,
                         int max_substeps, IntegratorType last, bool& switched);
  /// Forgets the `auto` decision (the bounds changed): re-decided and re-explained next step.
  void forgetChoice() { auto_choice_.clear(); }
  /// For `auto`: what it picked and why, e.g. "verlet: 5 substeps cost no more than an implicit
  /// Euler step, estimated at 90 substeps (h (omega_max + c_max) = 8.2 ...)".
  const std::string& autoChoice() const { return auto_choice_; }

  /// Substeps an explicit method `type` needs at step dt (1 for an implicit one); records an event
  /// when it splits the step into another count than `last_substeps`.
  int substeps(IntegratorType type, double dt, double omega_max, double c_max, int max_substeps, int last_substeps);

  /// Starts the blow-up check of one step: energy [J] before it, the body's energy scale [J per
  /// m/s²] and |g| [m/s²].
  void beginStep(bool explicit_method, double energy_before, double energy_scale, double gravity_norm);
  /// True when the step just taken blew up (explicit methods only).
  bool blewUp(bool finite, double energy_after) const;
  /// After a blow-up with `substeps`: the count to retry with, or 0 when already at `max_substeps`
  /// (the body freezes; `frozen_reason` says why).
  int retrySubsteps(IntegratorType type, double dt, int substeps, int max_substeps, std::string& frozen_reason);
  /// The reason to freeze after a step that ended non-finite or with a failed solve.
  std::string freezeReason(IntegratorType type, double dt, bool solve_failed);

  /// Counts and describes a stability event. Allocates nothing for a description of at most
  /// kEventCapacity characters (an event inside a warmed-up step, such as an energy correction).
  void record(std::string_view event);
  static constexpr std::size_t kEventCapacity = 512;
  long long events() const { return events_; }
  const std::string& lastEvent() const { return last_event_; }
  /// Back to no events and no `auto` decision (build, reset).
  void clear();

private:
  std::string auto_choice_;
  long long events_ = 0;
  std::string last_event_;
  bool explicit_method_ = false;
  double energy_before_ = 0.0;
  double allowed_growth_ = 0.0;
};

}  // namespace core
}  // namespace particle_sim
