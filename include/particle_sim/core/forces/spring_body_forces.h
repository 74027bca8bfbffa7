#pragma once

#include <Eigen/Core>
#include <vector>

#include "particle_sim/core/forces/baraff_witkin_model.h"
#include "particle_sim/core/forces/force_set.h"
#include "particle_sim/core/forces/plate_bending.h"
#include "particle_sim/core/forces/rod_bending.h"
#include "particle_sim/core/spring.h"

namespace particle_sim
{
namespace core
{
/// The force elements of a spring body: gravity, its springs (the list may be empty),
/// its Baraff–Witkin conditions (if any), its rod bending (if any: ropes built from a material
/// with EI > 0), air on its surface triangles (if any) and global damping. Forces, Jacobian blocks
/// and stability rows are summed in that order; energies in the order springs, gravity,
/// Baraff–Witkin, rod bending (the orders the golden hashes were recorded with; no recorded scene
/// has rod bending).
ForceSet makeSpringBodyForces(const std::vector<Spring>& springs, const BaraffWitkinDef& baraff_witkin,
                              const std::vector<Eigen::Vector3i>& triangles,
                              const RodBendingDef& rod_bending = RodBendingDef(),
                              const PlateBendingDef& plate_bending = PlateBendingDef());

}  // namespace core
}  // namespace particle_sim
