#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "particle_sim/core/body.h"
#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/builders/jelly.h"
#include "particle_sim/core/builders/mesh_cloth.h"
#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/constraints/self_collision.h"
#include "particle_sim/core/emitter.h"
#include "particle_sim/core/environment.h"
#include "particle_sim/core/integrator.h"
#include "particle_sim/core/names.h"  // body names follow validateBodyName()
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// World settings with their defaults (Box2D's b2DefaultWorldDef() style).
struct WorldDef
{
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -9.81);  ///< [m/s^2], each component in limits::kGravityComponent
  double global_damping = 0.0;  ///< [1/s] in limits::kGlobalDamping: f = −damping · m · v on spring-body particles
  double dt = 0.001;            ///< [s] fixed physics step
  std::uint64_t seed = 1;       ///< default seed of bodies that do not set their own
  int max_particles_per_body = 100000;  ///< cap on any body's particle count
  /// Cap on the particles of all bodies together (each body counts its full capacity: an
  /// emitter's pool, a spring body's particles), so that spawning bodies cannot exhaust memory.
  int max_particles_per_world = 2000000;
  /// Threads a step may share its loops with, the caller's included, in limits::kThreads; 0 = one
  /// per core of the machine. Results are the same bits at any count (WorkerPool); a body too small
  /// to share its loops never starts a thread.
  int threads = 0;
  /// Integrator settings of every spring body: each field a body definition does not set
  /// (BodyIntegratorDef) is this one, applied by addRope/addClothGrid/addMeshCloth/addJelly/addSpringNetwork.
  IntegratorDef integrator;
  GroundPlaneDef ground;
  std::vector<SphereColliderDef> spheres;
  std::vector<BoxColliderDef> boxes;
  std::vector<CapsuleColliderDef> capsules;
  AirDef air;
};

/// Largest accepted physics step [s]; larger steps are refused by validate(WorldDef).
constexpr double kMaxDt = 0.1;

Status validate(const WorldDef& def);

/// A deterministic per-body seed from the world seed and the body name, for bodies that do not set
/// their own seed: fnv1a64(body_name) XOR world_seed.
std::uint64_t deriveSeed(std::uint64_t world_seed, const std::string& body_name);

/// The simulated world: an environment (gravity, colliders) and named bodies, advanced by a fixed
/// step. Sim time is exactly step_count * dt; nothing here reads a clock. Bodies are referred to
/// by name, never by pointers kept by callers across calls that change the world.
class World
{
public:
  /// Builds an empty world; `def` must have passed validate().
  explicit World(const WorldDef& def);

  const WorldDef& definition() const { return def_; }
  /// The threads the step shares its loops with (WorldDef::threads, 0 resolved to the cores).
  const WorkerPool& workers() const { return *workers_; }
  const Environment& environment() const { return env_; }
  double dt() const { return def_.dt; }

  /// Moves the sphere collider called `name` to `center` [m] (a sphere carried by a robot's tool).
  Status setSphereCenter(const std::string& name, const Eigen::Vector3d& center);
  /// Moves the box or capsule called `name` to a new pose that it reaches over the next `h` [s] >= 0
  /// (a link following its frame): its motion (ColliderMotion) becomes the displacement and the
  /// turn over h, which the contacts of the next step answer; h = 0 places it at rest.
  Status setColliderPose(const std::string& name, const Eigen::Vector3d& center, const Eigen::Quaterniond& orientation,
                         double h);
  /// Validates `def` and adds the box or capsule from the next step on; refuses a name that any
  /// collider (sphere, box, capsule) has already.
  Status addCollider(const BoxColliderDef& def);
  Status addCollider(const CapsuleColliderDef& def);
  /// Removes the sphere, box or capsule called `name` from the next step on.
  Status removeCollider(const std::string& name);
  /// The pose of the box or capsule called `name`; false when there is none.
  bool colliderPose(const std::string& name, Eigen::Vector3d& center, Eigen::Quaterniond& orientation) const;
  /// Sets the wind velocity [m/s] felt by cloth and jelly from the next step; each component in
  /// limits::kWindComponent, else refused (nothing changes).
  Status setWind(const Eigen::Vector3d& wind);
  /// Sets gravity [m/s^2] from the next step; each component in limits::kGravityComponent.
  Status setGravity(const Eigen::Vector3d& gravity);
  /// Sets the global damping [1/s] (f = −damping · m · v on spring-body particles) from the next
  /// step; in limits::kGlobalDamping.
  Status setGlobalDamping(double damping);

  /// Sim time [s] = stepCount() * dt().
  double simTime() const { return static_cast<double>(step_count_) * def_.dt; }
  std::uint64_t stepCount() const { return step_count_; }

  /// Advances every body by one step of dt().
  void step();

  /// Puts every body back in the state it was built in. Sim time keeps running (monotonic).
  void reset();

  /// Validates `def` (names unique, values in range) and adds the emitter.
  Status addEmitter(const EmitterDef& def);
  /// Validates `def` and adds the spring network.
  Status addSpringNetwork(const SpringNetworkDef& def);
  /// Validates `def` and adds the rope it builds.
  Status addRope(const RopeDef& def);
  /// Validates `def` and adds the grid cloth it builds.
  Status addClothGrid(const ClothGridDef& def);
  /// Validates `def` and adds the mesh cloth it builds.
  Status addMeshCloth(const MeshClothDef& def);
  /// Validates `def` and adds the jelly it builds.
  Status addJelly(const JellyDef& def);
  /// Adds an already built body, refusing a duplicate or empty name.
  Status addBody(std::unique_ptr<Body> body);
  Status removeBody(const std::string& name);

  const Body* findBody(const std::string& name) const;
  Body* findBody(const std::string& name);
  /// The spring body called `name`, or null (no such body, or not a spring body).
  SpringNetworkBody* findSpringBody(const std::string& name);
  const SpringNetworkBody* findSpringBody(const std::string& name) const;
  const std::vector<std::unique_ptr<Body>>& bodies() const { return bodies_; }

  /// Live particles over all bodies.
  int particleCount() const;

  /// What the collision pass between surfaces (self_collision) did in the last step: its passes and
  /// impact zones, and per body (in bodies() order) its proximity pairs, collisions and the particles
  /// the fail-safe moved. All zero when no body enables self_collision (the pass does not run).
  const CollisionReport& lastCollisions() const { return collision_report_; }

private:
  WorldDef def_;
  Environment env_;
  std::unique_ptr<WorkerPool> workers_;  // by pointer: the bodies keep its address
  std::vector<std::unique_ptr<Body>> bodies_;
  std::uint64_t step_count_ = 0;
  SelfCollisionSolver self_collision_;
  CollisionReport collision_report_;
  std::vector<SpringNetworkBody*> colliding_bodies_;  // scratch of step(): the bodies that enable self_collision,
  std::vector<int> colliding_index_;                  // and their places in bodies_
};

}  // namespace core
}  // namespace particle_sim
