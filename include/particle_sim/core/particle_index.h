#pragma once

namespace particle_sim
{
namespace core
{
/// A particle index as scenes and definitions give it: 0 to count − 1, or negative counting back
/// from the end (−1 is the last particle). `index` must be in [−count, count − 1]
/// (checkPinIndices in validation.h refuses the rest).
inline int resolveParticleIndex(int index, int count)
{
  return index < 0 ? count + index : index;
}

}  // namespace core
}  // namespace particle_sim
