#pragma once

#include "particle_sim/core/integrators/integration_method.h"

namespace particle_sim
{
namespace core
{
/// The lecture's Verlet, x_{n+1} = x_n + k_d (x_n − x_{n−1}) + h² f(x_n, v_n) / m, written with the
/// displacement u_n = (x_n − x_{n−1}) / h kept in the velocity array (so collisions and pins can edit
/// it like a velocity): u_{n+1} = k_d u_n + h a_n, x_{n+1} = x_n + h u_{n+1}. The first step after
/// build, reset or a switch starts it at second order: x_{−1} = x_0 − h v_0 + h² a_0 / 2, i.e.
/// u_0 = v_0 − h a_0 / 2. Second order for position-only forces (first once forces depend on
/// velocity); stable for h ω <= 2. k_d is IntegratorDef::verlet_damping.
class VerletMethod : public IntegrationMethod
{
public:
  static constexpr const char* kName = "verlet";
  static constexpr bool kImplicit = false;
  static constexpr int kOrder = 2;                // of the global error
  static constexpr double kStabilityLimit = 2.0;  // h·ω on an undamped oscillator

  explicit VerletMethod(int particles) : force_(Eigen::Matrix3Xd::Zero(3, particles)) {}
  SolverReport step(double h, DynamicSystem& system, const IntegratorDef& settings) override;
  bool evaluatesForcesFirst() const override { return true; }
  bool writesNextState() const override { return true; }
  void restart() override { started_ = false; }
  bool hasHistory() const override { return started_; }

private:
  bool started_ = false;    // false until the second-order start is done
  Eigen::Matrix3Xd force_;  // f(x, v) [N]; the update takes a = f/m particle by particle
};

/// Verlet as a body's IntegratorDef::type.
inline constexpr IntegratorType kVerletIntegrator = IntegratorType::of<VerletMethod>();

}  // namespace core
}  // namespace particle_sim
