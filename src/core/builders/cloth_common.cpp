#include "particle_sim/core/builders/cloth_common.h"

#include <Eigen/Geometry>
#include <cmath>

#include "particle_sim/core/forces/baraff_witkin_model.h"
#include "particle_sim/core/names.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
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

ClothConstants ClothConstants::unset(ClothModel model, SpringClass spring_class)
{
  const SpringConstants shown = defaultClothConstants(model, spring_class);
  return {ClothConstant::unset(shown.stiffness), ClothConstant::unset(shown.damping)};
}

SpringConstants ClothConstants::resolve(ClothModel model, SpringClass spring_class) const
{
  const SpringConstants defaults = defaultClothConstants(model, spring_class);
  return {stiffness.orDefault(defaults.stiffness), damping.orDefault(defaults.damping)};
}

SpringConstants resolveClothConstants(ClothModel model, SpringClass spring_class, const ClothConstants& stretch,
                                      const ClothConstants& shear, const ClothConstants& bend)
{
  const ClothConstants& set = spring_class == SpringClass::Stretch ? stretch
                              : spring_class == SpringClass::Shear ? shear
                                                                   : bend;
  return set.resolve(model, spring_class);
}

Status validateClothMaterial(const std::optional<ClothMaterial>& material, ClothModel model,
                             const ClothConstants& stretch, const ClothConstants& shear, const ClothConstants& bend)
{
  if (!material) return Status::success();
  if (Status s = validate(*material); !s) return s;
  // The material gives every constant: one set beside it would be silently overridden.
  const std::pair<const char*, const ClothConstants*> classes[] = {
      {"stretch", &stretch}, {"shear", &shear}, {"bend", &bend}};
  for (const auto& [class_name, constants] : classes)
  {
    for (const auto& [field, constant] :
         {std::pair<const char*, const ClothConstant*>{"stiffness", &constants->stiffness},
          std::pair<const char*, const ClothConstant*>{"damping", &constants->damping}})
    {
      if (constant->isSet())
        return Status::failure(std::string("material and ") + class_name + "." + field +
                               " are both set: a material gives the cloth its constants; set one or the other");
    }
  }
  // Distance springs two apart have no stiffness to first order about the flat state (bending by θ
  // lengthens them by O(θ²)), so no spring constant gives a bending rigidity that holds at every
  // resolution and curvature: refused rather than approximated.
  if (model == ClothModel::Springs && material->bending_rigidity > 0.0)
    return Status::failure("material.bending_rigidity = " + formatValue(material->bending_rigidity) +
                           " N·m needs model baraff_witkin: the spring model's bend springs cannot carry a bending "
                           "rigidity (use model: baraff_witkin, recommended, or bending_rigidity: 0)");
  return Status::success();
}

// Damping from the ratio ζ. Each class gets stiffness-proportional (Rayleigh) damping, k_d = β k:
// a mode of angular frequency ω dominated by that class is then damped at ζ = β ω / 2. The mode ζ
// refers to is a property of the material and the cloth's size, never of the mesh: the fundamental of
// a strip of length L = √(rest area) fixed at one end,
//   stretch  ω = (π / 2L) √(E·t / ρ_A)          (axial, quarter wave)
//   shear    ω = (π / 2L) √(G·t / ρ_A)          (in-plane shear, quarter wave)
//   bend     ω = (1.8751 / L)² √(B / ρ_A)       (cantilever, Euler–Bernoulli plate strip)
// so β = 2ζ/ω is the same at every resolution (finer modes of the same cloth are damped more, as
// stiffness-proportional damping does).
ClothDampingTimes clothDampingTimes(const ClothMaterial& m, double area)
{
  const double length = std::sqrt(area), zeta = m.damping_ratio, rho = m.areal_density;
  const double quarter_wave = M_PI / (2.0 * length), cantilever = std::pow(1.8751 / length, 2);
  ClothDampingTimes times;
  times.stretch = 2.0 * zeta / (quarter_wave * std::sqrt(m.tensile_stiffness / rho));
  times.shear = 2.0 * zeta / (quarter_wave * std::sqrt(m.shear_stiffness / rho));
  if (m.bending_rigidity > 0.0) times.bend = 2.0 * zeta / (cantilever * std::sqrt(m.bending_rigidity / rho));
  return times;
}

double clothArea(const std::vector<Eigen::Vector3d>& x, const std::vector<Eigen::Vector3i>& triangles)
{
  double area = 0.0;
  for (const Eigen::Vector3i& t : triangles)
    area += 0.5 * (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]).norm();
  return area;
}

std::vector<double> lumpedClothMasses(const std::vector<Eigen::Vector3d>& x,
                                      const std::vector<Eigen::Vector3i>& triangles, double areal_density)
{
  std::vector<double> masses(x.size(), 0.0);
  for (const Eigen::Vector3i& t : triangles)
  {
    const double third = areal_density * 0.5 * (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]).norm() / 3.0;
    for (int c = 0; c < 3; ++c)
      masses[t[c]] += third;
  }
  return masses;
}

