#include "particle_sim/core/cloth.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <utility>

#include "particle_sim/core/builders/mesh_topology.h"
#include "particle_sim/core/builders/pins.h"
#include "particle_sim/core/names.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
namespace
{
Spring makeSpring(const std::vector<Eigen::Vector3d>& x, int i, int j, const SpringConstants& c, SpringClass cls)
{
  return {i, j, (x[j] - x[i]).norm(), c.stiffness, c.damping, cls};
}

Status checkCommon(const std::string& name, const SpringConstants& stretch, const SpringConstants& bend, double mass,
                   const StrainLimitDef& strain_limit, const BodyIntegratorDef& integrator, double contact_thickness)
{
  if (Status s = checkRange("contact_thickness", contact_thickness, limits::kContactThickness); !s) return s;
  if (Status s = validateBodyName(name); !s) return s;
  if (Status s = checkPositive("mass", mass); !s) return s;
  if (Status s = checkSpringConstants("stretch.", stretch.stiffness, stretch.damping); !s) return s;
  if (Status s = checkSpringConstants("bend.", bend.stiffness, bend.damping); !s) return s;
  if (Status s = validate(strain_limit); !s) return s;
  return validate(integrator);
}
}  // namespace

const char* toString(ClothModel model)
{
  return model == ClothModel::Springs ? "springs" : "baraff_witkin";
}

bool parseClothModel(const std::string& text, ClothModel& model)
{
  if (text == "springs")
    model = ClothModel::Springs;
  else if (text == "baraff_witkin")
    model = ClothModel::BaraffWitkin;
  else
    return false;
  return true;
}

namespace
{
// The Baraff–Witkin energies of a cloth whose triangles have rest coordinates `uvs` [m].
void addBaraffWitkin(const std::vector<Eigen::Vector2d>& uvs, const SpringConstants& stretch,
                     const SpringConstants& shear, const SpringConstants& bend, double b_u, double b_v,
                     SpringNetworkDef& net)
{
  BaraffWitkinDef& bw = net.baraff_witkin;
  std::string error;
  buildBaraffWitkin(net.positions, uvs, net.triangles, bw, error);  // validated before
  bw.stretch = stretch;
  bw.shear = shear;
  bw.bend = bend;
  bw.b_u = b_u;
  bw.b_v = b_v;
}

// A cloth network with nothing in it yet.
SpringNetworkDef emptyCloth(const std::string& name, const BodyIntegratorDef& integrator, const StrainLimitDef& limit,
                            double contact_thickness)
{
  SpringNetworkDef net;
  net.contact_thickness = contact_thickness;
  net.name = name;
  net.shape = NetworkShape::Cloth;
  net.integrator = integrator;
  net.strain_limit = limit;
  return net;
}

Status checkBaraffWitkinRest(double b_u, double b_v)
{
  if (Status s = checkPositive("b_u", b_u); !s) return s;
  return checkPositive("b_v", b_v);
}
}  // namespace

SpringConstants defaultClothConstants(ClothModel model, SpringClass spring_class)
{
  const bool bw = model == ClothModel::BaraffWitkin;
  switch (spring_class)
  {
    case SpringClass::Stretch:
      return bw ? kBaraffWitkinStretch : kSpringClothStretch;
    case SpringClass::Shear:
      return bw ? kBaraffWitkinShear : kSpringClothShear;
    case SpringClass::Bend:
      return bw ? kBaraffWitkinBend : kSpringClothBend;
  }
  return {};
}

ClothGridDef::ClothGridDef(ClothModel cloth_model)
    : model(cloth_model),
      stretch(defaultClothConstants(cloth_model, SpringClass::Stretch)),
      shear(defaultClothConstants(cloth_model, SpringClass::Shear)),
      bend(defaultClothConstants(cloth_model, SpringClass::Bend))
{}

MeshClothDef::MeshClothDef(ClothModel cloth_model)
    : model(cloth_model),
      stretch(defaultClothConstants(cloth_model, SpringClass::Stretch)),
      shear(defaultClothConstants(cloth_model, SpringClass::Shear)),
      bend(defaultClothConstants(cloth_model, SpringClass::Bend))
{}

