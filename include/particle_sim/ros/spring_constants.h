#pragma once

#include <string>

#include "particle_sim/core/status.h"
#include "particle_sim/core/world.h"

namespace particle_sim
{
namespace ros_interface
{
// Spring constants of a live body (no node handle, no master).

/// Sets stiffness [N/m] and damping [N·s/m] of the `spring_class` springs ("all": every class) of
/// `body`; shared by ~set_spring_constants and dynamic_reconfigure. On success the message says
/// what the change means for stability (springConstantsReport).
core::Status applySpringConstants(core::World& world, const std::string& body, const std::string& spring_class,
                                  double stiffness, double damping);

/// The constants of the first spring of `spring_class` ("all": of any class) of `body`, or of its
/// Baraff–Witkin conditions of that class; false when it has none (or is not a spring body).
bool readSpringConstants(const core::World& world, const std::string& body, const std::string& spring_class,
                         double& stiffness, double& damping);

}  // namespace ros_interface
}  // namespace particle_sim
