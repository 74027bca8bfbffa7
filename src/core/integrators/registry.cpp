#include "particle_sim/core/integrators/registry.h"

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
// The registry entry of `Method`, from what the method declares about itself.
template <class Method>
IntegratorInfo entry(IntegratorType type)
{
  auto make = [](int particles, const std::vector<std::pair<int, int>>& coupled_pairs) {
    std::unique_ptr<IntegrationMethod> method;
    if constexpr (Method::kImplicit)
      method = std::make_unique<Method>(particles, coupled_pairs);
    else
      method = std::make_unique<Method>(particles);
    return method;
  };
  return {type, Method::kName, Method::kImplicit, Method::kOrder, Method::kStabilityLimit, make};
}
}  // namespace

const std::vector<IntegratorInfo>& integratorRegistry()
{
  static const std::vector<IntegratorInfo> registry{
      entry<SymplecticEulerMethod>(IntegratorType::SymplecticEuler),
      entry<VerletMethod>(IntegratorType::Verlet),
      entry<ImplicitEulerMethod>(IntegratorType::ImplicitEuler),
      entry<Rk4Method>(IntegratorType::Rk4),
      entry<Bdf2Method>(IntegratorType::Bdf2),
  };
  return registry;
}

const IntegratorInfo* findIntegrator(IntegratorType type)
{
  for (const IntegratorInfo& info : integratorRegistry())
  {
    if (info.type == type) return &info;
  }
  return nullptr;
}

}  // namespace core
}  // namespace particle_sim
