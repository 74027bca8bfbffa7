#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "particle_sim/core/cloth_model.h"
#include "particle_sim/core/spring.h"
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

// What the grid and mesh cloth builders share ------------------------------------------------------

/// The checks every cloth passes: contact thickness, name, mass, stretch and bend constants,
/// strain limit and integrator, in that order.
Status validateClothCommon(const std::string& name, const SpringConstants& stretch, const SpringConstants& bend,
                           double mass, const StrainLimitDef& strain_limit, const IntegratorDef& integrator,
                           double contact_thickness);
/// Baraff–Witkin's rest stretch b_u, b_v > 0.
Status validateBaraffWitkinRest(double b_u, double b_v);
/// A cloth network (shape Cloth) with nothing in it yet.
SpringNetworkDef emptyCloth(const std::string& name, const IntegratorDef& integrator, const StrainLimitDef& limit,
                            double contact_thickness);
/// A spring of class `cls` from particle i to j of `x`, at rest at their distance.
Spring clothSpring(const std::vector<Eigen::Vector3d>& x, int i, int j, const SpringConstants& c, SpringClass cls);
/// Adds the Baraff–Witkin energies of the triangles of `net`, whose particles have rest coordinates
/// `uvs` [m], with these constants and rest stretch. The triangles must have passed
/// buildBaraffWitkin()'s checks.
void addBaraffWitkin(const std::vector<Eigen::Vector2d>& uvs, const SpringConstants& stretch,
                     const SpringConstants& shear, const SpringConstants& bend, double b_u, double b_v,
                     SpringNetworkDef& net);

}  // namespace core
}  // namespace particle_sim
