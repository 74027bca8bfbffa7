#pragma once

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <string>

namespace particle_sim
{
namespace ros_interface
{
/// Longest text of a service answer or log line built from user input [bytes].
constexpr std::size_t kMaxMessageBytes = 1024;
/// Longest user-given string (a body, frame or class name) quoted in a message [bytes].
constexpr std::size_t kMaxQuotedBytes = 80;

/// Length of the well-formed UTF-8 character starting at text[i], or 0 if the bytes there are not
/// one (stray continuation byte, overlong form, surrogate, beyond U+10FFFF, cut short).
inline std::size_t utf8CharLength(const std::string& text, std::size_t i)
{
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char lead = byte(i);
  if (lead < 0x80) return 1;
  std::size_t length = 0;
  unsigned char min_second = 0x80, max_second = 0xBF;
  if (lead >= 0xC2 && lead <= 0xDF)
    length = 2;
  else if (lead >= 0xE0 && lead <= 0xEF)
  {
    length = 3;
    if (lead == 0xE0) min_second = 0xA0;  // no overlong forms
    if (lead == 0xED) max_second = 0x9F;  // no surrogates
  }
  else if (lead >= 0xF0 && lead <= 0xF4)
  {
    length = 4;
    if (lead == 0xF0) min_second = 0x90;
    if (lead == 0xF4) max_second = 0x8F;  // at most U+10FFFF
  }
  else
    return 0;
  if (i + length > text.size()) return 0;
  if (byte(i + 1) < min_second || byte(i + 1) > max_second) return 0;
  for (std::size_t k = 2; k < length; ++k)
  {
    if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
  }
  return length;
}

/// `text` as valid UTF-8 of at most about `max_bytes` bytes: every byte that is not part of a
/// well-formed character is written as "\xNN", control characters as "\xNN" too, and a longer
/// text is cut at a character boundary, ending with "... (N bytes in all)".
inline std::string toMessageText(const std::string& text, std::size_t max_bytes = kMaxMessageBytes)
{
  static const char* kHex = "0123456789ABCDEF";
  std::string out;
  out.reserve(std::min(text.size(), max_bytes) + 32);
  std::size_t i = 0;
  while (i < text.size())
  {
    const std::size_t length = utf8CharLength(text, i);
    const unsigned char c = static_cast<unsigned char>(text[i]);
    const bool escaped = length == 0 || (length == 1 && (c < 0x20 || c == 0x7F) && c != '\n');
    const std::size_t out_length = escaped ? 4 : length;
    if (out.size() + out_length > max_bytes) break;
    if (escaped)
    {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0xF];
      i += 1;
    }
    else
    {
      out.append(text, i, length);
      i += length;
    }
  }
  if (i < text.size()) out += "... (" + std::to_string(text.size()) + " bytes in all)";
  return out;
}

/// A user-given name in quotes, made safe for a message: "'name'".
inline std::string quoteName(const std::string& name)
{
  return "'" + toMessageText(name, kMaxQuotedBytes) + "'";
}

/// A number exactly as received (the shortest text that reads back to the same double): "nan"
/// for every NaN (never "-nan"), "inf" and "-inf" for infinities.
inline std::string formatReceived(double value)
{
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0.0 ? "inf" : "-inf";
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

}  // namespace ros_interface
}  // namespace particle_sim
