#include "particle_sim/core/forces/spring_body_forces.h"

#include <memory>

#include "particle_sim/core/forces/air.h"
#include "particle_sim/core/forces/global_damping.h"
#include "particle_sim/core/forces/gravity.h"
#include "particle_sim/core/forces/rod_bending.h"
#include "particle_sim/core/forces/springs.h"

namespace particle_sim
{
namespace core
{
ForceSet makeSpringBodyForces(const std::vector<Spring>& springs, const BaraffWitkinDef& baraff_witkin,
                              const std::vector<Eigen::Vector3i>& triangles, const RodBendingDef& rod_bending,
                              const PlateBendingDef& plate_bending)
{
  ForceSet forces;
  constexpr int kGravity = 0, kSprings = 1, kBaraffWitkin = 2;
  forces.add(std::make_unique<GravityForce>());
  forces.add(std::make_unique<SpringForces>(springs));
  std::vector<int> energy_order{kSprings, kGravity};
  if (!baraff_witkin.empty())
  {
    forces.add(std::make_unique<BaraffWitkinModel>(baraff_witkin));
    energy_order.push_back(kBaraffWitkin);
  }
  // Only a body that declares rod bending pays for it (the others keep their element list).
  if (!rod_bending.empty())
  {
    energy_order.push_back(baraff_witkin.empty() ? kBaraffWitkin : kBaraffWitkin + 1);
    forces.add(std::make_unique<RodBendingForce>(rod_bending));
  }
  if (!plate_bending.empty())
  {
    energy_order.push_back(static_cast<int>(energy_order.size()));  // its index: every element so far has energy
    forces.add(std::make_unique<PlateBendingForce>(plate_bending));
  }
  if (!triangles.empty()) forces.add(std::make_unique<AirForce>(triangles));
  forces.add(std::make_unique<GlobalDampingForce>());
  // Air and global damping are dissipative or external: no potential energy.
  forces.setEnergyOrder(energy_order);
  return forces;
}

}  // namespace core
}  // namespace particle_sim
