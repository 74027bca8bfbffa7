#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "particle_sim/core/builders/cloth_common.h"
#include "particle_sim/core/cloth_model.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// Contact thickness [m] that keeps a cloth's flat triangles outside every sphere of `spheres`: a
/// triangle whose edges are at most L long (L = the longest rest edge of `triangles`) and whose
/// corners lie on a sphere of radius R dips into it by at most its circumradius ρ ≤ L/√3 as
/// R − √(R² − ρ²) = ρ² / (R + √(R² − ρ²)); that depth for the smallest sphere, capped at
/// limits::kContactThickness.max. 0 without spheres (a flat ground needs none). Scene files give it
/// to cloth that does not set contact_thickness.
double clothContactThickness(const std::vector<Eigen::Vector3d>& positions,
                             const std::vector<Eigen::Vector3i>& triangles,
                             const std::vector<SphereColliderDef>& spheres);

/// A cloth from a triangle mesh. Springs: every mesh edge is a stretch spring at its initial
/// length, and across every interior edge the two opposite vertices are joined by a bend spring.
/// Baraff–Witkin: the rest (u, v) of each vertex comes from `uvs` (texture coordinates), scaled so
/// that the (u, v) area equals the mesh's area.
struct MeshClothDef
{
  MeshClothDef() = default;
  /// A cloth of `cloth_model` with that model's default constants (defaultClothConstants()). Choose
  /// the model here: assigning `model` afterwards keeps the constants already set.
  explicit MeshClothDef(ClothModel cloth_model);

  std::string name;
  ClothModel model = ClothModel::Springs;
  std::vector<Eigen::Vector3d> vertices;   ///< [m]
  std::vector<Eigen::Vector3i> triangles;  ///< vertex indices
  std::vector<Eigen::Vector2d> uvs;        ///< per vertex texture coordinates; needed by Baraff–Witkin
  double mass = 0.5;                       ///< [kg] total, shared equally by the vertices
  SpringConstants stretch = kSpringClothStretch;
  SpringConstants shear = kSpringClothShear;  ///< Baraff–Witkin only
  SpringConstants bend = kSpringClothBend;    ///< stiffness 0 = no bend springs
  double b_u = 1.0, b_v = 1.0;                ///< Baraff–Witkin rest stretch
  std::vector<int> pins;
  StrainLimitDef strain_limit;
  IntegratorDef integrator;
  double contact_thickness = 0.0;  ///< [m] in limits::kContactThickness: kept from ground and spheres (0 = touch)
};

Status validate(const MeshClothDef& def, int max_particles);
/// The spring network of a mesh cloth (shape Cloth). `def` must have passed validate().
SpringNetworkDef buildMeshCloth(const MeshClothDef& def);

/// Area-weighted unit vertex normals of a triangle surface (zero for a vertex in no triangle).
void vertexNormals(const Eigen::Matrix3Xd& positions, int count, const std::vector<Eigen::Vector3i>& triangles,
                   std::vector<Eigen::Vector3d>& normals);

/// Per particle, the largest strain (l − L) / L of the stretch and shear springs it belongs to
/// and, for Baraff–Witkin cloth, of its triangles (max(|w_u|/b_u, |w_v|/b_v) − 1).
void vertexStrains(const SpringNetworkBody& body, std::vector<double>& strains);

}  // namespace core
}  // namespace particle_sim
