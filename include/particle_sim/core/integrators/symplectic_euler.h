#pragma once

#include "particle_sim/core/integrators/integration_method.h"

namespace particle_sim
{
namespace core
{
/// The lecture's mass-spring loop (symplectic Euler): v += h f(x, v) / m, then x += h v with the
/// new v. First order; stable for h ω <= 2.
class SymplecticEulerMethod : public IntegrationMethod
{
public:
  static constexpr const char* kName = "symplectic_euler";
  static constexpr bool kImplicit = false;
  static constexpr int kOrder = 1;                // of the global error
  static constexpr double kStabilityLimit = 2.0;  // h·ω on an undamped oscillator

  explicit SymplecticEulerMethod(int particles) : force_(Eigen::Matrix3Xd::Zero(3, particles)) {}
  SolverReport step(double h, DynamicSystem& system, const IntegratorDef& settings) override;
  bool evaluatesForcesFirst() const override { return true; }
  bool writesNextState() const override { return true; }

private:
  Eigen::Matrix3Xd force_;  // f(x, v) [N]; the update takes a = f/m particle by particle
};

/// Symplectic Euler as a body's IntegratorDef::type.
inline constexpr IntegratorType kSymplecticEulerIntegrator = IntegratorType::of<SymplecticEulerMethod>();

}  // namespace core
}  // namespace particle_sim
