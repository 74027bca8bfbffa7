#pragma once

#include <string>

#include "particle_sim/core/environment.h"
#include "particle_sim/core/particle_pool.h"
#include "particle_sim/core/worker_pool.h"

namespace particle_sim
{
namespace core
{
enum class BodyKind
{
  Emitter,        ///< free particles from an emitter: no springs, exact ballistic motion
  SpringNetwork,  ///< particles joined by springs: ropes, cloth, jelly, free-form networks
};

const char* toString(BodyKind kind);

/// A body owns its particles and advances them one fixed step at a time. Bodies never see each
/// other, so the world may step them independently.
class Body
{
public:
  explicit Body(std::string name) : name_(std::move(name)) {}
  virtual ~Body() = default;
  Body(const Body&) = delete;
  Body& operator=(const Body&) = delete;

  const std::string& name() const { return name_; }
  virtual BodyKind kind() const = 0;
  const ParticlePool& particles() const { return particles_; }

  /// Advances the body by `dt` [s] under `env`. Allocates nothing.
  virtual void step(double dt, const Environment& env) = 0;

  /// Threads the body may share the loops of its step with (the world's; null: none). The results
  /// are the same bits with any of them.
  virtual void setWorkers(WorkerPool* /*workers*/) {}

  /// Puts the body back in the state it was built in.
  virtual void reset() = 0;

  /// Kinetic energy Σ ½ m |v|² of the free (not pinned) live particles [J].
  virtual double kineticEnergy() const = 0;
  /// Potential energy under `gravity` [m/s²] (height 0 at z = 0) plus the body's internal energy
  /// (springs, Baraff–Witkin conditions) [J].
  virtual double potentialEnergy(const Eigen::Vector3d& gravity) const = 0;

protected:
  ParticlePool particles_;

private:
  std::string name_;
};

}  // namespace core
}  // namespace particle_sim
