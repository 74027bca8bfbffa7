#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "particle_sim/core/builders/cloth_common.h"

namespace particle_sim
{
namespace core
{
/// A regular grid cloth after Provot (1995): particle (a, b), a in [0, nu), b in [0, nv), sits at
/// origin + a/(nu−1) edge_u + b/(nv−1) edge_v and has index b·nu + a. Stretch springs join grid
/// neighbours, shear springs the two diagonals of each cell, bend springs particles two apart
/// along u and v. Each cell is split into two surface triangles along its (0,0)–(1,1) diagonal. A
/// Baraff–Witkin cloth given by its material bends by rods along its grid lines and hinges on the
/// diagonals (cloth_common.cpp), an isotropic plate.
///
///      edge_v
///        ^   corner_01 ---- edge_v1 ---- corner_11
///        |       |                           |
///        |    edge_u0                     edge_u1
///        |       |                           |
///     origin corner_00 ---- edge_v0 ---- corner_10  --> edge_u
struct ClothGridDef
{
  ClothGridDef() = default;
  /// A cloth of `cloth_model`; the same cloth as assigning `model` to a default one (the constants
  /// left unset take the model's defaults when the cloth is built, see ClothConstant).
  explicit ClothGridDef(ClothModel cloth_model);

  std::string name;
  ClothModel model = ClothModel::Springs;                    ///< springs, or Baraff–Witkin with (u, v) from the grid
  Eigen::Vector3d origin = Eigen::Vector3d(-0.5, 0.0, 2.0);  ///< [m] particle (0, 0)
  Eigen::Vector3d edge_u = Eigen::Vector3d(1.0, 0.0, 0.0);   ///< [m] from (0, 0) to (nu − 1, 0)
  Eigen::Vector3d edge_v = Eigen::Vector3d(0.0, 1.0, 0.0);   ///< [m] from (0, 0) to (0, nv − 1)
  int nu = 15;                                               ///< particles along u, >= 2
  int nv = 15;                                               ///< particles along v, >= 2
  double mass = kClothMass;                                  ///< [kg] total, shared equally
  /// Unset: the model's defaults (defaultClothConstants()). Bend stiffness 0 = no bend springs.
  ClothConstants stretch = ClothConstants::unset(ClothModel::Springs, SpringClass::Stretch);
  ClothConstants shear = ClothConstants::unset(ClothModel::Springs, SpringClass::Shear);
  ClothConstants bend = ClothConstants::unset(ClothModel::Springs, SpringClass::Bend);
  double b_u = kBaraffWitkinRestStretch;  ///< Baraff–Witkin rest stretch along u, > 0
  double b_v = kBaraffWitkinRestStretch;  ///< Baraff–Witkin rest stretch along v, > 0
  std::vector<int> pins;                  ///< indices; negative counts from the end
  std::vector<std::string>
      named_pins;  ///< corner_00, corner_10, corner_01, corner_11, edge_u0, edge_u1, edge_v0, edge_v1
  StrainLimitDef strain_limit;
  BodyIntegratorDef integrator;     ///< what the body sets; the rest is the world's default
  double contact_thickness = 0.0;   ///< [m] in limits::kContactThickness: kept from ground and spheres (0 = touch)
  double tear_strain = 0.0;         ///< [-] in limits::kTearStrain: springs stretched past it break (SpringNetworkDef)
  SelfCollisionDef self_collision;  ///< with itself and others (SpringNetworkDef); off by default
  /// The cloth's material in physical units (issue 17). Set, it gives the particle masses (areal
  /// density, lumped: a quarter of each cell's rest area to each corner; `mass` is then unused) and
  /// every constant, for the mesh built (cloth_common.h); no stretch, shear or bend constant may be
  /// set beside it. Unset: `mass` and the constants, as before.
  std::optional<ClothMaterial> material;

  /// The constants of `spring_class` this cloth gets: those set, else its model's defaults.
  SpringConstants constants(SpringClass spring_class) const;
};

Status validate(const ClothGridDef& def, int max_particles);
/// The spring network of a grid cloth (shape Cloth). `def` must have passed validate().
SpringNetworkDef buildClothGrid(const ClothGridDef& def);
/// The particle indices a named pin of a nu x nv grid covers; false when the name is unknown.
bool namedGridPins(const std::string& name, int nu, int nv, std::vector<int>& indices);
/// "corner_00, corner_10, corner_01, corner_11, edge_u0, edge_u1, edge_v0, edge_v1"
const char* namedGridPinNames();

}  // namespace core
}  // namespace particle_sim
