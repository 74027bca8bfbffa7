#pragma once

#include <vector>

namespace particle_sim
{
namespace core
{
/// A pin index as builders and scene files accept it, resolved for a body of `count` particles:
/// a negative index counts from the end (−1 = the last particle). `index` must be in
/// [−count, count − 1] (checkPinIndices()).
inline int resolvePinIndex(int index, int count)
{
  return index < 0 ? count + index : index;
}

/// Appends every index of `pins`, resolved for `count` particles, to `out`.
inline void appendPins(const std::vector<int>& pins, int count, std::vector<int>& out)
{
  for (int pin : pins)
    out.push_back(resolvePinIndex(pin, count));
}

}  // namespace core
}  // namespace particle_sim