double clothContactThickness(const std::vector<Eigen::Vector3d>& positions,
                             const std::vector<Eigen::Vector3i>& triangles,
                             const std::vector<SphereColliderDef>& spheres)
{
  if (spheres.empty()) return 0.0;
  double radius = spheres.front().radius;
  for (const SphereColliderDef& sphere : spheres)
    radius = std::min(radius, sphere.radius);
  double longest = 0.0;
  for (const Eigen::Vector3i& t : triangles)
    for (int c = 0; c < 3; ++c)
      longest = std::max(longest, (positions[t[(c + 1) % 3]] - positions[t[c]]).norm());
  // Depth of the circumcentre of a triangle of circumradius ρ ≤ L/√3 inscribed in the sphere.
  const double rho_squared = longest * longest / 3.0;
  const double depth = rho_squared / (radius + std::sqrt(std::max(0.0, radius * radius - rho_squared)));
  return std::min(depth, limits::kContactThickness.max);
}

const char* namedGridPinNames()
{
  return "corner_00, corner_10, corner_01, corner_11, edge_u0, edge_u1, edge_v0, edge_v1";
}

bool namedGridPins(const std::string& name, int nu, int nv, std::vector<int>& indices)
{
  auto index = [nu](int a, int b) { return b * nu + a; };
  indices.clear();
  if (name == "corner_00")
    indices = {index(0, 0)};
  else if (name == "corner_10")
    indices = {index(nu - 1, 0)};
  else if (name == "corner_01")
    indices = {index(0, nv - 1)};
  else if (name == "corner_11")
    indices = {index(nu - 1, nv - 1)};
  else if (name == "edge_v0" || name == "edge_v1")  // the edges along u, at v = 0 or v = 1
    for (int a = 0; a < nu; ++a)
      indices.push_back(index(a, name == "edge_v0" ? 0 : nv - 1));
  else if (name == "edge_u0" || name == "edge_u1")  // the edges along v, at u = 0 or u = 1
    for (int b = 0; b < nv; ++b)
      indices.push_back(index(name == "edge_u0" ? 0 : nu - 1, b));
  else
    return false;
  return true;
}

Status validate(const ClothGridDef& def, int max_particles)
{
  if (Status s = checkCommon(def.name, def.stretch, def.bend, def.mass, def.strain_limit, def.integrator,
                             def.contact_thickness);
      !s)
    return s;
  if (Status s = checkSpringConstants("shear.", def.shear.stiffness, def.shear.damping); !s) return s;
  if (Status s = checkFinite("origin", def.origin); !s) return s;
  if (Status s = checkFinite("edge_u", def.edge_u); !s) return s;
  if (Status s = checkFinite("edge_v", def.edge_v); !s) return s;
  if (def.edge_u.cross(def.edge_v).norm() <= 1e-12 * def.edge_u.norm() * def.edge_v.norm() || def.edge_u.norm() == 0.0)
    return Status::failure("edge_u = " + formatValue(def.edge_u) + " and edge_v = " + formatValue(def.edge_v) +
                           " must be non-zero and not parallel");
  if (Status s = checkIntRange("resolution[0]", def.nu, 2, max_particles); !s) return s;
  if (Status s = checkIntRange("resolution[1]", def.nv, 2, max_particles); !s) return s;
  if (static_cast<long long>(def.nu) * def.nv > max_particles)
    return Status::failure("resolution = [" + std::to_string(def.nu) + ", " + std::to_string(def.nv) + "] makes " +
                           std::to_string(static_cast<long long>(def.nu) * def.nv) + " particles, over the cap of " +
                           std::to_string(max_particles));
  if (Status s = checkPinIndices(def.pins, def.nu * def.nv); !s) return s;
  if (Status s = checkBaraffWitkinRest(def.b_u, def.b_v); !s) return s;
  std::vector<int> ignored;
  for (std::size_t k = 0; k < def.named_pins.size(); ++k)
  {
    if (!namedGridPins(def.named_pins[k], def.nu, def.nv, ignored))
      return Status::failure("pins[" + std::to_string(k) + "] = '" + def.named_pins[k] +
                             "' is not a pin name; allowed: " + namedGridPinNames() + ", or an index");
  }
  return Status::success();
}

