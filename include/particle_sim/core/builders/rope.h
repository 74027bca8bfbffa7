#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "particle_sim/core/integrator.h"
#include "particle_sim/core/materials/rope_material.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// A rope: `particles` evenly spaced from `start` to `end`, N − 1 stretch springs and, when
/// bend_stiffness > 0, bend springs between i and i + 2.
///
/// With a `material` (physical units, issue 17) the rope is built from it instead, for the segment
/// length l = rest length / (N − 1) it has, so that it behaves the same at any N (see buildRope());
/// mass, stretch_stiffness, stretch_damping, bend_stiffness and bend_damping are then not used.
struct RopeDef
{
  std::string name;
  int particles = 20;                                ///< >= 2
  Eigen::Vector3d start = Eigen::Vector3d(0, 0, 2);  ///< [m] particle 0
  Eigen::Vector3d end = Eigen::Vector3d(2, 0, 2);    ///< [m] particle N − 1
  double mass = 1.0;                                 ///< [kg] total, shared equally
  double rest_length =
      0.0;  ///< [m] total rest length; 0 = |end − start| (a larger or smaller value starts it slack or stretched)
  double stretch_stiffness = 500.0;  ///< [N/m]
  double stretch_damping = 0.5;      ///< [N·s/m]
  double bend_stiffness = 0.0;       ///< [N/m]; 0 = no bend springs
  double bend_damping = 0.0;         ///< [N·s/m]
  std::vector<int> pins;             ///< indices pinned where they start; negative counts from the end (-1 = last)
  BodyIntegratorDef integrator;      ///< what the body sets; the rest is the world's default
  double contact_thickness = 0.0;    ///< [m] in limits::kContactThickness: kept from ground and spheres (0 = touch)
  double tear_strain = 0.0;          ///< [-] in limits::kTearStrain: springs stretched past it break (SpringNetworkDef)
  SelfCollisionDef self_collision;   ///< with itself and others (SpringNetworkDef); off by default
  std::optional<RopeMaterial> material;  ///< physical units; when set, replaces mass and the spring constants
};

Status validate(const RopeDef& def, int max_particles);

/// The spring network of a rope (shape Rope). `def` must have passed validate().
///
/// From a material (μ [kg/m], EA [N], ζ [-]) and the segment length l [m], rest length L [m]:
/// - masses lumped at the particles: μ l each, μ l / 2 at the two ends (total μ L);
/// - stretch springs k = EA / l [N/m] (a segment of a bar of stiffness EA);
/// - stretch damping c = η / l [N·s/m] from a Kelvin–Voigt axial viscosity η = 2 ζ L √(EA μ) / π
///   [N·s]: ζ is the damping ratio of the rope's lowest axial (stretch) mode, free–free or
///   fixed–fixed, wavelength 2 L. η is a property of the continuum, so every mode resolved at
///   any N keeps its damping (a mode of wavenumber q has ζ_q = ζ q L / π);
/// - when EI > 0, rod bending at each interior particle (forces/rod_bending.h), k = EI / l [N·m],
///   its damping with the same retardation time τ = η / EA [s] (bending viscosity η_b = τ EI): the
///   damping is stiffness-proportional, every mode of frequency ω has ζ_ω = τ ω / 2.
SpringNetworkDef buildRope(const RopeDef& def);

/// The stretch spring constants a material gives a rope of rest length `rest_length` [m] built of
/// segments `segment` [m] long: {k [N/m], c [N·s/m]} (see buildRope()).
struct RopeSpringConstants
{
  double stiffness;  ///< k = EA / l [N/m]
  double damping;    ///< c = η / l [N·s/m]
};
RopeSpringConstants ropeStretchConstants(const RopeMaterial& material, double rest_length, double segment);

}  // namespace core
}  // namespace particle_sim
