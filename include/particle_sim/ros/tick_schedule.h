#pragma once

#include <chrono>

namespace particle_sim
{
namespace ros_interface
{
/// When the node's loop runs its next tick (README "Time").
struct NextTick
{
  std::chrono::steady_clock::time_point due;  ///< run the tick once the steady clock reaches it
  double dropped = 0.0;                       ///< [s] lag given up: due was more than max_lag behind now
};

/// The tick after one that was due at `last_due`, `period` later. A due time in the past (the loop
/// is late) stands, so that the next ticks run at once until the loop is back on its schedule,
/// unless it is more than `max_lag` in the past: then the schedule starts again from `now`, and
/// the lag is dropped.
inline NextTick nextTick(std::chrono::steady_clock::time_point last_due, std::chrono::duration<double> period,
                         std::chrono::steady_clock::time_point now, std::chrono::duration<double> max_lag)
{
  using Duration = std::chrono::steady_clock::duration;
  NextTick next;
  next.due = last_due + std::chrono::duration_cast<Duration>(period);
  if (next.due < now - std::chrono::duration_cast<Duration>(max_lag))
  {
    next.dropped = std::chrono::duration<double>(now - next.due).count();
    next.due = now;
  }
  return next;
}

}  // namespace ros_interface
}  // namespace particle_sim
