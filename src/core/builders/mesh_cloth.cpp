#include "particle_sim/core/builders/mesh_cloth.h"

#include <Eigen/Geometry>
#include <cmath>

#include "particle_sim/core/builders/mesh_topology.h"
#include "particle_sim/core/builders/pins.h"
#include "particle_sim/core/forces/baraff_witkin_model.h"
#include "particle_sim/core/forces/plate_bending.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
MeshClothDef::MeshClothDef(ClothModel cloth_model)
    : model(cloth_model),
      stretch(ClothConstants::unset(cloth_model, SpringClass::Stretch)),
      shear(ClothConstants::unset(cloth_model, SpringClass::Shear)),
      bend(ClothConstants::unset(cloth_model, SpringClass::Bend))
{}

SpringConstants MeshClothDef::constants(SpringClass spring_class) const
{
  return resolveClothConstants(model, spring_class, stretch, shear, bend);
}

Status validate(const MeshClothDef& def, int max_particles)
{
  if (Status s = validateClothCommon(def); !s) return s;
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
    const SpringConstants shear = def.constants(SpringClass::Shear);
    if (Status s = checkSpringConstants("shear.", shear.stiffness, shear.damping); !s) return s;
    if (Status s = validateBaraffWitkinRest(def.b_u, def.b_v); !s) return s;
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
  const SpringConstants stretch = def.constants(SpringClass::Stretch), shear = def.constants(SpringClass::Shear),
                        bend = def.constants(SpringClass::Bend);
  SpringNetworkDef net = emptyCloth(def.name, def.integrator, def.strain_limit, def.contact_thickness);
  net.tear_strain = def.tear_strain;
  net.self_collision = def.self_collision;
  net.positions = def.vertices;
  net.triangles = def.triangles;
  const int n = static_cast<int>(def.vertices.size());
  net.masses.assign(n, def.mass / n);
  if (def.material) net.masses = lumpedClothMasses(def.vertices, def.triangles, def.material->areal_density);

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
    if (def.material)
    {
      // A material bends with the isotropic plate (forces/plate_bending.h) of the flat pattern, the
      // texture coordinates scaled: the same B in every direction, on any triangulation, where
      // Baraff–Witkin's hinges of every edge would bend less across some directions than others.
      const ClothClassConstants c = baraffWitkinMaterialConstants(*def.material, mesh_area);
      addBaraffWitkin(uvs, c.stretch, c.shear, SpringConstants{0.0, 0.0}, def.b_u, def.b_v, net);
      net.baraff_witkin.bends.clear();
      net.baraff_witkin.bend_weights.clear();
      std::string error;  // none: validate() refused triangles without area in (u, v)
      if (c.bend.stiffness > 0.0)
        buildPlateBending(uvs, def.triangles, c.bend.stiffness, c.bend.damping, net.plate_bending, error);
    }
    else
      addBaraffWitkin(uvs, stretch, shear, bend, def.b_u, def.b_v, net);
    appendPins(def.pins, n, net.pins);
    return net;
  }
  // A material's edge springs (issue 17), by a per-triangle-area rule: each triangle T adjacent to an
  // edge e gives it E·t a_T / |e|², so k_e = E·t Σ_T a_T / |e|². On equilateral triangles (side h,
  // k = (√3/2) E·t for an interior edge) the triangular spring lattice's plane modulus 2k/√3 is E·t,
  // its Poisson ratio 1/3 and its shear modulus 3/8 E·t, at any h: an edge-spring mesh cannot take
  // the material's shear stiffness apart from its tensile one (use baraff_witkin for that); other
  // triangle shapes follow the same rule approximately. Damping: β k (clothDampingTimes()).
  double spring_damping_time = 0.0;
  if (def.material)
    spring_damping_time = clothDampingTimes(*def.material, clothArea(def.vertices, def.triangles)).stretch;
  // Each edge once (keyed by its sorted ends): a stretch spring, and across an interior edge
  // (two triangles) a bend spring between the vertices opposite it.
  for (const auto& [edge, sides] : meshEdges(def.triangles))
  {
    Spring spring = clothSpring(net.positions, edge.first, edge.second, stretch, SpringClass::Stretch);
    if (def.material)
    {
      double adjacent_area = 0.0;
      for (const auto& side : sides)
      {
        const Eigen::Vector3i& t = def.triangles[side.triangle];
        adjacent_area +=
            0.5 * (def.vertices[t[1]] - def.vertices[t[0]]).cross(def.vertices[t[2]] - def.vertices[t[0]]).norm();
      }
      spring.stiffness = def.material->tensile_stiffness * adjacent_area / (spring.rest_length * spring.rest_length);
      spring.damping = spring_damping_time * spring.stiffness;
    }
    net.springs.push_back(spring);
    if (!def.material && bend.stiffness > 0.0 && sides.size() == 2 && sides[0].opposite != sides[1].opposite)
      net.springs.push_back(clothSpring(net.positions, sides[0].opposite, sides[1].opposite, bend, SpringClass::Bend));
  }
  appendPins(def.pins, n, net.pins);
  return net;
}

}  // namespace core
}  // namespace particle_sim
