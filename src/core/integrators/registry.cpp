#include "particle_sim/core/integrators/registry.h"

#include <algorithm>
#include <string>

#include "particle_sim/core/integrators/bdf2.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/rk4.h"
#include "particle_sim/core/integrators/symplectic_euler.h"
#include "particle_sim/core/integrators/verlet.h"

namespace particle_sim
{
namespace core
{
namespace
{
// The registry: the built-in methods, one integratorEntry line each, in the order listed to users
// (config/Sim.cfg reads these lines for dynamic_reconfigure's enum), then what
// ScopedIntegratorRegistration adds.
std::vector<IntegratorInfo>& registry()
{
  static std::vector<IntegratorInfo> entries{
      integratorEntry<SymplecticEulerMethod>(),
      integratorEntry<VerletMethod>(),
      integratorEntry<ImplicitEulerMethod>(),
      integratorEntry<Rk4Method>(),
      integratorEntry<Bdf2Method>(),
  };
  return entries;
}
}  // namespace

const std::vector<IntegratorInfo>& integratorRegistry()
{
  return registry();
}

const IntegratorInfo* findIntegrator(IntegratorType type)
{
  for (const IntegratorInfo& info : integratorRegistry())
  {
    if (info.type == type) return &info;
  }
  return nullptr;
}

ScopedIntegratorRegistration::ScopedIntegratorRegistration(const IntegratorInfo& entry) : type_(entry.type)
{
  IntegratorType taken = kAutoIntegrator;
  if (findIntegrator(entry.type) || parseIntegratorType(entry.name, taken))
  {
    status_ = Status::failure(std::string("integrator '") + entry.name + "' is already registered");
    return;
  }
  registry().push_back(entry);
}

ScopedIntegratorRegistration::~ScopedIntegratorRegistration()
{
  if (!status_) return;
  std::vector<IntegratorInfo>& entries = registry();
  entries.erase(
      std::remove_if(entries.begin(), entries.end(), [this](const IntegratorInfo& info) { return info.type == type_; }),
      entries.end());
}

}  // namespace core
}  // namespace particle_sim
