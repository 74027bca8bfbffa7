#pragma once

#include <Eigen/Core>
#include <cmath>
#include <sstream>
#include <string>

#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// Range checks shared by every definition's validate(); each failure names the field, the
/// value that was given and what is allowed, e.g. "rate = -3 is out of range: must be >= 0".

inline std::string formatValue(double value)
{
  std::ostringstream out;
  out << value;
  return out.str();
}

inline std::string formatValue(const Eigen::Vector3d& value)
{
  std::ostringstream out;
  out << "[" << value.x() << ", " << value.y() << ", " << value.z() << "]";
  return out.str();
}

inline Status checkFinite(const std::string& field, double value)
{
  if (std::isfinite(value)) return Status::success();
  return Status::failure(field + " = " + formatValue(value) + " is not a finite number");
}

inline Status checkFinite(const std::string& field, const Eigen::Vector3d& value)
{
  if (value.allFinite()) return Status::success();
  return Status::failure(field + " = " + formatValue(value) + " is not finite: every component must be a number");
}

inline Status checkMin(const std::string& field, double value, double min)
{
  if (Status s = checkFinite(field, value); !s) return s;
  if (value >= min) return Status::success();
  return Status::failure(field + " = " + formatValue(value) + " is out of range: must be >= " + formatValue(min));
}

inline Status checkPositive(const std::string& field, double value)
{
  if (Status s = checkFinite(field, value); !s) return s;
  if (value > 0.0) return Status::success();
  return Status::failure(field + " = " + formatValue(value) + " is out of range: must be > 0");
}

inline Status checkRange(const std::string& field, double value, double min, double max)
{
  if (Status s = checkFinite(field, value); !s) return s;
  if (value >= min && value <= max) return Status::success();
  return Status::failure(field + " = " + formatValue(value) + " is out of range: must be in [" + formatValue(min) +
                         ", " + formatValue(max) + "]");
}

inline Status checkIntRange(const std::string& field, long long value, long long min, long long max)
{
  if (value >= min && value <= max) return Status::success();
  return Status::failure(field + " = " + std::to_string(value) + " is out of range: must be in [" +
                         std::to_string(min) + ", " + std::to_string(max) + "]");
}

/// Stiffness [N/m] and damping [N·s/m] of a spring class, both >= 0; `where` prefixes the names.
inline Status checkSpringConstants(const std::string& where, double stiffness, double damping)
{
  if (Status s = checkMin(where + "stiffness", stiffness, 0.0); !s) return s;
  return checkMin(where + "damping", damping, 0.0);
}

/// Pin indices of a body of `count` particles; negative ones count from the end (-1 = last).
template <typename Container>
Status checkPinIndices(const Container& pins, int count)
{
  for (std::size_t k = 0; k < pins.size(); ++k)
  {
    const long long pin = pins[k];
    if (pin < -count || pin >= count)
      return Status::failure("pins[" + std::to_string(k) + "] = " + std::to_string(pin) +
                             " is out of range: must be in [" + std::to_string(-count) + ", " +
                             std::to_string(count - 1) + "] (negative counts from the end)");
  }
  return Status::success();
}

}  // namespace core
}  // namespace particle_sim
