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

}  // namespace core
}  // namespace particle_sim
