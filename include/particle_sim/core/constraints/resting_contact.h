#pragma once

#include <Eigen/Core>
#include <vector>

#include "particle_sim/core/environment.h"
#include "particle_sim/core/particle_pool.h"

namespace particle_sim
{
namespace core
{
/// A particle lying on a collider's surface at the start of an implicit step. The implicit solve
/// (ImplicitEulerSolver::solve) holds it with Baraff & Witkin's constrained directions (1998,
/// section 5.3), inside the solve, so the springs around it are solved knowing what it does (a
/// projection after the solve, which the solve did not foresee, makes resting cloth jitter and
/// creep):
/// - stuck (static friction): all its velocity ends equal to the surface's, while the impulse the
///   surface needs for that stays inside the friction cone |J_t| <= friction · J_n;
/// - slipping (sticking would need more): only its velocity along the normal is held, and the
///   friction impulse is the largest the cone allows, friction · J_n, against the way it slides
///   (the direction sticking needed), inside the solve;
/// - let go: holding it would pull (J_n < 0: its neighbours lift it off the surface).
struct RestingContact
{
  int particle = -1;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();           ///< outward unit normal of the surface
  Eigen::Vector3d surface_velocity = Eigen::Vector3d::Zero();  ///< [m/s] of the surface point it lies on
  double friction = 0.0;                                       ///< [-] the collider's Coulomb coefficient
  /// Set by the solve: held along the normal in this step (it was not leaving the surface, and
  /// holding it did not pull it).
  bool held = false;
  /// Set by the solve: held in every direction (static friction sufficed).
  bool stuck = false;
  /// Set by the solve: holding it pulled, so it was let go and the system solved again.
  bool let_go = false;
  /// Set by the solve: sticking needed more than static friction, so it slides with the friction
  /// impulse `friction_impulse` [N·s] (on the cone's rim, along the impulse sticking needed).
  bool slipping = false;
  Eigen::Vector3d friction_impulse = Eigen::Vector3d::Zero();
  /// Set by the solve: the impulse [N·s] the surface gave the held particle (what its row of the
  /// system lacks for the velocity it was held to), and its part along the normal; 0 when not held.
  Eigen::Vector3d impulse = Eigen::Vector3d::Zero();
  double normal_impulse = 0.0;
};

/// How close [m] to a collider's surface (grown by the contact thickness) a particle must be to
/// rest on it: particles put on the surface by a collision response or held there lie within
/// rounding of it.
inline constexpr double kRestingContactDistance = 1e-6;

/// The live, non-pinned particles of `pool` within kRestingContactDistance of a collider's surface
/// (or inside it), each with the nearest such surface (the deepest, when inside several): its
/// outward normal, velocity and friction. `out` is overwritten (its capacity kept).
void findRestingContacts(const Environment& env, const ParticlePool& pool, double thickness,
                         std::vector<RestingContact>& out);

}  // namespace core
}  // namespace particle_sim
