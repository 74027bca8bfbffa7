#include "particle_sim/core/integrator.h"

#include <limits>
#include <string>

#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/registry.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
IntegratorType::IntegratorType() : IntegratorType(kImplicitEulerIntegrator) {}

const char* toString(IntegratorType type)
{
  return type.name();
}

double stabilityLimit(IntegratorType type)
{
  const IntegratorInfo* info = findIntegrator(type);
  return info ? info->stability_limit : std::numeric_limits<double>::infinity();
}

bool isImplicit(IntegratorType type)
{
  const IntegratorInfo* info = findIntegrator(type);
  return info && info->implicit;
}

std::string integratorTypeNames()
{
  std::string list;
  for (const IntegratorInfo& info : integratorRegistry())
    list += std::string(info.name) + ", ";
  return list + toString(kAutoIntegrator);
}

bool parseIntegratorType(const std::string& text, IntegratorType& type)
{
  for (const IntegratorInfo& info : integratorRegistry())
  {
    if (text == info.name)
    {
      type = info.type;
      return true;
    }
  }
  if (text != toString(kAutoIntegrator)) return false;
  type = kAutoIntegrator;
  return true;
}

const char* toString(LinearSolverType type)
{
  switch (type)
  {
    case LinearSolverType::ConjugateGradient:
      return "cg";
    case LinearSolverType::Direct:
      return "direct";
    case LinearSolverType::Multigrid:
      return "multigrid";
    case LinearSolverType::Auto:
      break;
  }
  return "auto";
}

bool parseLinearSolverType(const std::string& text, LinearSolverType& type)
{
  for (LinearSolverType t : {LinearSolverType::Auto, LinearSolverType::ConjugateGradient, LinearSolverType::Direct,
                             LinearSolverType::Multigrid})
  {
    if (text == toString(t))
    {
      type = t;
      return true;
    }
  }
  return false;
}

const char* linearSolverTypeNames()
{
  return "auto, cg, direct, multigrid";
}

IntegratorDef resolve(const BodyIntegratorDef& body, const IntegratorDef& defaults)
{
  IntegratorDef def = defaults;
  def.type = body.type.value_or(defaults.type);
  def.verlet_damping = body.verlet_damping.value_or(defaults.verlet_damping);
  def.cg_tolerance = body.cg_tolerance.value_or(defaults.cg_tolerance);
  def.cg_velocity_tolerance = body.cg_velocity_tolerance.value_or(defaults.cg_velocity_tolerance);
  def.cg_max_iterations = body.cg_max_iterations.value_or(defaults.cg_max_iterations);
  def.max_substeps = body.max_substeps.value_or(defaults.max_substeps);
  def.linear_solver = body.linear_solver.value_or(defaults.linear_solver);
  return def;
}

BodyIntegratorDef settingEveryField(const IntegratorDef& def)
{
  return {def.type,         def.verlet_damping, def.cg_tolerance, def.cg_velocity_tolerance, def.cg_max_iterations,
          def.max_substeps, def.linear_solver};
}

Status validate(const BodyIntegratorDef& def)
{
  // The built-in defaults pass, so only a field the body sets can be refused.
  return validate(resolve(def));
}

Status validate(const IntegratorDef& def)
{
  // A method whose registration has ended (ScopedIntegratorRegistration) is no longer one.
  if (def.type != kAutoIntegrator && !findIntegrator(def.type))
    return Status::failure("integrator = " + quoteReceived(toString(def.type)) +
                           " is not registered; allowed: " + integratorTypeNames());
  if (Status s = checkRange("verlet_damping", def.verlet_damping, 0.0, 1.0); !s) return s;
  if (Status s = checkPositive("cg_tolerance", def.cg_tolerance); !s) return s;
  if (Status s = checkRange("cg_velocity_tolerance", def.cg_velocity_tolerance, limits::kSolverVelocityTolerance); !s)
    return s;
  if (Status s = checkIntRange("cg_max_iterations", def.cg_max_iterations, 1, 1000000); !s) return s;
  return checkIntRange("max_substeps", def.max_substeps, 1, 1 << 20);
}

}  // namespace core
}  // namespace particle_sim
