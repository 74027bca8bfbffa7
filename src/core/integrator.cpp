#include "particle_sim/core/integrator.h"

#include <cmath>
#include <limits>

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
    case IntegratorType::Auto:
      return "auto";
  }
  return "unknown";
}

double stabilityLimit(IntegratorType type)
{
  switch (type)
  {
    case IntegratorType::SymplecticEuler:
    case IntegratorType::Verlet:
      return 2.0;
    case IntegratorType::Rk4:
      return 2.0 * std::sqrt(2.0);
    case IntegratorType::ImplicitEuler:
    case IntegratorType::Auto:
      break;
  }
  return std::numeric_limits<double>::infinity();
}

const char* integratorTypeNames()
{
  return "symplectic_euler, verlet, implicit_euler, rk4, auto";
}

bool parseIntegratorType(const std::string& text, IntegratorType& type)
{
  for (IntegratorType candidate : {IntegratorType::SymplecticEuler, IntegratorType::Verlet,
                                   IntegratorType::ImplicitEuler, IntegratorType::Rk4, IntegratorType::Auto})
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
  if (Status s = checkIntRange("cg_max_iterations", def.cg_max_iterations, 1, 1000000); !s) return s;
  return checkIntRange("max_substeps", def.max_substeps, 1, 1 << 20);
}

}  // namespace core
}  // namespace particle_sim
