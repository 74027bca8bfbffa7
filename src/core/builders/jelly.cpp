#include "particle_sim/core/builders/jelly.h"

#include "particle_sim/core/builders/pins.h"
#include "particle_sim/core/names.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
Status validate(const JellyDef& def, int max_particles)
{
  if (Status s = validateBodyName(def.name); !s) return s;
  if (Status s = checkFinite("origin", def.origin); !s) return s;
  for (int axis = 0; axis < 3; ++axis)
  {
    if (Status s = checkPositive("size[" + std::to_string(axis) + "]", def.size[axis]); !s) return s;
  }
  const int counts[3] = {def.nx, def.ny, def.nz};
  for (int axis = 0; axis < 3; ++axis)
  {
    if (Status s = checkIntRange("resolution[" + std::to_string(axis) + "]", counts[axis], 2, max_particles); !s)
      return s;
  }
  const long long n = static_cast<long long>(def.nx) * def.ny * def.nz;
  if (n > max_particles)
    return Status::failure("resolution = [" + std::to_string(def.nx) + ", " + std::to_string(def.ny) + ", " +
                           std::to_string(def.nz) + "] makes " + std::to_string(n) + " particles, over the cap of " +
                           std::to_string(max_particles));
  if (Status s = checkPositive("mass", def.mass); !s) return s;
  if (Status s = checkSpringConstants("stretch.", def.stretch.stiffness, def.stretch.damping); !s) return s;
  if (Status s = checkSpringConstants("shear.", def.shear.stiffness, def.shear.damping); !s) return s;
  if (Status s = checkSpringConstants("bend.", def.bend.stiffness, def.bend.damping); !s) return s;
  if (Status s = checkFinite("velocity", def.velocity); !s) return s;
  if (Status s = checkPinIndices(def.pins, static_cast<int>(n)); !s) return s;
  if (Status s = validate(def.strain_limit); !s) return s;
  if (Status s = checkRange("contact_thickness", def.contact_thickness, limits::kContactThickness); !s) return s;
  return validate(def.integrator);
}

SpringNetworkDef buildJelly(const JellyDef& def)
{
  SpringNetworkDef net;
  net.name = def.name;
  net.shape = NetworkShape::Jelly;
  net.integrator = def.integrator;
  net.contact_thickness = def.contact_thickness;
  net.tear_strain = def.tear_strain;
  net.self_collision = def.self_collision;
  net.strain_limit = def.strain_limit;
  const int nx = def.nx, ny = def.ny, nz = def.nz, n = nx * ny * nz;
  auto index = [=](int a, int b, int c) { return (c * ny + b) * nx + a; };
  auto inside = [=](int a, int b, int c) { return a >= 0 && a < nx && b >= 0 && b < ny && c >= 0 && c < nz; };

  // Lattice particles, equal masses, one initial velocity.
  const Eigen::Vector3d spacing(def.size.x() / (nx - 1), def.size.y() / (ny - 1), def.size.z() / (nz - 1));
  for (int c = 0; c < nz; ++c)
    for (int b = 0; b < ny; ++b)
      for (int a = 0; a < nx; ++a)
        net.positions.push_back(def.origin + spacing.cwiseProduct(Eigen::Vector3d(a, b, c)));
  net.masses.assign(n, def.mass / n);
  net.velocities.assign(n, def.velocity);

  // Springs from each particle to the neighbours at these lattice offsets (each pair once):
  // axis neighbours (stretch), face and body diagonals (shear), two apart on an axis (bend).
  struct Offset
  {
    int da, db, dc;
    SpringClass cls;
  };
  static const Offset kOffsets[] = {
      {1, 0, 0, SpringClass::Stretch}, {0, 1, 0, SpringClass::Stretch}, {0, 0, 1, SpringClass::Stretch},
      {1, 1, 0, SpringClass::Shear},   {1, -1, 0, SpringClass::Shear},  {1, 0, 1, SpringClass::Shear},
      {1, 0, -1, SpringClass::Shear},  {0, 1, 1, SpringClass::Shear},   {0, 1, -1, SpringClass::Shear},
      {1, 1, 1, SpringClass::Shear},   {1, 1, -1, SpringClass::Shear},  {1, -1, 1, SpringClass::Shear},
      {1, -1, -1, SpringClass::Shear}, {2, 0, 0, SpringClass::Bend},    {0, 2, 0, SpringClass::Bend},
      {0, 0, 2, SpringClass::Bend},
  };
  for (int c = 0; c < nz; ++c)
    for (int b = 0; b < ny; ++b)
      for (int a = 0; a < nx; ++a)
        for (const Offset& o : kOffsets)
        {
          if (!inside(a + o.da, b + o.db, c + o.dc)) continue;
          const SpringConstants& k = o.cls == SpringClass::Stretch ? def.stretch
                                     : o.cls == SpringClass::Shear ? def.shear
                                                                   : def.bend;
          if (o.cls == SpringClass::Bend && k.stiffness == 0.0) continue;
          const int i = index(a, b, c), j = index(a + o.da, b + o.db, c + o.dc);
          net.springs.push_back({i, j, (net.positions[j] - net.positions[i]).norm(), k.stiffness, k.damping, o.cls});
        }

  // The surface: each boundary face as a grid of quads, two triangles each, wound outwards.
  // A face is fixed by its axis and side; (p, q) walk the other two axes so that p × q points out.
  auto addFace = [&](int axis, bool high) {
    const int counts[3] = {nx, ny, nz};
    int p_axis = (axis + 1) % 3, q_axis = (axis + 2) % 3;
    if (!high) std::swap(p_axis, q_axis);  // flip the winding on the low side
    for (int p = 0; p + 1 < counts[p_axis]; ++p)
      for (int q = 0; q + 1 < counts[q_axis]; ++q)
      {
        auto at = [&](int dp, int dq) {
          int coords[3];
          coords[axis] = high ? counts[axis] - 1 : 0;
          coords[p_axis] = p + dp;
          coords[q_axis] = q + dq;
          return index(coords[0], coords[1], coords[2]);
        };
        net.triangles.emplace_back(at(0, 0), at(1, 0), at(1, 1));
        net.triangles.emplace_back(at(0, 0), at(1, 1), at(0, 1));
      }
  };
  for (int axis = 0; axis < 3; ++axis)
  {
    addFace(axis, false);
    addFace(axis, true);
  }

  appendPins(def.pins, n, net.pins);
  return net;
}

}  // namespace core
}  // namespace particle_sim
