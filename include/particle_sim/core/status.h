#pragma once

#include <string>
#include <utility>

namespace particle_sim
{
namespace core
{
/// Outcome of an operation that can be refused: validation of user input, a spawn, a pin.
/// The core never throws through callers (ROS callbacks in particular); it returns a Status
/// whose message names the field, the value and what is allowed.
struct Status
{
  bool ok = true;
  std::string message;

  static Status success(std::string msg = {}) { return {true, std::move(msg)}; }
  static Status failure(std::string msg) { return {false, std::move(msg)}; }
  explicit operator bool() const { return ok; }
};

}  // namespace core
}  // namespace particle_sim
