#include "particle_sim/core/builders/rope.h"

#include <cmath>

#include "particle_sim/core/builders/pins.h"
#include "particle_sim/core/names.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
namespace
{
constexpr double kPi = 3.14159265358979323846;

double totalRestLength(const RopeDef& def)
{
  return def.rest_length > 0.0 ? def.rest_length : (def.end - def.start).norm();
}

/// The material, then the spring constants it gives at this segment length within the ranges every
/// spring is held to (limits.h): a very stiff material on very short segments is refused here, by
/// name, rather than as springs[k] of the built network.
Status validateMaterial(const RopeMaterial& material, double rest_length, int particles)
{
  if (Status s = validate(material); !s) return Status::failure("material." + s.message);
  const double segment = rest_length / (particles - 1);
  const RopeSpringConstants constants = ropeStretchConstants(material, rest_length, segment);
  const std::string built = " for segments of " + formatValue(segment) + " m (" + std::to_string(particles) +
                            " particles over " + formatValue(rest_length) + " m)";
  if (Status s = checkRange("stretch stiffness EA / l", constants.stiffness, limits::kStiffness); !s)
    return Status::failure("material.axial_stiffness = " + formatValue(material.axial_stiffness) + " N gives " +
                           s.message + built + ": use fewer particles or a softer material");
  if (Status s = checkRange("stretch damping", constants.damping, limits::kDamping); !s)
    return Status::failure("material.damping_ratio = " + formatValue(material.damping_ratio) + " gives " + s.message +
                           built + ": use fewer particles or a smaller damping ratio");
  return Status::success();
}
}  // namespace

RopeSpringConstants ropeStretchConstants(const RopeMaterial& material, double rest_length, double segment)
{
  // Kelvin–Voigt axial viscosity η [N·s] that gives the lowest axial mode (wavenumber q = π / L)
  // the damping ratio ζ: ζ = η q / (2 √(EA μ)).
  const double viscosity =
      2.0 * material.damping_ratio * rest_length * std::sqrt(material.axial_stiffness * material.linear_density) / kPi;
  return {material.axial_stiffness / segment, viscosity / segment};
}

Status validate(const RopeDef& def, int max_particles)
{
  if (Status s = validateBodyName(def.name); !s) return s;
  if (Status s = checkIntRange("particles", def.particles, 2, max_particles); !s) return s;
  if (Status s = checkFinite("start", def.start); !s) return s;
  if (Status s = checkFinite("end", def.end); !s) return s;
  if ((def.end - def.start).norm() == 0.0 && def.rest_length == 0.0)
    return Status::failure("start = end = " + formatValue(def.start) + " and rest_length = 0: the rope has no length");
  if (Status s = checkMin("rest_length", def.rest_length, 0.0); !s) return s;
  if (def.material)
  {
    if (Status s = validateMaterial(*def.material, totalRestLength(def), def.particles); !s) return s;
  }
  else
  {
    if (Status s = checkPositive("mass", def.mass); !s) return s;
    if (Status s = checkSpringConstants("stretch.", def.stretch_stiffness, def.stretch_damping); !s) return s;
    if (Status s = checkSpringConstants("bend.", def.bend_stiffness, def.bend_damping); !s) return s;
  }
  if (Status s = checkPinIndices(def.pins, def.particles); !s) return s;
  if (Status s = checkRange("contact_thickness", def.contact_thickness, limits::kContactThickness); !s) return s;
  return validate(def.integrator);
}

SpringNetworkDef buildRope(const RopeDef& def)
{
  SpringNetworkDef net;
  net.name = def.name;
  net.shape = NetworkShape::Rope;
  net.integrator = def.integrator;
  net.contact_thickness = def.contact_thickness;
  net.tear_strain = def.tear_strain;
  net.self_collision = def.self_collision;
  const int n = def.particles;
  const double total_rest = totalRestLength(def);
  const double segment = total_rest / (n - 1);
  for (int i = 0; i < n; ++i)
    net.positions.push_back(def.start + (def.end - def.start) * (static_cast<double>(i) / (n - 1)));
  if (def.material)
  {
    // Lumped masses: each particle carries the half segments on either side of it.
    const RopeMaterial& material = *def.material;
    for (int i = 0; i < n; ++i)
      net.masses.push_back(material.linear_density * segment * (i == 0 || i == n - 1 ? 0.5 : 1.0));
    const RopeSpringConstants stretch = ropeStretchConstants(material, total_rest, segment);
    for (int i = 0; i + 1 < n; ++i)
      net.springs.push_back({i, i + 1, segment, stretch.stiffness, stretch.damping, SpringClass::Stretch});
    // Rod bending at each interior particle: k = EI / l̄ with l̄ = l (half of each neighbouring
    // segment), and the bending viscosity with the axial one's retardation time: η_b = EI · c / k.
    if (material.bending_stiffness > 0.0)
    {
      const double bend_stiffness = material.bending_stiffness / segment;
      const double bend_damping = bend_stiffness * stretch.damping / stretch.stiffness;
      for (int i = 1; i + 1 < n; ++i)
        net.rod_bending.bends.push_back({{i - 1, i, i + 1}, bend_stiffness, bend_damping});
    }
    appendPins(def.pins, n, net.pins);
    return net;
  }
  for (int i = 0; i < n; ++i)
    net.masses.push_back(def.mass / n);
  for (int i = 0; i + 1 < n; ++i)
    net.springs.push_back({i, i + 1, segment, def.stretch_stiffness, def.stretch_damping, SpringClass::Stretch});
  if (def.bend_stiffness > 0.0)
  {
    for (int i = 0; i + 2 < n; ++i)
      net.springs.push_back({i, i + 2, 2.0 * segment, def.bend_stiffness, def.bend_damping, SpringClass::Bend});
  }
  appendPins(def.pins, n, net.pins);
  return net;
}

}  // namespace core
}  // namespace particle_sim