SpringNetworkDef buildClothGrid(const ClothGridDef& def)
{
  SpringNetworkDef net = emptyCloth(def.name, def.integrator, def.strain_limit, def.contact_thickness);
  const int nu = def.nu, nv = def.nv, n = nu * nv;
  auto index = [nu](int a, int b) { return b * nu + a; };

  // Particles on the grid, equal masses.
  for (int b = 0; b < nv; ++b)
    for (int a = 0; a < nu; ++a)
      net.positions.push_back(def.origin + def.edge_u * (static_cast<double>(a) / (nu - 1)) +
                              def.edge_v * (static_cast<double>(b) / (nv - 1)));
  net.masses.assign(n, def.mass / n);

  // Provot's springs: stretch to the neighbours, shear across each cell, bend two apart (none for
  // a Baraff–Witkin cloth, which gets its energies from the triangles below).
  const std::vector<Eigen::Vector3d>& x = net.positions;
  const bool springs = def.model == ClothModel::Springs;
  for (int b = 0; b < nv; ++b)
  {
    for (int a = 0; a < nu; ++a)
    {
      if (a + 1 < nu && b + 1 < nv)
      {
        // Two triangles per cell, both wound like (edge_u, edge_v).
        net.triangles.emplace_back(index(a, b), index(a + 1, b), index(a + 1, b + 1));
        net.triangles.emplace_back(index(a, b), index(a + 1, b + 1), index(a, b + 1));
      }
      if (!springs) continue;
      if (a + 1 < nu)
        net.springs.push_back(makeSpring(x, index(a, b), index(a + 1, b), def.stretch, SpringClass::Stretch));
      if (b + 1 < nv)
        net.springs.push_back(makeSpring(x, index(a, b), index(a, b + 1), def.stretch, SpringClass::Stretch));
      if (a + 1 < nu && b + 1 < nv)
      {
        net.springs.push_back(makeSpring(x, index(a, b), index(a + 1, b + 1), def.shear, SpringClass::Shear));
        net.springs.push_back(makeSpring(x, index(a + 1, b), index(a, b + 1), def.shear, SpringClass::Shear));
      }
      if (def.bend.stiffness > 0.0)
      {
        if (a + 2 < nu) net.springs.push_back(makeSpring(x, index(a, b), index(a + 2, b), def.bend, SpringClass::Bend));
        if (b + 2 < nv) net.springs.push_back(makeSpring(x, index(a, b), index(a, b + 2), def.bend, SpringClass::Bend));
      }
    }
  }

  // Baraff–Witkin: (u, v) of each particle are its rest coordinates in the cloth's plane, u along
  // edge_u and v perpendicular to it, so the cloth starts at rest.
  if (!springs)
  {
    const Eigen::Vector3d e1 = def.edge_u.normalized();
    const Eigen::Vector3d e2 = (def.edge_v - def.edge_v.dot(e1) * e1).normalized();
    std::vector<Eigen::Vector2d> uvs;
    for (const Eigen::Vector3d& p : net.positions)
      uvs.emplace_back((p - def.origin).dot(e1), (p - def.origin).dot(e2));
    addBaraffWitkin(uvs, def.stretch, def.shear, def.bend, def.b_u, def.b_v, net);
  }

  // Pins by index and by name, each particle once.
  appendPins(def.pins, n, net.pins);
  for (const std::string& name : def.named_pins)
  {
    std::vector<int> indices;
    namedGridPins(name, nu, nv, indices);
    net.pins.insert(net.pins.end(), indices.begin(), indices.end());
  }
  std::sort(net.pins.begin(), net.pins.end());
  net.pins.erase(std::unique(net.pins.begin(), net.pins.end()), net.pins.end());
  return net;
}

