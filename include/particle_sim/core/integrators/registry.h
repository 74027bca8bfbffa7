#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "particle_sim/core/integrator.h"
#include "particle_sim/core/integrators/integration_method.h"

namespace particle_sim
{
namespace core
{
/// One integrator as callers see it: its name, what it is, and how to make one for a body.
struct IntegratorInfo
{
  IntegratorType type;
  const char* name;        ///< as in scene files and services, e.g. "implicit_euler"
  bool implicit;           ///< solves a linear system each step (needs the Jacobian pattern)
  int order;               ///< convergence order of the global error on smooth problems
  double stability_limit;  ///< h·ω limit on an undamped oscillator; infinity when unconditionally stable
  /// A method for a body of `particles` whose Jacobian couples `coupled_pairs`.
  std::unique_ptr<IntegrationMethod> (*make)(int particles, const std::vector<std::pair<int, int>>& coupled_pairs);
};

/// Every integrator, one registration line each, in the order they are listed to users. `auto`
/// is not among them: it is a policy that picks one per step (see SpringNetworkBody).
const std::vector<IntegratorInfo>& integratorRegistry();

/// The entry of `type`, or null (for IntegratorType::Auto).
const IntegratorInfo* findIntegrator(IntegratorType type);

}  // namespace core
}  // namespace particle_sim
