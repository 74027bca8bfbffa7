#pragma once
// Small helpers shared by the unit tests of the spring bodies.

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include "particle_sim/core/spring.h"
#include "particle_sim/core/status.h"

namespace particle_sim_test
{
inline const double kNaN = std::numeric_limits<double>::quiet_NaN();

// Whether a refusal's message names `field`.
inline bool mentions(const particle_sim::core::Status& status, const std::string& field)
{
  return status.message.find(field) != std::string::npos;
}

// How many of `springs` are of `spring_class`.
inline int countClass(const std::vector<particle_sim::core::Spring>& springs,
                      particle_sim::core::SpringClass spring_class)
{
  return static_cast<int>(std::count_if(springs.begin(), springs.end(),
                                        [&](const auto& s) { return s.spring_class == spring_class; }));
}
}  // namespace particle_sim_test
