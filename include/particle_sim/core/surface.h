#pragma once
// Measurements on the surface triangles of cloth and jelly, for scene defaults and for drawing:
// not builders (those are in builders/), not physics.

#include <Eigen/Core>
#include <vector>

#include "particle_sim/core/environment.h"
#include "particle_sim/core/spring_network.h"

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

/// Area-weighted unit vertex normals of a triangle surface (zero for a vertex in no triangle).
void vertexNormals(const Eigen::Matrix3Xd& positions, int count, const std::vector<Eigen::Vector3i>& triangles,
                   std::vector<Eigen::Vector3d>& normals);

/// Per particle, the largest strain (l − L) / L of the stretch and shear springs it belongs to
/// and, for Baraff–Witkin cloth, of its triangles (max(|w_u|/b_u, |w_v|/b_v) − 1).
void vertexStrains(const SpringNetworkBody& body, std::vector<double>& strains);

}  // namespace core
}  // namespace particle_sim
