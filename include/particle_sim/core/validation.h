#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <sstream>
#include <string>

#include "particle_sim/core/limits.h"
#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// Range checks shared by every definition's validate(); each failure names the field, the
/// value that was given and what is allowed, e.g. "rate = -3 is out of range: must be >= 0".
/// Values are printed as received: never clamped, and non-finite ones as "nan", "inf", "-inf".

inline std::string formatValue(double value)
{
  if (std::isnan(value)) return "nan";  // never "-nan": the sign of a NaN means nothing
  if (std::isinf(value)) return value > 0.0 ? "inf" : "-inf";
  std::ostringstream out;
  out << value;
  return out.str();
}

inline std::string formatValue(const Eigen::Vector3d& value)
{
  return "[" + formatValue(value.x()) + ", " + formatValue(value.y()) + ", " + formatValue(value.z()) + "]";
}

/// Longest received text that messages echo [characters]; longer text is cut (at a character
/// boundary) and its length given.
constexpr std::size_t kMaxEchoedCharacters = limits::kMaxNameLength;

/// Number of bytes of the well-formed UTF-8 character that starts at text[at], or 0 when the bytes
/// there are not one (a stray continuation byte, a truncated or overlong sequence, a surrogate).
inline std::size_t utf8CharacterLength(const std::string& text, std::size_t at)
{
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char lead = byte(at);
  std::size_t length = 0;
  unsigned int code = 0;
  if (lead < 0x80) return 1;
  if (lead >= 0xC2 && lead <= 0xDF)
    length = 2, code = lead & 0x1F;
  else if (lead >= 0xE0 && lead <= 0xEF)
    length = 3, code = lead & 0x0F;
  else if (lead >= 0xF0 && lead <= 0xF4)
    length = 4, code = lead & 0x07;
  else
    return 0;
  if (at + length > text.size()) return 0;
  for (std::size_t k = 1; k < length; ++k)
  {
    if ((byte(at + k) & 0xC0) != 0x80) return 0;
    code = (code << 6) | (byte(at + k) & 0x3F);
  }
  const unsigned int smallest[5] = {0, 0, 0x80, 0x800, 0x10000};
  if (code < smallest[length] || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) return 0;
  return length;
}

/// Number of characters of `text` (a byte that is not well-formed UTF-8 counts as one).
inline std::size_t characterCount(const std::string& text)
{
  std::size_t count = 0;
  for (std::size_t at = 0; at < text.size(); ++count)
    at += std::max<std::size_t>(1, utf8CharacterLength(text, at));
  return count;
}

/// Received text as messages show it: in quotes, bytes that are not well-formed UTF-8 written as
/// \xNN, cut after `max_characters` characters (never inside one) with the full length added,
/// e.g. 'abc...' (100000 characters). The result is always valid UTF-8.
inline std::string quoteReceived(const std::string& text, std::size_t max_characters = kMaxEchoedCharacters)
{
  std::string out = "'";
  std::size_t shown = 0, at = 0;
  for (; at < text.size() && shown < max_characters; ++shown)
  {
    const std::size_t length = utf8CharacterLength(text, at);
    if (length == 0)
    {
      static const char* const kHex = "0123456789ABCDEF";
      const unsigned char bad = static_cast<unsigned char>(text[at]);
      out += std::string("\\x") + kHex[bad >> 4] + kHex[bad & 0xF];
      ++at;
    }
    else
    {
      out.append(text, at, length);
      at += length;
    }
  }
  if (at < text.size()) return out + "...' (" + std::to_string(characterCount(text)) + " characters)";
  return out + "'";
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

/// `value` within the one allowed range of its quantity (limits.h), e.g.
/// "stiffness = 1e+200 is out of range: must be in [0, 1e+09] N/m".
inline Status checkRange(const std::string& field, double value, const limits::Range& range)
{
  const std::string unit = std::string(range.unit) == "-" ? "" : std::string(" ") + range.unit;
  if (!std::isfinite(value))
    return Status::failure(field + " = " + formatValue(value) + " is not a finite number: must be in [" +
                           formatValue(range.min) + ", " + formatValue(range.max) + "]" + unit);
  if (value >= range.min && value <= range.max) return Status::success();
  return Status::failure(field + " = " + formatValue(value) + " is out of range: must be in [" +
                         formatValue(range.min) + ", " + formatValue(range.max) + "]" + unit);
}

/// Every component of `value` within `range`; the message names the component and shows the whole
/// vector, e.g. "wind.x = 1e+308 is out of range: must be in [-100, 100] m/s (wind = [1e+308, 0, 0])".
inline Status checkRange(const std::string& field, const Eigen::Vector3d& value, const limits::Range& range)
{
  if (!value.allFinite())
    return Status::failure(field + " = " + formatValue(value) +
                           " is not finite: every component must be a number in [" + formatValue(range.min) + ", " +
                           formatValue(range.max) + "] " + range.unit);
  const char* const axes[3] = {".x", ".y", ".z"};
  for (int axis = 0; axis < 3; ++axis)
  {
    if (Status s = checkRange(field + axes[axis], value[axis], range); !s)
      return Status::failure(s.message + " (" + field + " = " + formatValue(value) + ")");
  }
  return Status::success();
}

inline Status checkIntRange(const std::string& field, long long value, long long min, long long max)
{
  if (value >= min && value <= max) return Status::success();
  return Status::failure(field + " = " + std::to_string(value) + " is out of range: must be in [" +
                         std::to_string(min) + ", " + std::to_string(max) + "]");
}

/// Stiffness [N/m] and damping [N·s/m] of a spring class, within limits::kStiffness and
/// limits::kDamping; `where` prefixes the names.
inline Status checkSpringConstants(const std::string& where, double stiffness, double damping)
{
  if (Status s = checkRange(where + "stiffness", stiffness, limits::kStiffness); !s) return s;
  return checkRange(where + "damping", damping, limits::kDamping);
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
