#pragma once

#include <Eigen/Core>
#include <vector>

#include "particle_sim/core/particle_pool.h"
#include "particle_sim/core/spring.h"
#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// Provot's strain limiting (1995): after each step, relaxation passes over the stretch and shear
/// springs move the ends of every spring longer than (1 + max_strain) times its rest length back to
/// that length (shared by inverse mass; pinned ends stay), until none is over or `iterations`
/// passes are done. Velocities change by the position correction over dt.
struct StrainLimitDef
{
  double max_strain = 0.0;  ///< [-] > 0 turns it on (e.g. 0.1 = 10 %); 0 = off
  int iterations = 50;      ///< cap on relaxation passes, >= 1 (the limit holds exactly only with enough)
};

/// Checks max_strain >= 0 and strain_iterations in [1, 100000].
Status validate(const StrainLimitDef& def);

/// Provot's limit as a constraint applied after the integrator, over a body's stretch and shear
/// springs (bend springs are not limited). Allocates nothing after construction.
class StrainLimit
{
public:
  /// `particles`: the body's particle count; `springs`: all its springs (bend ones are skipped).
  StrainLimit(const StrainLimitDef& def, const std::vector<Spring>& springs, int particles);
  /// Sizes the work arrays for a body that now has `particles` (a vertex split added some).
  void resize(int particles) { unlimited_position_.setZero(3, particles); }

  bool enabled() const { return def_.max_strain > 0.0; }
  /// Limits these springs from now on (the body's after a tear; bend ones are skipped).
  void setSprings(const std::vector<Spring>& springs);
  /// Moves over-stretched springs' ends back (in proportion to their inverse masses), then adds
  /// the correction over `h` [s] to the velocities.
  void apply(double h, ParticlePool& pool);

private:
  StrainLimitDef def_;
  std::vector<Spring> springs_;          // stretch and shear springs, in the body's order
  Eigen::Matrix3Xd unlimited_position_;  // positions before the correction
};

}  // namespace core
}  // namespace particle_sim
