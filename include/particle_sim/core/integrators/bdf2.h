#pragma once

#include <limits>
#include <utility>
#include <vector>

#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/implicit_euler_solver.h"
#include "particle_sim/core/integrators/integration_method.h"

namespace particle_sim
{
namespace core
{
/// Second-order backward differentiation formula (BDF2), as Choi & Ko 2002 use it for cloth:
///
///   x_{n+1} = (4 x_n − x_{n−1}) / 3 + (2h/3) v_{n+1},
///   v_{n+1} = (4 v_n − v_{n−1}) / 3 + (2h/3) M⁻¹ f(x_{n+1}, v_{n+1}),
///
/// linearised as implicit Euler is (one Newton step), with h' = 2h/3, at the extrapolated state
/// x_p = 2 x_n − x_{n−1}, v_p = 2 v_n − v_{n−1} (O(h²) from the answer, so that the elements'
/// approximate Jacobian keeps the method second order), Δv = v_{n+1} − v_p:
///
///   (M − h' ∂f/∂v − h'² ∂f/∂x) Δv = M (v̂ − v_p) + h' f(x_p, v_p) + h'² ∂f/∂x w,   w = (x̂ + h' v_p − x_p) / h',
///
/// where x̂ = (4 x_n − x_{n−1}) / 3 and v̂ = (4 v_n − v_{n−1}) / 3, solved by the same modified PCG
/// (ImplicitEulerSolver) with pinned particles filtered. Pinned particles need no history: they
/// move x_n + h v_n, as with implicit Euler.
///
///  - The first step has no history (after build, reset, a switch of method, or a change of step
///    length, for which the constant-step formula does not hold): it is taken with implicit Euler.
///  - A free particle whose state was changed after the last step (collision response, Provot's
///    strain limit, a caller) restarts its history from the changed state (x', v'): v_{n−1} =
///    v' − (v_n − v_{n−1}) (the last change of velocity is kept), x_{n−1} = x' − h v'. Its next
///    step is then a consistent first-order one instead of carrying the motion from before the
///    change on (into the ground or sphere it touched), so BDF2 converges in contact.
///  - When nothing does work on the body (no wind, no moving pin) and the step gained energy, the
///    excess is taken out of the kinetic energy when that suffices (an O(h³) change on smooth
///    motion, so the order stays 2), else the step is redone with implicit Euler; either is
///    reported as an event. So, like implicit Euler, it never gains energy on its own.
class Bdf2Method : public IntegrationMethod
{
public:
  static constexpr const char* kName = "bdf2";
  static constexpr bool kImplicit = true;
  static constexpr int kOrder = 2;                                                    // of the global error
  static constexpr double kStabilityLimit = std::numeric_limits<double>::infinity();  // h·ω: A-stable

  /// `coupled_pairs`: the particle pairs the system's Jacobian couples (the solver's pattern).
  Bdf2Method(int particles, const std::vector<std::pair<int, int>>& coupled_pairs);
  SolverReport step(double h, DynamicSystem& system, const IntegratorDef& settings) override;
  /// Forgets the previous state (the next step is an implicit Euler one) and the warm starts.
  void restart() override;
  bool hasHistory() const override { return has_history_; }

private:
  // The step itself, from the history as it stands.
  SolverReport advance(double h, DynamicSystem& system, const IntegratorDef& settings);
  // Restarts the history of the free particles whose state differs from (x_left_, v_left_).
  void restartEditedParticles(double h, DynamicSystem& system);

  ImplicitEulerMethod first_step_;  // the step without history, and the fallback
  ImplicitEulerSolver solver_;
  bool has_history_ = false;
  double previous_h_ = 0.0;                                     // [s] the step length the history was taken with
  Eigen::Matrix3Xd x_previous_, v_previous_;                    // (x_{n−1}, v_{n−1}) [m], [m/s]
  Eigen::Matrix3Xd x_left_, v_left_;                            // the state the last step left [m], [m/s]
  Eigen::Matrix3Xd force_, x0_, v0_, x_hat_, x_predicted_, w_;  // work arrays; (x0, v0) = (x_n, v_n)
};

/// BDF2 as a body's IntegratorDef::type.
inline constexpr IntegratorType kBdf2Integrator = IntegratorType::of<Bdf2Method>();

}  // namespace core
}  // namespace particle_sim