// Baraff–Witkin constants from membrane and plate theory. The energies are per unit rest area
// (forces/baraff_witkin_model.h): a triangle of rest area a stores
//   stretch  k_s a (ε_u² + ε_v²) / 2,   ε_d = |w_d| − 1 (the strain along u or v),
//   shear    k_h a (w_u·w_v)² / 2,      w_u·w_v = γ (the engineering shear strain, for small strains),
// and the stretch conditions along u and v are independent (no Poisson coupling). So:
// - a strip of width w stretched uniaxially by ε stores k_s ε²/2 per area: its tension is k_s ε per
//   width, the force E·t·w·ε of membrane theory when k_s = E·t [N/m];
// - simple shear γ stores k_h γ²/2 per area: the shear flow is k_h γ per width, G·t·γ when
//   k_h = G·t [N/m];
// - bending: a bend element of rest edge e between triangles of areas a₁, a₂ stores
//   k_b |e|²/(a₁ + a₂) θ²/2. On a grid of cells h_u × h_v bent into a cylinder of curvature κ about an
//   axis along v, the two triangles of a cell stay coplanar (their P1 slopes along u are equal), the
//   diagonals and u-edges keep θ = 0, and each v-edge (length h_v, a₁ + a₂ = h_u h_v) turns by
//   θ = κ h_u: per cell (area h_u h_v) the energy is k_b h_v²/(h_u h_v) (κ h_u)²/2 = k_b κ² h_u h_v / 2,
//   i.e. k_b κ²/2 per area, the plate's B κ²/2 when k_b = B: the factor is exactly 1, at any h.
//   Other curvatures show what hinges on a regular grid cannot do. With every cell split along the
//   (0,0)–(1,1) diagonal, a uniform curvature (κ_uu, κ_vv, κ_uv) stores, per area and for square
//   cells, k_b/2 [(κ_uu + κ_uv)² + (κ_vv + κ_uv)² + 4 κ_uv²]: bending couples to twist. Alternating
//   the diagonals (union jack) cancels that coupling for uniform curvatures, but not for a twist
//   whose sign alternates from cell to cell, which the hinges of the grid lines see as bending and
//   price only by the diagonals: a clamped strip then bends as if its rigidity were 2/3 B (4/5 B with
//   one-way diagonals, where a uniform twist does it), at any resolution. So a material grid cloth (cloth_grid.cpp)
//   bends differently: a discrete rod along every grid line (forces/rod_bending.h, k = B h⊥ / h∥) carries κ_uu and
//   κ_vv, and only the diagonal hinges remain, weighted α = 2 h_u² h_v² / (h_u² + h_v²)² of the discrete-shells weight,
//   for the twist. Any uniform curvature then stores B/2 (κ_uu² + κ_vv² + 2 κ_uv²) = B/2 (κ₁² + κ₂²)
//   per area, the isotropic plate of Poisson ratio 0, at any resolution and cell aspect ratio; a
//   rod sees every zig-zag of its line, so no mode bends for less; and a clamped strip is the
//   discrete elastica (tested in cloth_material_test.cpp and validation_cloth_test.cpp). A mesh
//   cloth, whose triangles follow no grid, has no hinges: it bends with the isotropic plate of its
//   flat pattern (forces/plate_bending.h, mesh_cloth.cpp), B/2 ∫ (κ₁ + κ₂)² dA.
ClothClassConstants baraffWitkinMaterialConstants(const ClothMaterial& material, double area)
{
  const ClothDampingTimes beta = clothDampingTimes(material, area);
  ClothClassConstants c;
  c.stretch = {material.tensile_stiffness, beta.stretch * material.tensile_stiffness};
  c.shear = {material.shear_stiffness, beta.shear * material.shear_stiffness};
  c.bend = {material.bending_rigidity, beta.bend * material.bending_rigidity};
  return c;
}

Status validateClothCommon(const std::string& name, const SpringConstants& stretch, const SpringConstants& bend,
                           double mass, const StrainLimitDef& strain_limit, const BodyIntegratorDef& integrator,
                           double contact_thickness)
{
  if (Status s = checkRange("contact_thickness", contact_thickness, limits::kContactThickness); !s) return s;
  if (Status s = validateBodyName(name); !s) return s;
  if (Status s = checkPositive("mass", mass); !s) return s;
  if (Status s = checkSpringConstants("stretch.", stretch.stiffness, stretch.damping); !s) return s;
  if (Status s = checkSpringConstants("bend.", bend.stiffness, bend.damping); !s) return s;
  if (Status s = validate(strain_limit); !s) return s;
  return validate(integrator);
}

Status validateBaraffWitkinRest(double b_u, double b_v)
{
  if (Status s = checkPositive("b_u", b_u); !s) return s;
  return checkPositive("b_v", b_v);
}

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

Spring clothSpring(const std::vector<Eigen::Vector3d>& x, int i, int j, const SpringConstants& c, SpringClass cls)
{
  return {i, j, (x[j] - x[i]).norm(), c.stiffness, c.damping, cls};
}

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

}  // namespace core
}  // namespace particle_sim
