#include "particle_sim/core/integrator.h"

#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
const char* toString(IntegratorType type)
{
  switch (type)
  {
    case IntegratorType::SymplecticEuler:
      return "symplectic_euler";
    case IntegratorType::Verlet:
      return "verlet";
    case IntegratorType::ImplicitEuler:
      return "implicit_euler";
    case IntegratorType::Rk4:
      return "rk4";
  }
  return "unknown";
}

const char* integratorTypeNames() { return "symplectic_euler, verlet, implicit_euler, rk4"; }

bool parseIntegratorType(const std::string& text, IntegratorType& type)
{
  for (IntegratorType candidate : {IntegratorType::SymplecticEuler, IntegratorType::Verlet,
                                   IntegratorType::ImplicitEuler, IntegratorType::Rk4})
  {
    if (text == toString(candidate))
    {
      type = candidate;
      return true;
    }
  }
  return false;
}

Status validate(const IntegratorDef& def)
{
  if (Status s = checkRange("verlet_damping", def.verlet_damping, 0.0, 1.0); !s) return s;
  if (Status s = checkPositive("cg_tolerance", def.cg_tolerance); !s) return s;
  return checkIntRange("cg_max_iterations", def.cg_max_iterations, 1, 1000000);
}

}  // namespace core
}  // namespace particle_sim
