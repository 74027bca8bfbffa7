#pragma once
// Cloths for the self-collision tests (and particle_sim_perf's self-collision case): a square grid
// cloth folded in half, and the layers of config/scenes/cloth_pile.yaml.

#include <cmath>
#include <string>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/spring_network.h"

namespace particle_sim_test
{
// A square grid cloth folded in half, its upper half lying `gap` above its lower half and joined to
// it by a half-circle crease, in the plane z = height; the springs keep the flat cloth's rest
// lengths (folding is an isometry of the stretch and shear springs; the bend springs across the
// crease are compressed).
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
// Layer k (0 to 4) of config/scenes/cloth_pile.yaml: a 17 × 17 spring cloth, 0.7 m, 0.1 kg,
// centred above the origin at 0.7 m + 5 cm per layer and turned 9° per layer; implicit Euler with
// CG, self-collision thickness 8 mm.
inline particle_sim::core::SpringNetworkDef clothPileLayer(int k)
{
  namespace core = particle_sim::core;
  core::ClothGridDef grid(core::ClothModel::Springs);
  grid.name = "cloth_" + std::to_string(k);
  grid.nu = grid.nv = 17;
  const double turn = k * 9.0 * M_PI / 180.0;
  grid.edge_u = 0.7 * Eigen::Vector3d(std::cos(turn), std::sin(turn), 0.0);
  grid.edge_v = 0.7 * Eigen::Vector3d(-std::sin(turn), std::cos(turn), 0.0);
  grid.origin = Eigen::Vector3d(0.0, 0.0, 0.70 + 0.05 * k) - 0.5 * (grid.edge_u + grid.edge_v);
  grid.mass = 0.1;
  grid.stretch = core::ClothConstants{800.0, 0.3};
  grid.shear = core::ClothConstants{200.0, 0.1};
  grid.bend = core::ClothConstants{1.0, 0.01};
  grid.contact_thickness = 0.004;
  grid.integrator.type = core::kImplicitEulerIntegrator;
  grid.integrator.linear_solver = core::LinearSolverType::ConjugateGradient;
  core::SpringNetworkDef def = core::buildClothGrid(grid);
  def.self_collision = core::SelfCollisionDef{true, 0.008};
  return def;
}

}  // namespace particle_sim_test
