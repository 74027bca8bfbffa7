#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "particle_sim/core/cloth_model.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// Default constants of a spring cloth (Provot's springs) [N/m], [N·s/m]. Those of a Baraff–Witkin
/// cloth are kBaraffWitkinStretch, kBaraffWitkinShear and kBaraffWitkinBend (forces/baraff_witkin_model.h).
constexpr SpringConstants kSpringClothStretch{1000.0, 0.5};
constexpr SpringConstants kSpringClothShear{200.0, 0.2};
constexpr SpringConstants kSpringClothBend{20.0, 0.05};

/// The default constants of `spring_class` for a cloth of `model`.
SpringConstants defaultClothConstants(ClothModel model, SpringClass spring_class);

/// Contact thickness [m] that keeps a cloth's flat triangles outside every sphere of `spheres`: a
/// triangle whose edges are at most L long (L = the longest rest edge of `triangles`) and whose
/// corners lie on a sphere of radius R dips into it by at most its circumradius ρ ≤ L/√3 as
/// R − √(R² − ρ²) = ρ² / (R + √(R² − ρ²)); that depth for the smallest sphere, capped at
/// limits::kContactThickness.max. 0 without spheres (a flat ground needs none). Scene files give it
/// to cloth that does not set contact_thickness.
double clothContactThickness(const std::vector<Eigen::Vector3d>& positions,
                             const std::vector<Eigen::Vector3i>& triangles,
                             const std::vector<SphereColliderDef>& spheres);

/// A regular grid cloth after Provot (1995): particle (a, b), a in [0, nu), b in [0, nv), sits at
/// origin + a/(nu−1) edge_u + b/(nv−1) edge_v and has index b·nu + a. Stretch springs join grid
/// neighbours, shear springs the two diagonals of each cell, bend springs particles two apart
/// along u and v. Each cell is split into two surface triangles.
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
  /// A cloth of `cloth_model` with that model's default constants (defaultClothConstants()). Choose
  /// the model here: assigning `model` afterwards keeps the constants already set.
  explicit ClothGridDef(ClothModel cloth_model);

  std::string name;
  ClothModel model = ClothModel::Springs;                    ///< springs, or Baraff–Witkin with (u, v) from the grid
  Eigen::Vector3d origin = Eigen::Vector3d(-0.5, 0.0, 2.0);  ///< [m] particle (0, 0)
  Eigen::Vector3d edge_u = Eigen::Vector3d(1.0, 0.0, 0.0);   ///< [m] from (0, 0) to (nu − 1, 0)
  Eigen::Vector3d edge_v = Eigen::Vector3d(0.0, 1.0, 0.0);   ///< [m] from (0, 0) to (0, nv − 1)
  int nu = 15;                                               ///< particles along u, >= 2
  int nv = 15;                                               ///< particles along v, >= 2
  double mass = 0.5;                                         ///< [kg] total, shared equally
  SpringConstants stretch = kSpringClothStretch;
  SpringConstants shear = kSpringClothShear;
  SpringConstants bend =
      kSpringClothBend;         ///< stiffness 0 = no bend springs (Baraff–Witkin: see BaraffWitkinDef units)
  double b_u = 1.0, b_v = 1.0;  ///< Baraff–Witkin rest stretch along u and v, > 0
  std::vector<int> pins;        ///< indices; negative counts from the end
  std::vector<std::string>
      named_pins;  ///< corner_00, corner_10, corner_01, corner_11, edge_u0, edge_u1, edge_v0, edge_v1
  StrainLimitDef strain_limit;
  BodyIntegratorDef integrator;    ///< what the body sets; the rest is the world's default
  double contact_thickness = 0.0;  ///< [m] in limits::kContactThickness: kept from ground and spheres (0 = touch)
};

Status validate(const ClothGridDef& def, int max_particles);
/// The spring network of a grid cloth (shape Cloth). `def` must have passed validate().
SpringNetworkDef buildClothGrid(const ClothGridDef& def);
/// The particle indices a named pin of a nu x nv grid covers; false when the name is unknown.
bool namedGridPins(const std::string& name, int nu, int nv, std::vector<int>& indices);
/// "corner_00, corner_10, corner_01, corner_11, edge_u0, edge_u1, edge_v0, edge_v1"
const char* namedGridPinNames();

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
  BodyIntegratorDef integrator;    ///< what the body sets; the rest is the world's default
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
