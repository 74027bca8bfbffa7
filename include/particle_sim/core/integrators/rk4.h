#pragma once

#include "particle_sim/core/integrators/integration_method.h"

namespace particle_sim
{
namespace core
{
/// Classical fourth-order Runge–Kutta on (x, v) with derivative (v, a(x, v)), the accuracy
/// reference. Fourth order; stable for h ω <= 2√2. Its stages start from the state it is given,
/// so a step that the stability guard splits into n substeps is n RK4 steps of h / n.
class Rk4Method : public IntegrationMethod
{
public:
  static constexpr const char* kName = "rk4";
  static constexpr bool kImplicit = false;
  static constexpr int kOrder = 4;                                     // of the global error
  static constexpr double kStabilityLimit = 2.0 * 1.4142135623730951;  // h·ω = 2√2 (the double nearest √2, doubled)

  explicit Rk4Method(int particles);
  SolverReport step(double h, DynamicSystem& system, const IntegratorDef& settings) override;
  bool evaluatesForcesFirst() const override { return true; }

private:
  Eigen::Matrix3Xd stage_x_, stage_v_, kx_[4], kv_[4];
};

/// RK4 as a body's IntegratorDef::type.
inline constexpr IntegratorType kRk4Integrator = IntegratorType::of<Rk4Method>();

}  // namespace core
}  // namespace particle_sim
