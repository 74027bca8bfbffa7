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
/// A cloth from a triangle mesh. Springs: every mesh edge is a stretch spring at its initial
/// length, and across every interior edge the two opposite vertices are joined by a bend spring.
/// Baraff–Witkin: the rest (u, v) of each vertex comes from `uvs` (texture coordinates), scaled so
/// that the (u, v) area equals the mesh's area.
struct MeshClothDef
{
  MeshClothDef() = default;
  /// A cloth of `cloth_model`; the same cloth as assigning `model` to a default one (the constants
  /// left unset take the model's defaults when the cloth is built, see ClothConstant).
  explicit MeshClothDef(ClothModel cloth_model);

  std::string name;
  ClothModel model = ClothModel::Springs;
  std::vector<Eigen::Vector3d> vertices;   ///< [m]
  std::vector<Eigen::Vector3i> triangles;  ///< vertex indices
  std::vector<Eigen::Vector2d> uvs;        ///< per vertex texture coordinates; needed by Baraff–Witkin
  double mass = kClothMass;                ///< [kg] total, shared equally by the vertices
  /// Unset: the model's defaults (defaultClothConstants()). Shear: Baraff–Witkin only. Bend
  /// stiffness 0 = no bend springs.
  ClothConstants stretch = ClothConstants::unset(ClothModel::Springs, SpringClass::Stretch);
  ClothConstants shear = ClothConstants::unset(ClothModel::Springs, SpringClass::Shear);
  ClothConstants bend = ClothConstants::unset(ClothModel::Springs, SpringClass::Bend);
  double b_u = kBaraffWitkinRestStretch;  ///< Baraff–Witkin rest stretch along u
  double b_v = kBaraffWitkinRestStretch;  ///< Baraff–Witkin rest stretch along v
  std::vector<int> pins;
  StrainLimitDef strain_limit;
  BodyIntegratorDef integrator;     ///< what the body sets; the rest is the world's default
  double contact_thickness = 0.0;   ///< [m] in limits::kContactThickness: kept from ground and spheres (0 = touch)
  double tear_strain = 0.0;         ///< [-] in limits::kTearStrain: springs stretched past it break (SpringNetworkDef)
  SelfCollisionDef self_collision;  ///< with itself and others (SpringNetworkDef); off by default
  /// The cloth's material in physical units (issue 17). Set, it gives the particle masses (areal
  /// density, lumped: a third of each triangle's rest area to each corner; `mass` is then unused) and
  /// every constant, for the mesh built (cloth_common.h); no stretch, shear or bend constant may be
  /// set beside it. Unset: `mass` and the constants, as before.
  std::optional<ClothMaterial> material;

  /// The constants of `spring_class` this cloth gets: those set, else its model's defaults.
  SpringConstants constants(SpringClass spring_class) const;
};

Status validate(const MeshClothDef& def, int max_particles);
/// The spring network of a mesh cloth (shape Cloth). `def` must have passed validate().
SpringNetworkDef buildMeshCloth(const MeshClothDef& def);

}  // namespace core
}  // namespace particle_sim
