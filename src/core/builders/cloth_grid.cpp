#include "particle_sim/core/builders/cloth_grid.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <optional>

#include "particle_sim/core/builders/pins.h"
#include "particle_sim/core/forces/rod_bending.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
ClothGridDef::ClothGridDef(ClothModel cloth_model)
    : model(cloth_model),
      stretch(ClothConstants::unset(cloth_model, SpringClass::Stretch)),
      shear(ClothConstants::unset(cloth_model, SpringClass::Shear)),
      bend(ClothConstants::unset(cloth_model, SpringClass::Bend))
{}

SpringConstants ClothGridDef::constants(SpringClass spring_class) const
{
  return resolveClothConstants(model, spring_class, stretch, shear, bend);
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

namespace
{
// Spring constants of a grid cloth of `material` (issue 17), from membrane equivalence. A cell of
// h_u × h_v has a u spring (length h_u), a v spring (length h_v) and two diagonals (length
// L_d = √(h_u² + h_v²)). Under a uniform small strain ε a spring of direction d and length L stores
// k L² (dᵀ ε d)²/2; summed over a cell and divided by its area h_u h_v, the energy density is
//   W = ½ C₁₁ ε_uu² + ½ C₂₂ ε_vv² + C₁₂ ε_uu ε_vv + ½ C₆₆ γ²,   γ = 2 ε_uv,
//   C₁₁ = k_u h_u/h_v + k_d 2 h_u³/(h_v L_d²),  C₂₂ = k_v h_v/h_u + k_d 2 h_v³/(h_u L_d²),
//   C₁₂ = C₆₆ = k_d 2 h_u h_v / L_d².
// Shear: C₆₆ = G·t gives k_d = G·t L_d² / (2 h_u h_v) (= G·t on square cells), and then C₁₂ = G·t.
// Tension: a strip pulled along u contracts freely across, so its stiffness is C₁₁ − C₁₂²/C₂₂; with
// C₁₁ = C₂₂ = C this is E·t when C = (E·t + √((E·t)² + 4 (G·t)²)) / 2, whence
//   k_u = (C − G·t h_u²/h_v²) h_v/h_u,   k_v = (C − G·t h_v²/h_u²) h_u/h_v
// (= C − G·t on square cells). The cloth's (u, v) cells must be rectangular for this to be exact; the
// grid's cells are h_u × h_v with h = |edge|/(n − 1). An axis spring inside the cloth is shared by the
// two cells on its sides (one per cell, as counted above); one on the border belongs to one cell and
// gets half the constants, so that a uniform strain of the whole cloth stores exactly W × area (the
// patch test). Damping: β k per class (clothDampingTimes()).
struct GridMaterialSprings
{
  SpringConstants u, v, diagonal;
};

GridMaterialSprings gridMaterialSprings(const ClothGridDef& def, const ClothMaterial& material)
{
  const double hu = def.edge_u.norm() / (def.nu - 1), hv = def.edge_v.norm() / (def.nv - 1);
  const double et = material.tensile_stiffness, gt = material.shear_stiffness;
  const double c = 0.5 * (et + std::sqrt(et * et + 4.0 * gt * gt));
  const ClothDampingTimes beta = clothDampingTimes(material, def.edge_u.cross(def.edge_v).norm());
  GridMaterialSprings springs;
  springs.u.stiffness = (c - gt * hu * hu / (hv * hv)) * hv / hu;
  springs.v.stiffness = (c - gt * hv * hv / (hu * hu)) * hu / hv;
  springs.diagonal.stiffness = gt * (hu * hu + hv * hv) / (2.0 * hu * hv);
  springs.u.damping = beta.stretch * springs.u.stiffness;
  springs.v.damping = beta.stretch * springs.v.stiffness;
  springs.diagonal.damping = beta.shear * springs.diagonal.stiffness;
  return springs;
}

// The bending of a material grid cloth (cloth_common.cpp explains why not the hinges of every edge):
// a discrete rod along every grid line (forces/rod_bending.h), k = B h⊥ / h∥ (half on the border
// lines, which carry half a cell's width), for κ_uu and κ_vv; and Baraff–Witkin's dihedral hinges on
// the cells' diagonals only, each weighted α |e|²/(a₁ + a₂) = 2 h_u h_v / (h_u² + h_v²), for the
// twist: per area B/2 (κ_uu² + κ_vv² + 2 κ_uv²), the isotropic plate of Poisson ratio 0. `bend` is
// the Baraff–Witkin bend constants of the material (stiffness B, damping β B).
void addGridPlateBending(const ClothGridDef& def, const SpringConstants& bend, SpringNetworkDef& net)
{
  const int nu = def.nu, nv = def.nv;
  auto index = [nu](int a, int b) { return b * nu + a; };
  const double hu = def.edge_u.norm() / (nu - 1), hv = def.edge_v.norm() / (nv - 1);
  auto rod = [&bend](int i, int j, int k, double stiffness) {
    return RodBend{{i, j, k}, stiffness, bend.damping / bend.stiffness * stiffness};
  };
  for (int b = 0; b < nv && bend.stiffness > 0.0; ++b)
  {
    const double width = (b == 0 || b == nv - 1) ? 0.5 * hv : hv;
    for (int a = 1; a + 1 < nu; ++a)
      net.rod_bending.bends.push_back(rod(index(a - 1, b), index(a, b), index(a + 1, b), bend.stiffness * width / hu));
  }
  for (int a = 0; a < nu && bend.stiffness > 0.0; ++a)
  {
    const double width = (a == 0 || a == nu - 1) ? 0.5 * hu : hu;
    for (int b = 1; b + 1 < nv; ++b)
      net.rod_bending.bends.push_back(rod(index(a, b - 1), index(a, b), index(a, b + 1), bend.stiffness * width / hv));
  }

  // Keep the diagonal hinges, reweighted; drop those of the grid lines (the rods bend those).
  BaraffWitkinDef& bw = net.baraff_witkin;
  const double alpha = 2.0 * hu * hu * hv * hv / ((hu * hu + hv * hv) * (hu * hu + hv * hv));
  std::size_t kept = 0;
  for (std::size_t k = 0; k < bw.bends.size(); ++k)
  {
    const int p = bw.bends[k].v[1], q = bw.bends[k].v[2];  // the hinge's edge
    if (p % nu == q % nu || p / nu == q / nu) continue;
    bw.bends[kept] = bw.bends[k];
    bw.bend_weights[kept++] = alpha * bw.bend_weights[k];
  }
  bw.bends.resize(kept);
  bw.bend_weights.resize(kept);
}

// `c` halved for a spring on the border (issue 17's material springs), else `c`.
SpringConstants borderHalf(const SpringConstants& c, bool on_border)
{
  return on_border ? SpringConstants{0.5 * c.stiffness, 0.5 * c.damping} : c;
}
}  // namespace

Status validate(const ClothGridDef& def, int max_particles)
{
  if (Status s = validateClothCommon(def); !s) return s;
  const SpringConstants shear = def.constants(SpringClass::Shear);
  if (Status s = checkSpringConstants("shear.", shear.stiffness, shear.damping); !s) return s;
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
  if (Status s = validateBaraffWitkinRest(def.b_u, def.b_v); !s) return s;
  if (def.material && def.model == ClothModel::Springs)
  {
    // Very elongated cells leave the axis springs nothing to carry once the diagonals give the shear.
    const GridMaterialSprings springs = gridMaterialSprings(def, *def.material);
    if (!(springs.u.stiffness > 0.0 && springs.v.stiffness > 0.0))
      return Status::failure("material.shear_stiffness = " + formatValue(def.material->shear_stiffness) +
                             " N/m is too large for cells of aspect ratio " +
                             formatValue((def.edge_u.norm() / (def.nu - 1)) / (def.edge_v.norm() / (def.nv - 1))) +
                             " with the spring model: use model baraff_witkin or cells closer to square");
  }
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
  const SpringConstants stretch = def.constants(SpringClass::Stretch), shear = def.constants(SpringClass::Shear),
                        bend = def.constants(SpringClass::Bend);
  SpringNetworkDef net = emptyCloth(def.name, def.integrator, def.strain_limit, def.contact_thickness);
  net.tear_strain = def.tear_strain;
  net.self_collision = def.self_collision;
  const int nu = def.nu, nv = def.nv, n = nu * nv;
  auto index = [nu](int a, int b) { return b * nu + a; };

  // Particles on the grid, equal masses (a material's lumped masses once the triangles are built).
  for (int b = 0; b < nv; ++b)
    for (int a = 0; a < nu; ++a)
      net.positions.push_back(def.origin + def.edge_u * (static_cast<double>(a) / (nu - 1)) +
                              def.edge_v * (static_cast<double>(b) / (nv - 1)));
  net.masses.assign(n, def.mass / n);
  std::optional<GridMaterialSprings> material_springs;
  if (def.material && def.model == ClothModel::Springs) material_springs = gridMaterialSprings(def, *def.material);

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
      const SpringConstants& along_u = material_springs ? material_springs->u : stretch;
      const SpringConstants& along_v = material_springs ? material_springs->v : stretch;
      const SpringConstants& diagonal = material_springs ? material_springs->diagonal : shear;
      if (a + 1 < nu)
        net.springs.push_back(clothSpring(x, index(a, b), index(a + 1, b),
                                          borderHalf(along_u, material_springs && (b == 0 || b == nv - 1)),
                                          SpringClass::Stretch));
      if (b + 1 < nv)
        net.springs.push_back(clothSpring(x, index(a, b), index(a, b + 1),
                                          borderHalf(along_v, material_springs && (a == 0 || a == nu - 1)),
                                          SpringClass::Stretch));
      if (a + 1 < nu && b + 1 < nv)
      {
        net.springs.push_back(clothSpring(x, index(a, b), index(a + 1, b + 1), diagonal, SpringClass::Shear));
        net.springs.push_back(clothSpring(x, index(a + 1, b), index(a, b + 1), diagonal, SpringClass::Shear));
      }
      if (!material_springs && bend.stiffness > 0.0)  // a material's cloth has no bend springs (validate())
      {
        if (a + 2 < nu) net.springs.push_back(clothSpring(x, index(a, b), index(a + 2, b), bend, SpringClass::Bend));
        if (b + 2 < nv) net.springs.push_back(clothSpring(x, index(a, b), index(a, b + 2), bend, SpringClass::Bend));
      }
    }
  }

  // A material's masses: a quarter of each cell's area at each of its corners (a third of each
  // triangle would give the grid's two corners on the diagonal twice the mass of the other two).
  if (def.material)
  {
    const double quarter =
        def.material->areal_density * def.edge_u.cross(def.edge_v).norm() / (4.0 * (nu - 1) * (nv - 1));
    net.masses.assign(n, 0.0);
    for (int b = 0; b + 1 < nv; ++b)
      for (int a = 0; a + 1 < nu; ++a)
        for (int corner : {index(a, b), index(a + 1, b), index(a, b + 1), index(a + 1, b + 1)})
          net.masses[corner] += quarter;
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
    if (def.material)
    {
      const ClothClassConstants c = baraffWitkinMaterialConstants(*def.material, clothArea(x, net.triangles));
      addBaraffWitkin(uvs, c.stretch, c.shear, c.bend, def.b_u, def.b_v, net);
      addGridPlateBending(def, c.bend, net);
    }
    else
      addBaraffWitkin(uvs, stretch, shear, bend, def.b_u, def.b_v, net);
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

}  // namespace core
}  // namespace particle_sim
