#pragma once
// Small helpers shared by the unit tests of the spring bodies.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "particle_sim/core/fnv1a.h"
#include "particle_sim/core/spring.h"
#include "particle_sim/core/status.h"
#include "particle_sim/core/world.h"

namespace particle_sim_test
{
inline const double kNaN = std::numeric_limits<double>::quiet_NaN();

// An environment without gravity or ground: a body moves under its own forces only.
inline particle_sim::core::Environment noGravity()
{
  particle_sim::core::Environment env;
  env.gravity.setZero();
  env.ground.enabled = false;
  return env;
}

// A pool's positions, then its velocities, side by side (3 × 2n): one run's end state.
inline Eigen::Matrix3Xd positionsAndVelocities(const particle_sim::core::ParticlePool& pool)
{
  const int n = pool.size();
  Eigen::Matrix3Xd state(3, 2 * n);
  state << pool.position.leftCols(n), pool.velocity.leftCols(n);
  return state;
}

// The same numbers to the bit (== would call -0 and 0 equal, and no NaN equal to itself).
inline bool sameBits(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b)
{
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

// Whether a refusal's message names `field`.
inline bool mentions(const particle_sim::core::Status& status, const std::string& field)
{
  return status.message.find(field) != std::string::npos;
}

// How many of `springs` are of `spring_class`.
inline int countClass(const std::vector<particle_sim::core::Spring>& springs,
                      particle_sim::core::SpringClass spring_class)
{
  return static_cast<int>(
      std::count_if(springs.begin(), springs.end(), [&](const auto& s) { return s.spring_class == spring_class; }));
}

// FNV-1a, 64 bits (core/fnv1a.h), over raw bytes added piece by piece: doubles are hashed bit for
// bit, so any change of any bit of the state (even 0.0 against -0.0) changes the hash.
class Fnv1a64
{
public:
  void addBytes(const void* data, std::size_t size) { hash_ = particle_sim::core::fnv1a64(data, size, hash_); }
  void addDoubles(const double* data, std::size_t count) { addBytes(data, count * sizeof(double)); }
  template <typename T>
  void addValue(const T& value)
  {
    static_assert(std::is_integral_v<T> || std::is_enum_v<T>, "plain integers and enums only (no padding)");
    addBytes(&value, sizeof(value));
  }
  void addString(const std::string& text)
  {
    addValue(static_cast<std::uint64_t>(text.size()));
    addBytes(text.data(), text.size());
  }
  std::uint64_t value() const { return hash_; }

private:
  std::uint64_t hash_ = particle_sim::core::kFnv1a64OffsetBasis;
};

// The full state of `world`, hashed bit for bit: the step count, then per body in world order its
// name, kind and live particles (positions, velocities, previous positions, inverse masses,
// ages); emitters add their emitted and dropped counts, spring bodies their pins, pin targets and
// whether they are frozen.
inline std::uint64_t worldStateHash(const particle_sim::core::World& world)
{
  Fnv1a64 hash;
  hash.addValue(world.stepCount());
  for (const auto& body : world.bodies())
  {
    hash.addString(body->name());
    hash.addValue(body->kind());
    const particle_sim::core::ParticlePool& p = body->particles();
    const auto live = static_cast<std::size_t>(p.size());
    hash.addValue(static_cast<std::uint64_t>(live));
    // Live particles are the first columns, contiguous (column-major 3 x capacity).
    hash.addDoubles(p.position.data(), 3 * live);
    hash.addDoubles(p.velocity.data(), 3 * live);
    hash.addDoubles(p.previous_position.data(), 3 * live);
    hash.addDoubles(p.inverse_mass.data(), live);
    hash.addDoubles(p.age.data(), live);
    if (const auto* emitter = dynamic_cast<const particle_sim::core::EmitterBody*>(body.get()))
    {
      hash.addValue(emitter->emittedCount());
      hash.addValue(emitter->droppedCount());
    }
    if (const auto* spring_body = dynamic_cast<const particle_sim::core::SpringNetworkBody*>(body.get()))
    {
      for (int i = 0; i < p.size(); ++i)
      {
        hash.addValue(static_cast<std::uint8_t>(spring_body->isPinned(i)));
        if (!spring_body->isPinned(i)) continue;
        const Eigen::Vector3d target = spring_body->pinTarget(i);
        hash.addDoubles(target.data(), 3);
      }
      hash.addValue(static_cast<std::uint8_t>(spring_body->frozen()));
    }
  }
  return hash.value();
}
}  // namespace particle_sim_test
