#pragma once
// Cloths for the self-collision tests: a square grid cloth folded in half, its upper half lying
// `gap` above its lower half and joined to it by a half-circle crease, in the plane z = height; the
// springs keep the flat cloth's rest lengths (folding is an isometry of the stretch and shear
// springs; the bend springs across the crease are compressed).

#include <cmath>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/spring_network.h"

namespace particle_sim_test
{
inline particle_sim::core::SpringNetworkDef foldedCloth(const std::string& name, int n, double size, double gap,
                                                        double height, double thickness)
{
  namespace core = particle_sim::core;
  core::ClothGridDef grid;
  grid.name = name;
  grid.nu = n;
  grid.nv = n;
  grid.origin = Eigen::Vector3d(0.0, 0.0, height);
  grid.edge_u = Eigen::Vector3d(size, 0.0, 0.0);
  grid.edge_v = Eigen::Vector3d(0.0, size, 0.0);
  grid.mass = 0.1;
  grid.stretch = core::ClothConstants{500.0, 0.2};
  grid.shear = core::ClothConstants{100.0, 0.05};
  grid.bend = core::ClothConstants{2.0, 0.01};
  core::SpringNetworkDef def = core::buildClothGrid(grid);
  def.self_collision = core::SelfCollisionDef{true, thickness};
  // Along u: flat for s < a, a half circle of radius gap / 2 around (a, height + gap / 2), then back
  // above the flat part.
  const double r = 0.5 * gap;
  const double a = 0.5 * (size - M_PI * r);
  for (Eigen::Vector3d& x : def.positions)
  {
    const double s = x.x();
    if (s <= a) continue;
    if (s < a + M_PI * r)
    {
      const double theta = (s - a) / r - 0.5 * M_PI;
      x.x() = a + r * std::cos(theta);
      x.z() = height + r + r * std::sin(theta);
    }
    else
    {
      x.x() = a - (s - a - M_PI * r);
      x.z() = height + gap;
    }
  }
  return def;
}
}  // namespace particle_sim_test
