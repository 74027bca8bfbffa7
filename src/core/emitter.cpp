#include "particle_sim/core/emitter.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "particle_sim/core/names.h"
#include "particle_sim/core/validation.h"
#include "particle_sim/core/worker_pool.h"

namespace particle_sim
{
namespace core
{
const char* toString(BodyKind kind)
{
  switch (kind)
  {
    case BodyKind::Emitter:
      return "emitter";
    case BodyKind::SpringNetwork:
      return "spring_network";
  }
  return "unknown";
}

const char* toString(EmitterType type)
{
  switch (type)
  {
    case EmitterType::Fountain:
      return "fountain";
    case EmitterType::Waterfall:
      return "waterfall";
    case EmitterType::SemiSphere:
      return "semi_sphere";
    case EmitterType::Explosion:
      return "explosion";
  }
  return "unknown";
}

const char* emitterTypeNames()
{
  return "fountain, waterfall, semi_sphere, explosion";
}

bool parseEmitterType(const std::string& text, EmitterType& type)
{
  for (EmitterType candidate :
       {EmitterType::Fountain, EmitterType::Waterfall, EmitterType::SemiSphere, EmitterType::Explosion})
  {
    if (text == toString(candidate))
    {
      type = candidate;
      return true;
    }
  }
  return false;
}

Status validate(const EmitterDef& def, int max_particles_cap, double dt)
{
  if (Status s = validateBodyName(def.name); !s) return s;
  if (Status s = checkFinite("origin", def.origin); !s) return s;
  if (Status s = checkMin("rate", def.rate, 0.0); !s) return s;
  // One step can emit at most the whole pool: a rate owing more per step could only drop particles.
  if (Status s = checkIntRange("max_particles", def.max_particles, 1, max_particles_cap); !s) return s;
  if (dt > 0.0 && def.rate > maxEmitterRate(def.max_particles, dt))
    return Status::failure("rate = " + formatValue(def.rate) + " is out of range: must be in [0, " +
                           formatValue(maxEmitterRate(def.max_particles, dt)) +
                           "] particles/s (max_particles = " + std::to_string(def.max_particles) +
                           " per step of dt = " + formatValue(dt) + " s; a faster rate could only drop particles)");
  if (Status s = checkIntRange("burst_count", def.burst_count, 0, max_particles_cap); !s) return s;
  if (def.rate == 0.0 && def.burst_count == 0)
    return Status::failure("rate = 0 and burst_count = 0: the emitter would never emit; set one of them > 0");
  if (Status s = checkFinite("speed", def.speed); !s) return s;
  if (def.type != EmitterType::Fountain && def.type != EmitterType::Waterfall)
  {
    if (Status s = checkMin("speed", def.speed, 0.0); !s) return s;
  }
  if (Status s = checkMin("spread", def.spread, 0.0); !s) return s;
  if (Status s = checkPositive("lifetime", def.lifetime); !s) return s;
  if (Status s = checkPositive("particle_mass", def.particle_mass); !s) return s;
  return checkRange("contact_thickness", def.contact_thickness, limits::kContactThickness);
}

double maxEmitterRate(int max_particles, double dt)
{
  return static_cast<double>(max_particles) / dt;
}

namespace
{
constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;

// The lecture's rand01(), from a seeded 64-bit Mersenne twister: the top 53 bits as a double in
// [0, 1). Written out (not std::uniform_real_distribution) so that it is the same on every
// standard library.
double rand01(std::mt19937_64& rng)
{
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

// Unit direction at azimuth alpha and altitude beta, z up.
Eigen::Vector3d direction(double alpha, double beta)
{
  return {std::cos(alpha) * std::cos(beta), std::sin(alpha) * std::cos(beta), std::sin(beta)};
}
}  // namespace

void EmitterBody::sample(const EmitterDef& def, std::mt19937_64& rng, Eigen::Vector3d& position,
                         Eigen::Vector3d& velocity)
{
  switch (def.type)
  {
    // Fountain and waterfall: a random horizontal velocity in [-spread/2, spread/2)^2 and a fixed
    // vertical one (10 and 0 m/s in the lecture).
    case EmitterType::Fountain:
    case EmitterType::Waterfall: {
      const double vx = def.spread * (rand01(rng) - 0.5);
      const double vy = def.spread * (rand01(rng) - 0.5);
      position = def.origin;
      velocity = {vx, vy, def.speed};
      return;
    }
    // Semi-sphere: azimuth in [-180, 180) degrees, altitude in [0, 90); start on the unit sphere.
    case EmitterType::SemiSphere: {
      const double alpha = 360.0 * (rand01(rng) - 0.5) * kDegree;
      const double beta = 90.0 * rand01(rng) * kDegree;
      const Eigen::Vector3d dir = direction(alpha, beta);
      position = def.origin + dir;
      velocity = def.speed * dir;
      return;
    }
    // Explosion: azimuth in [-180, 180), altitude in [-90, 90); start 0.01 m from the origin.
    // The lecture's speed * position would scale the speed by 0.01, so the unit direction is used.
    case EmitterType::Explosion: {
      const double alpha = 360.0 * (rand01(rng) - 0.5) * kDegree;
      const double beta = 180.0 * (rand01(rng) - 0.5) * kDegree;
      const Eigen::Vector3d dir = direction(alpha, beta);
      position = def.origin + 0.01 * dir;
      velocity = def.speed * dir;
      return;
    }
  }
}

EmitterBody::EmitterBody(const EmitterDef& def) : Body(def.name), def_(def)
{
  particles_.resize(def_.max_particles, 0);
  reset();
}

void EmitterBody::reset()
{
  rng_.seed(def_.seed);
  particles_.live_count = 0;
  pending_ = 0.0;
  emitted_ = 0;
  dropped_ = 0;
  emit(def_.burst_count);
}

void EmitterBody::emit(int count)
{
  ParticlePool& p = particles_;
  const double inverse_mass = 1.0 / def_.particle_mass;
  for (int k = 0; k < count; ++k)
  {
    if (p.live_count == p.capacity())
    {
      dropped_ += count - k;
      return;
    }
    const int i = p.live_count++;
    Eigen::Vector3d x, v;
    sample(def_, rng_, x, v);
    p.position.col(i) = x;
    p.previous_position.col(i) = x;
    p.velocity.col(i) = v;
    p.inverse_mass[i] = inverse_mass;
    p.age[i] = 0.0;
    ++emitted_;
  }
}

double EmitterBody::kineticEnergy() const
{
  double energy = 0.0;
  for (int i = 0; i < particles_.size(); ++i)
    energy += 0.5 * def_.particle_mass * particles_.velocity.col(i).squaredNorm();
  return energy;
}

double EmitterBody::potentialEnergy(const Eigen::Vector3d& gravity) const
{
  double energy = 0.0;
  for (int i = 0; i < particles_.size(); ++i)
    energy -= def_.particle_mass * gravity.dot(particles_.position.col(i));
  return energy;
}

namespace
{
// ⌈count / stride⌉: how many of `count` particles a snapshot copies.
std::size_t copiedOf(int count, int stride)
{
  return static_cast<std::size_t>((count + stride - 1) / stride);
}

// Copies particle i into slot i / stride of the snapshot.
inline void copyIntoSnapshot(const ParticlePool& p, int i, int stride, ParticleSnapshot& snapshot)
{
  const int k = i / stride;
  for (int c = 0; c < 3; ++c)
    snapshot.position[3 * static_cast<std::size_t>(k) + c] = p.position(c, i);
  snapshot.age[static_cast<std::size_t>(k)] = p.age[i];
}

// Resizes the snapshot for the particles [0, live).
void sizeSnapshot(int live, int stride, ParticleSnapshot& snapshot)
{
  snapshot.position.resize(3 * copiedOf(live, stride));
  snapshot.age.resize(copiedOf(live, stride));
}

// The first multiple of `stride` at or after `i`.
inline int firstMultipleFrom(int i, int stride)
{
  return (i + stride - 1) / stride * stride;
}
}  // namespace

void EmitterBody::snapshotNextStep(int stride, ParticleSnapshot* into)
{
  snapshot_stride_ = into != nullptr ? std::max(stride, 1) : 0;
  snapshot_ = into;
}

void EmitterBody::copySnapshot(int stride, ParticleSnapshot& into) const
{
  into.stride = std::max(stride, 1);
  sizeSnapshot(particles_.live_count, into.stride, into);
  for (int i = 0; i < particles_.live_count; i += into.stride)
    copyIntoSnapshot(particles_, i, into.stride, into);
}

void EmitterBody::step(double dt, const Environment& env)
{
  ParticlePool& p = particles_;
  // A snapshot asked for by snapshotNextStep(): this step only.
  ParticleSnapshot* const snapshot = snapshot_;
  const int stride = snapshot_stride_;
  snapshot_ = nullptr;
  snapshot_stride_ = 0;
  if (snapshot) sizeSnapshot(p.live_count, stride, *snapshot);

  // 1. Exact ballistic motion under constant gravity (free particles need no integrator), then the
  //    colliders, a chunk of particles at a time while its particles are still in the cache (each
  //    particle alone: the same bits as a pass of each over all of them). The positions become the
  //    previous ones by a swap of the arrays, not a copy; the new ones are written over the old
  //    previous ones (x' = x + (h v + h² g / 2), as before). A snapshot copies the chunk's
  //    particles it takes while they are in the cache, too.
  constexpr int kChunk = 1024;
  const Eigen::Vector3d half_g_dt2 = 0.5 * dt * dt * env.gravity;
  const Eigen::Vector3d g_dt = dt * env.gravity;
  p.position.swap(p.previous_position);
  // Raw pointers, read once: the stores would otherwise make the compiler reload each array's.
  const double* const start = p.previous_position.data();
  double* const x = p.position.data();
  double* const v = p.velocity.data();
  double* const age = p.age.data();
  shareLoop(workers_, p.live_count, kParticlesPerVectorChunk, [&](int first, int last) {
    for (int begin = first; begin < last; begin += kChunk)
    {
      const int end = std::min(begin + kChunk, last);
      for (int i = begin; i < end; ++i)
      {
        for (int c = 0; c < 3; ++c)
        {
          x[3 * i + c] = start[3 * i + c] + (dt * v[3 * i + c] + half_g_dt2[c]);
          v[3 * i + c] += g_dt[c];
        }
        age[i] += dt;
      }
      resolveCollisionsIn(begin, end, env, p, nullptr, &p.previous_position, def_.contact_thickness, dt);
      if (snapshot)
        for (int i = firstMultipleFrom(begin, stride); i < end; i += stride)
          copyIntoSnapshot(p, i, stride, *snapshot);
    }
  });

  // 2. Recycle particles older than their lifetime: the last live particle takes the slot (and a
  //    snapshot takes it again there).
  for (int i = 0; i < p.live_count;)
  {
    if (p.age[i] >= def_.lifetime)
    {
      p.copy(--p.live_count, i);
      if (snapshot && i % stride == 0 && i < p.live_count) copyIntoSnapshot(p, i, stride, *snapshot);
    }
    else
    {
      ++i;
    }
  }
  const int survivors = p.live_count;

  // 3. Emit what the continuous rate owes for this step; new particles start at age 0. The debt
  //    is counted in doubles (capped at 2^53, where they stop being exact integers) and only what
  //    fits in the pool is converted to int; the rest is dropped and counted.
  constexpr double kMaxOwed = 9007199254740992.0;  // 2^53
  const double owed_now = def_.rate * dt;
  pending_ = std::isfinite(owed_now) ? std::min(pending_ + owed_now, kMaxOwed) : kMaxOwed;
  const double owed = std::floor(pending_);
  pending_ -= owed;
  const int room = p.capacity() - p.live_count;
  const int due = owed < room ? static_cast<int>(owed) : room;
  const long long not_emitted = static_cast<long long>(owed) - due;
  dropped_ = dropped_ > std::numeric_limits<long long>::max() - not_emitted ? std::numeric_limits<long long>::max()
                                                                            : dropped_ + not_emitted;
  emit(due);

  // The snapshot of what emission added.
  if (snapshot)
  {
    sizeSnapshot(p.live_count, stride, *snapshot);
    for (int i = firstMultipleFrom(survivors, stride); i < p.live_count; i += stride)
      copyIntoSnapshot(p, i, stride, *snapshot);
    snapshot->stride = stride;
  }
}

}  // namespace core
}  // namespace particle_sim