Status validate(const MeshClothDef& def, int max_particles)
{
  if (Status s = checkCommon(def.name, def.stretch, def.bend, def.mass, def.strain_limit, def.integrator,
                             def.contact_thickness);
      !s)
    return s;
  const int n = static_cast<int>(def.vertices.size());
  if (Status s = checkIntRange("vertices (count)", n, 3, max_particles); !s) return s;
  if (def.triangles.empty()) return Status::failure("triangles is empty: a mesh cloth needs at least one triangle");
  for (int i = 0; i < n; ++i)
  {
    if (Status s = checkFinite("vertices[" + std::to_string(i) + "]", def.vertices[i]); !s) return s;
  }
  for (std::size_t k = 0; k < def.triangles.size(); ++k)
  {
    const Eigen::Vector3i& t = def.triangles[k];
    for (int c = 0; c < 3; ++c)
    {
      if (t[c] < 0 || t[c] >= n)
        return Status::failure("triangles[" + std::to_string(k) + "] uses vertex " + std::to_string(t[c]) +
                               ", out of range: the mesh has " + std::to_string(n) + " vertices");
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      return Status::failure("triangles[" + std::to_string(k) + "] repeats a vertex");
    // A triangle of zero area has no normal (drawn and lit as garbage, no air force).
    const Eigen::Vector3d e1 = def.vertices[t[1]] - def.vertices[t[0]], e2 = def.vertices[t[2]] - def.vertices[t[0]];
    if (e1.cross(e2).norm() <= 1e-12 * e1.norm() * e2.norm())
      return Status::failure("triangles[" + std::to_string(k) + "] = [" + std::to_string(t[0]) + ", " +
                             std::to_string(t[1]) + ", " + std::to_string(t[2]) +
                             "] has zero area (its corners are on one line): it has no normal");
  }
  if (Status s = checkPinIndices(def.pins, n); !s) return s;
  if (def.model == ClothModel::BaraffWitkin)
  {
    if (Status s = checkSpringConstants("shear.", def.shear.stiffness, def.shear.damping); !s) return s;
    if (Status s = checkBaraffWitkinRest(def.b_u, def.b_v); !s) return s;
    if (def.uvs.size() != def.vertices.size())
      return Status::failure("model = baraff_witkin needs texture coordinates (vt) for every vertex; the mesh has " +
                             std::to_string(def.uvs.size()) + " for " + std::to_string(n) + " vertices");
    BaraffWitkinDef probe;
    std::string error;
    if (!buildBaraffWitkin(def.vertices, def.uvs, def.triangles, probe, error)) return Status::failure(error);
  }
  return Status::success();
}

SpringNetworkDef buildMeshCloth(const MeshClothDef& def)
{
  SpringNetworkDef net = emptyCloth(def.name, def.integrator, def.strain_limit, def.contact_thickness);
  net.positions = def.vertices;
  net.triangles = def.triangles;
  const int n = static_cast<int>(def.vertices.size());
  net.masses.assign(n, def.mass / n);

  if (def.model == ClothModel::BaraffWitkin)
  {
    // Texture coordinates scaled so that the (u, v) area equals the mesh's area.
    double mesh_area = 0.0, uv_area = 0.0;
    for (const Eigen::Vector3i& t : def.triangles)
    {
      mesh_area +=
          0.5 * (def.vertices[t[1]] - def.vertices[t[0]]).cross(def.vertices[t[2]] - def.vertices[t[0]]).norm();
      const Eigen::Vector2d a = def.uvs[t[1]] - def.uvs[t[0]], b = def.uvs[t[2]] - def.uvs[t[0]];
      uv_area += 0.5 * std::abs(a.x() * b.y() - a.y() * b.x());
    }
    const double scale = std::sqrt(mesh_area / uv_area);
    std::vector<Eigen::Vector2d> uvs;
    for (const Eigen::Vector2d& uv : def.uvs)
      uvs.push_back(scale * uv);
    addBaraffWitkin(uvs, def.stretch, def.shear, def.bend, def.b_u, def.b_v, net);
    appendPins(def.pins, n, net.pins);
    return net;
  }
  // Each edge once (keyed by its sorted ends): a stretch spring, and across an interior edge
  // (two triangles) a bend spring between the vertices opposite it.
  for (const auto& [edge, sides] : meshEdges(def.triangles))
  {
    net.springs.push_back(makeSpring(net.positions, edge.first, edge.second, def.stretch, SpringClass::Stretch));
    if (def.bend.stiffness > 0.0 && sides.size() == 2 && sides[0].opposite != sides[1].opposite)
      net.springs.push_back(
          makeSpring(net.positions, sides[0].opposite, sides[1].opposite, def.bend, SpringClass::Bend));
  }
  appendPins(def.pins, n, net.pins);
  return net;
}

void vertexNormals(const Eigen::Matrix3Xd& positions, int count, const std::vector<Eigen::Vector3i>& triangles,
                   std::vector<Eigen::Vector3d>& normals)
{
  normals.assign(count, Eigen::Vector3d::Zero());
  // The cross product of two edges is the normal times twice the area: summing it weights by area.
  for (const Eigen::Vector3i& t : triangles)
  {
    const Eigen::Vector3d e1 = positions.col(t[1]) - positions.col(t[0]);
    const Eigen::Vector3d e2 = positions.col(t[2]) - positions.col(t[0]);
    const Eigen::Vector3d area_normal = e1.cross(e2);
    for (int c = 0; c < 3; ++c)
      normals[t[c]] += area_normal;
  }
  for (Eigen::Vector3d& normal : normals)
  {
    const double length = normal.norm();
    if (length > 0.0) normal /= length;
  }
}

void vertexStrains(const SpringNetworkBody& body, std::vector<double>& strains)
{
  const ParticlePool& p = body.particles();
  strains.assign(p.size(), 0.0);
  if (body.baraffWitkin()) body.baraffWitkin()->vertexStrains(p.position, strains);
  for (const Spring& s : body.springs())
  {
    if (s.spring_class == SpringClass::Bend || s.rest_length == 0.0) continue;
    const double strain = ((p.position.col(s.j) - p.position.col(s.i)).norm() - s.rest_length) / s.rest_length;
    strains[s.i] = std::max(strains[s.i], strain);
    strains[s.j] = std::max(strains[s.j], strain);
  }
}

}  // namespace core
}  // namespace particle_sim
