#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "particle_sim/core/integrator.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// A rope: `particles` evenly spaced from `start` to `end`, N − 1 stretch springs and, when
/// bend_stiffness > 0, bend springs between i and i + 2.
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
};

Status validate(const RopeDef& def, int max_particles);

/// The spring network of a rope (shape Rope). `def` must have passed validate().
SpringNetworkDef buildRope(const RopeDef& def);

}  // namespace core
}  // namespace particle_sim
