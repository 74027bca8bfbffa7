#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "particle_sim/core/body.h"
#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// The lecture's four emitters, mapped to z up (the lecture's y is our z, its x and z our x, y).
enum class EmitterType
{
  Fountain,    ///< from `origin`, velocity (spread (r - 1/2), spread (r - 1/2), speed)
  Waterfall,   ///< like the fountain; its vertical `speed` defaults to 0 so it pours over an edge
  SemiSphere,  ///< from the unit upper half sphere around `origin`, velocity = speed * direction
  Explosion,   ///< from a 0.01 m sphere around `origin`, velocity = speed * unit direction
};

const char* toString(EmitterType type);
/// Parses "fountain", "waterfall", "semi_sphere" or "explosion"; false when unknown.
bool parseEmitterType(const std::string& text, EmitterType& type);
/// The accepted names, for error messages: "fountain, waterfall, semi_sphere, explosion".
const char* emitterTypeNames();

/// Everything that defines an emitter, with its defaults. Built alike by a scene file and by the
/// ~spawn_emitter service, and checked by the same validate().
struct EmitterDef
{
  std::string name;
  EmitterType type = EmitterType::Fountain;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< [m] in the world frame
  double rate = 100.0;    ///< [particles/s] emitted continuously, 0 = none; at most maxEmitterRate(max_particles, dt)
  int burst_count = 0;    ///< [particles] emitted at once when the emitter starts (and on reset)
  double speed = 10.0;    ///< [m/s] initial speed (vertical component for fountain and waterfall)
  double spread = 1.0;    ///< [m/s] width of the random horizontal velocity of fountain and waterfall
  double lifetime = 3.0;  ///< [s] after which a particle is recycled
  double particle_mass = 0.01;     ///< [kg]
  int max_particles = 2000;        ///< size of the fixed particle pool
  std::uint64_t seed = 1;          ///< random seed: the same seed gives the same particles
  double contact_thickness = 0.0;  ///< [m] in limits::kContactThickness: kept from ground and spheres (0 = touch)
};

/// Upper bound on `max_particles` of one emitter unless the caller allows more (the node's
/// ~max_particles_per_body parameter).
constexpr int kDefaultMaxParticlesCap = 1000000;

/// Checks every field; on failure the message names the field, its value and the allowed range.
/// With the world's step `dt` [s] (> 0) it also bounds the rate by maxEmitterRate().
Status validate(const EmitterDef& def, int max_particles_cap = kDefaultMaxParticlesCap, double dt = 0.0);

/// Largest emission rate [particles/s] of an emitter whose pool holds `max_particles`, stepped by
/// `dt` [s]: max_particles / dt, one whole pool per step. A faster rate would owe more particles in
/// one step than the pool can ever hold, so everything above it could only be dropped.
double maxEmitterRate(int max_particles, double dt);

/// Every `stride`-th live particle of an emitter (indices 0, stride, 2 stride, ...), as a step left
/// them: what a drawing of the particles needs, copied out for another thread to read while the
/// emitter steps on (EmitterBody::snapshotNextStep()).
struct ParticleSnapshot
{
  int stride = 0;                ///< of the copy taken; 0 while none is
  std::vector<double> position;  ///< [m] x, y, z of each copied particle, in index order
  std::vector<double> age;       ///< [s] each copied particle's
};

/// An emitter and the particles it has emitted. Its pool holds `max_particles` particles, the
/// live ones first; a particle older than `lifetime` is recycled, and an emission that finds the
/// pool full is dropped (counted in `droppedCount()`).
class EmitterBody : public Body
{
public:
  explicit EmitterBody(const EmitterDef& def);

  BodyKind kind() const override { return BodyKind::Emitter; }
  const EmitterDef& definition() const { return def_; }

  /// Moves every particle along its exact ballistic path x += v dt + g dt^2 / 2, v += g dt, ages it
  /// and resolves its collisions (shared with the workers by chunks of particles), then recycles
  /// and emits.
  void step(double dt, const Environment& env) override;
  void setWorkers(WorkerPool* workers) override { workers_ = workers; }
  void reset() override;
  /// Σ ½ m |v|² over the live particles [J].
  double kineticEnergy() const override;
  /// Σ −m g · x over the live particles [J]; free particles store no other energy.
  double potentialEnergy(const Eigen::Vector3d& gravity) const override;

  /// Asks the next step() for a snapshot of every `stride`-th live particle (stride ≥ 1) into
  /// `into`, kept by the caller (its vectors keep their capacity); the step sets into->stride to
  /// `stride` once it is taken. It is taken while the step has each particle in the cache: the
  /// motion's chunks copy theirs, and the slots that recycling and emission write afterwards are
  /// copied again, so it equals a copy made after the step, at a fraction of the memory traffic.
  /// Only the next step; snapshotNextStep(0, nullptr) takes the request back. The step grows
  /// `into`'s vectors only past their capacity: a snapshot asked again and again allocates nothing
  /// once the particles' count has settled.
  void snapshotNextStep(int stride, ParticleSnapshot* into);
  /// The same snapshot of the particles as they are now (stride ≥ 1), a pass over them.
  void copySnapshot(int stride, ParticleSnapshot& into) const;
  long long emittedCount() const { return emitted_; }
  long long droppedCount() const { return dropped_; }

  /// Draws one particle's initial position and velocity by the lecture's formula for `type`.
  /// Exposed so tests can check the formulas directly.
  static void sample(const EmitterDef& def, std::mt19937_64& rng, Eigen::Vector3d& position, Eigen::Vector3d& velocity);

private:
  void emit(int count);

  EmitterDef def_;
  std::mt19937_64 rng_;
  double pending_ = 0.0;  // fractional particles owed by the continuous rate
  long long emitted_ = 0;
  long long dropped_ = 0;
  WorkerPool* workers_ = nullptr;  // the world's, for the motion's pass
  // snapshotNextStep()'s request, for the next step only.
  int snapshot_stride_ = 0;
  ParticleSnapshot* snapshot_ = nullptr;
};

}  // namespace core
}  // namespace particle_sim
