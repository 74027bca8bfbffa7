#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "particle_sim/core/integrator.h"
#include "particle_sim/core/integrators/integration_method.h"
#include "particle_sim/core/status.h"

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

/// The registry entry of `Method`, from what the method declares about itself: `kName`,
/// `kImplicit`, `kOrder`, `kStabilityLimit`, and a constructor taking the particle count (and, for
/// an implicit method, the coupled pairs of the Jacobian's pattern).
template <class Method>
IntegratorInfo integratorEntry()
{
  auto make = [](int particles, const std::vector<std::pair<int, int>>& coupled_pairs) {
    std::unique_ptr<IntegrationMethod> method;
    if constexpr (Method::kImplicit)
      method = std::make_unique<Method>(particles, coupled_pairs);
    else
      method = std::make_unique<Method>(particles);
    return method;
  };
  return {IntegratorType::of<Method>(), Method::kName, Method::kImplicit, Method::kOrder,
          Method::kStabilityLimit,      make};
}

/// Every integrator, one registration line each in src/core/integrators/registry.cpp, in the order
/// they are listed to users. `auto` is not among them: it is a policy that picks one per step
/// (see StabilityGuard).
const std::vector<IntegratorInfo>& integratorRegistry();

/// The entry of `type`, or null (for kAutoIntegrator). Entries, and references to them, stay valid
/// until a ScopedIntegratorRegistration is made or ends.
const IntegratorInfo* findIntegrator(IntegratorType type);

/// Adds a method to the registry for as long as this object lives, after the built-in ones (for a
/// test that proves a method needs nothing but its own code and its entry, or for a program that
/// brings its own). Make it before building the bodies that may use the method and keep it
/// until they are gone; not thread-safe (registration happens before stepping). A method or name
/// already registered (or "auto") is refused: status() says why, and nothing is added or removed.
class ScopedIntegratorRegistration
{
public:
  /// Registers `entry`, normally integratorEntry<Method>().
  explicit ScopedIntegratorRegistration(const IntegratorInfo& entry);
  ~ScopedIntegratorRegistration();
  ScopedIntegratorRegistration(const ScopedIntegratorRegistration&) = delete;
  ScopedIntegratorRegistration& operator=(const ScopedIntegratorRegistration&) = delete;

  const Status& status() const { return status_; }

private:
  IntegratorType type_;
  Status status_;
};

}  // namespace core
}  // namespace particle_sim
