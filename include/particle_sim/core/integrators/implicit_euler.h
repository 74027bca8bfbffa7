#pragma once

#include <limits>
#include <utility>
#include <vector>

#include "particle_sim/core/integrators/implicit_euler_solver.h"
#include "particle_sim/core/integrators/integration_method.h"

namespace particle_sim
{
namespace core
{
/// Linearised backward Euler (Baraff & Witkin 1998), first order and unconditionally stable:
///  1. one linearisation at (x0, v0), solved by the modified PCG of ImplicitEulerSolver;
///  2. when nothing does work on the body (no wind, no moving pin) and that step gained energy
///     (large rotations or stretches in one step), Newton iterations of full backward Euler:
///     (M − h ∂f/∂v − h² ∂f/∂x) δ = h f(x_k, v_k) − M (v_k − v0) at x_k = x0 + h v_k,
///     v_{k+1} = v_k + δ, while the energy is above its value before the step; should that still
///     gain energy, Newton iterations with a line search on backward Euler's incremental potential
///     (convergedBackwardEuler()), until the residual force is 1e-8 of the step's force;
///  3. energy still gained is taken out of the kinetic energy, and reported as an event.
class ImplicitEulerMethod : public IntegrationMethod
{
public:
  static constexpr const char* kName = "implicit_euler";
  static constexpr bool kImplicit = true;
  static constexpr int kOrder = 1;                                                    // of the global error
  static constexpr double kStabilityLimit = std::numeric_limits<double>::infinity();  // h·ω: unconditionally stable

  /// `coupled_pairs`: the particle pairs the system's Jacobian couples (the solver's pattern).
  ImplicitEulerMethod(int particles, const std::vector<std::pair<int, int>>& coupled_pairs);
  SolverReport step(double h, DynamicSystem& system, const IntegratorDef& settings) override;
  /// Forgets the solver's warm start.
  void restart() override { solver_.clearWarmStart(); }

private:
  // Newton iterations of full backward Euler after those of step() left the energy above its value
  // before the step; `newton` counts them on, `report` is their last solve's.
  void convergedBackwardEuler(double h, DynamicSystem& system, const IntegratorDef& settings, int& newton,
                              SolverReport& report);

  static constexpr int kNewtonIterations = 8;
  static constexpr int kConvergedNewtonIterations = 30;
  static constexpr double kNewtonTolerance = 1e-8;  // residual force / force at v0
  static constexpr int kLineSearchHalvings = 12;    // α down to 1/4096
  ImplicitEulerSolver solver_;
  // Work arrays: (x0, v0) = state at the start of the (sub)step; v_k and δ of a Newton iteration.
  Eigen::Matrix3Xd force_, x0_, v0_, v_newton_, delta_;
};

/// Implicit Euler as a body's IntegratorDef::type.
inline constexpr IntegratorType kImplicitEulerIntegrator = IntegratorType::of<ImplicitEulerMethod>();

}  // namespace core
}  // namespace particle_sim
