#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "particle_sim/core/spring_network.h"

namespace particle_sim
{
namespace core
{
/// A jelly block: an nx x ny x nz lattice filling the box from `origin` to origin + size, with
/// structural (stretch) springs between lattice neighbours, shear springs across every face
/// diagonal and body diagonal of each cell, and bend springs between particles two apart along
/// each axis. Its six boundary faces, split into triangles facing outwards, are its surface.
/// Particle (a, b, c) has index (c · ny + b) · nx + a.
struct JellyDef
{
  std::string name;
  Eigen::Vector3d origin = Eigen::Vector3d(-0.25, -0.25, 1.0);  ///< [m] lowest corner
  Eigen::Vector3d size = Eigen::Vector3d(0.5, 0.5, 0.5);        ///< [m] > 0 each
  int nx = 5, ny = 5, nz = 5;                                   ///< particles per axis, >= 2
  double mass = 1.0;                                            ///< [kg] total
  SpringConstants stretch{2000.0, 1.0};
  SpringConstants shear{1000.0, 0.5};
  SpringConstants bend{200.0, 0.2};  ///< stiffness 0 = no bend springs
  std::vector<int> pins;
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  ///< [m/s] initial velocity of every particle
  StrainLimitDef strain_limit;
  BodyIntegratorDef integrator;     ///< what the body sets; the rest is the world's default
  double contact_thickness = 0.0;   ///< [m] in limits::kContactThickness: kept from ground and spheres (0 = touch)
  double tear_strain = 0.0;         ///< [-] in limits::kTearStrain: springs stretched past it break (SpringNetworkDef)
  SelfCollisionDef self_collision;  ///< with itself and others (SpringNetworkDef); off by default
};

Status validate(const JellyDef& def, int max_particles);
/// The spring network of a jelly (shape Jelly). `def` must have passed validate().
SpringNetworkDef buildJelly(const JellyDef& def);

}  // namespace core
}  // namespace particle_sim
