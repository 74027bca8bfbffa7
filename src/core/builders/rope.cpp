#include "particle_sim/core/builders/rope.h"

#include "particle_sim/core/builders/pins.h"
#include "particle_sim/core/names.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
Status validate(const RopeDef& def, int max_particles)
{
  if (Status s = validateBodyName(def.name); !s) return s;
  if (Status s = checkIntRange("particles", def.particles, 2, max_particles); !s) return s;
  if (Status s = checkFinite("start", def.start); !s) return s;
  if (Status s = checkFinite("end", def.end); !s) return s;
  if ((def.end - def.start).norm() == 0.0 && def.rest_length == 0.0)
    return Status::failure("start = end = " + formatValue(def.start) + " and rest_length = 0: the rope has no length");
  if (Status s = checkPositive("mass", def.mass); !s) return s;
  if (Status s = checkMin("rest_length", def.rest_length, 0.0); !s) return s;
  if (Status s = checkSpringConstants("stretch.", def.stretch_stiffness, def.stretch_damping); !s) return s;
  if (Status s = checkSpringConstants("bend.", def.bend_stiffness, def.bend_damping); !s) return s;
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
  const int n = def.particles;
  const double total_rest = def.rest_length > 0.0 ? def.rest_length : (def.end - def.start).norm();
  const double segment = total_rest / (n - 1);
  for (int i = 0; i < n; ++i)
  {
    net.positions.push_back(def.start + (def.end - def.start) * (static_cast<double>(i) / (n - 1)));
    net.masses.push_back(def.mass / n);
  }
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
