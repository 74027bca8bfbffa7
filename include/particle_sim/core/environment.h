#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "particle_sim/core/particle_pool.h"
#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
class WorkerPool;

/// How a collider answers a particle that reached it.
struct ContactDef
{
  double restitution = 0.5;   ///< [-] in [0, 1]: share of the normal speed kept after a bounce
  double friction = 0.3;      ///< [-] >= 0: Coulomb coefficient, tangential speed lost <= friction * normal impulse / m
  double bounce_speed = 0.2;  ///< [m/s] >= 0: slower impacts do not bounce (resting contact stays at rest)
};

/// The horizontal plane z = height; particles stay above it.
struct GroundPlaneDef
{
  bool enabled = true;
  double height = 0.0;  ///< [m]
  ContactDef contact;
};

/// A static sphere; particles stay outside it.
struct SphereColliderDef
{
  std::string name;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< [m]
  double radius = 1.0;                               ///< [m] > 0
  ContactDef contact;
};

/// How a collider's frame moves: the rigid velocity at a point p is velocity + angular_velocity ×
/// (p − center). Contacts respond to the particle's velocity relative to it, so a moving link pushes
/// what it meets instead of passing through. Set by World::setColliderPose from successive poses.
struct ColliderMotion
{
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();          ///< [m/s] of the centre
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  ///< [rad/s]
};

/// A box, oriented; particles stay outside it (a table, a robot link, a finger pad).
struct BoxColliderDef
{
  std::string name;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();                 ///< [m]
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< the box's axes in the sim frame (unit)
  Eigen::Vector3d half_extents = Eigen::Vector3d(0.5, 0.5, 0.5);    ///< [m] > 0, along the box's axes
  ContactDef contact;
  ColliderMotion motion;
};

/// A capsule: every point within `radius` of the segment center ± half_length · a, where a is the
/// orientation's x axis; particles stay outside it (a finger, a forearm, a rod).
struct CapsuleColliderDef
{
  std::string name;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();                 ///< [m]
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< the axis is its x axis (unit)
  double half_length = 0.5;                                         ///< [m] >= 0, of the axis segment
  double radius = 0.1;                                              ///< [m] > 0
  ContactDef contact;
  ColliderMotion motion;
};

/// Air around cloth and jelly: each surface triangle of area A and unit normal n, moving at the
/// mean velocity v of its corners, feels f = drag · A · ((wind − v)·n) n, shared equally by its
/// three corners (only the normal component: a sheet moving in its own plane feels none).
struct AirDef
{
  double drag = 0.0;                               ///< [N·s/m³] >= 0; 0 = no air (nothing computed)
  Eigen::Vector3d wind = Eigen::Vector3d::Zero();  ///< [m/s] wind velocity
};

Status validate(const ContactDef& def, const std::string& where);
Status validate(const AirDef& def);
Status validate(const GroundPlaneDef& def);
Status validate(const SphereColliderDef& def);
Status validate(const BoxColliderDef& def);
/// A finite unit quaternion (norm 1 within 1e-6), named `where`.orientation in the message.
Status validateOrientation(const std::string& where, const Eigen::Quaterniond& q);
Status validate(const CapsuleColliderDef& def);

/// What every body feels: gravity and the colliders. Bodies read it; only the world changes it.
struct Environment
{
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -9.81);  ///< [m/s^2], z up (REP-103)
  GroundPlaneDef ground;
  std::vector<SphereColliderDef> spheres;
  std::vector<BoxColliderDef> boxes;
  std::vector<CapsuleColliderDef> capsules;
  AirDef air;
  double damping = 0.0;  ///< [N·s/m per kg = 1/s] >= 0: global damping, f = −damping · m · v on spring-body particles

  /// Whether a particle can touch anything: the ground or any sphere, box or capsule.
  bool hasColliders() const { return ground.enabled || !spheres.empty() || !boxes.empty() || !capsules.empty(); }
};

/// Moves every live, non-pinned particle of `pool` that ended a step inside a collider back out.
/// With a contact `thickness` t [m] > 0 the colliders act as if grown by t: particles stay at least
/// t above the ground plane and t outside every sphere (a drawn surface between them then stays
/// outside the sphere; see clothContactThickness()).
/// `start_velocity`, when given, is each particle's velocity at the start of the step: a contact
/// bounces only if the particle was already moving into the surface then (faster than
/// bounce_speed), so a particle resting on a surface that an implicit step pulls into it is not
/// thrown off.
///
/// For each collider with outward normal n and penetration depth p > 0:
///   position  x += (1 + e) p n          (mirror image for e = 1, the surface for e = 0)
///   velocity  v_n' = -e v_n when moving inward faster than bounce_speed (now and at the start of the
///             step), else 0,
///             |v_t| shrinks by at most mu (1 + e) |v_n| (Coulomb friction on the impulse).
/// The result is always outside the collider that was handled.
///
/// `start_position`, when given, is each particle's position at the start of the step: a particle
/// whose straight path crossed a sphere, box or capsule (fast particles, or thin boxes, that it
/// would tunnel through) is put back where the path first met the collider and responds there.
/// For a moving box or capsule the path is taken relative to it (its motion over `h` [s], the
/// step, undone at the start), and the response uses the velocity relative to its surface.
///
/// Each particle is handled alone: with `workers` the particles are shared between threads, with
/// the same bits as one. With no collider at all (no ground, sphere, box or capsule), nothing runs.
void resolveCollisions(const Environment& env, ParticlePool& pool, const Eigen::Matrix3Xd* start_velocity = nullptr,
                       const Eigen::Matrix3Xd* start_position = nullptr, double thickness = 0.0, double h = 0.0,
                       WorkerPool* workers = nullptr);
/// resolveCollisions() for the particles [begin, end) alone (the same bits for each), for a pass
/// that moves a chunk of particles and resolves its collisions while the chunk is in the cache.
void resolveCollisionsIn(int begin, int end, const Environment& env, ParticlePool& pool,
                         const Eigen::Matrix3Xd* start_velocity = nullptr,
                         const Eigen::Matrix3Xd* start_position = nullptr, double thickness = 0.0, double h = 0.0);

}  // namespace core
}  // namespace particle_sim
