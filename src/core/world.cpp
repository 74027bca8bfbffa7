#include "particle_sim/core/world.h"

#include <algorithm>
#include <cmath>

#include "particle_sim/core/fnv1a.h"
#include "particle_sim/core/names.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
Status validate(const WorldDef& def)
{
  if (Status s = checkRange("gravity", def.gravity, limits::kGravityComponent); !s) return s;
  if (Status s = checkRange("global_damping", def.global_damping, limits::kGlobalDamping); !s) return s;
  if (Status s = checkPositive("dt", def.dt); !s) return s;
  if (Status s = checkRange("dt", def.dt, 0.0, kMaxDt); !s) return s;
  if (Status s = checkIntRange("max_particles_per_body", def.max_particles_per_body,
                               static_cast<long long>(limits::kParticlesPerBody.min),
                               static_cast<long long>(limits::kParticlesPerBody.max));
      !s)
    return s;
  if (Status s = checkIntRange("max_particles_per_world", def.max_particles_per_world,
                               static_cast<long long>(limits::kParticlesPerWorld.min),
                               static_cast<long long>(limits::kParticlesPerWorld.max));
      !s)
    return s;
  if (Status s = checkIntRange("threads", def.threads, static_cast<long long>(limits::kThreads.min),
                               static_cast<long long>(limits::kThreads.max));
      !s)
    return s;
  if (Status s = validate(def.integrator); !s) return s;
  if (Status s = validate(def.ground); !s) return s;
  if (Status s = validate(def.air); !s) return s;
  std::vector<std::string> names;
  for (const SphereColliderDef& sphere : def.spheres)
  {
    if (Status s = validate(sphere); !s) return s;
    names.push_back(sphere.name);
  }
  for (const BoxColliderDef& box : def.boxes)
  {
    if (Status s = validate(box); !s) return s;
    names.push_back(box.name);
  }
  for (const CapsuleColliderDef& capsule : def.capsules)
  {
    if (Status s = validate(capsule); !s) return s;
    names.push_back(capsule.name);
  }
  // Boxes and capsules are moved by name, so no two colliders share one.
  for (std::size_t i = 0; i < names.size(); ++i)
  {
    if (std::find(names.begin() + i + 1, names.end(), names[i]) != names.end())
      return Status::failure("collider name = '" + names[i] +
                             "' is used twice: sphere, box and capsule names must be unique");
  }
  return Status::success();
}

World::World(const WorldDef& def)
    : def_(def), workers_(std::make_unique<WorkerPool>(def.threads == 0 ? WorkerPool::coreCount() : def.threads))
{
  env_.gravity = def.gravity;
  env_.ground = def.ground;
  env_.spheres = def.spheres;
  env_.boxes = def.boxes;
  env_.capsules = def.capsules;
  env_.air = def.air;
  env_.damping = def.global_damping;
}

Status World::setSphereCenter(const std::string& name, const Eigen::Vector3d& center)
{
  if (Status s = checkFinite("center", center); !s) return s;
  for (SphereColliderDef& sphere : env_.spheres)
  {
    if (sphere.name != name) continue;
    sphere.center = center;
    return Status::success();
  }
  return Status::failure("sphere = " + quoteReceived(name) + ": no sphere collider has that name");
}

namespace
{
// Moves a box or capsule: the motion is the pose change over h.
template <typename Collider>
void moveCollider(Collider& collider, const Eigen::Vector3d& center, const Eigen::Quaterniond& orientation, double h)
{
  if (h > 0.0)
  {
    const Eigen::AngleAxisd turn(orientation * collider.orientation.conjugate());
    double angle = turn.angle();
    if (angle > M_PI) angle -= 2.0 * M_PI;  // the short way round
    collider.motion.velocity = (center - collider.center) / h;
    collider.motion.angular_velocity = turn.axis() * angle / h;
  }
  else
    collider.motion = ColliderMotion();
  collider.center = center;
  collider.orientation = orientation;
}
}  // namespace

Status World::setColliderPose(const std::string& name, const Eigen::Vector3d& center,
                              const Eigen::Quaterniond& orientation, double h)
{
  if (Status s = checkFinite("center", center); !s) return s;
  if (Status s = validateOrientation("collider '" + name + "'", orientation); !s) return s;
  if (Status s = checkMin("h", h, 0.0); !s) return s;
  for (BoxColliderDef& box : env_.boxes)
  {
    if (box.name != name) continue;
    moveCollider(box, center, orientation, h);
    return Status::success();
  }
  for (CapsuleColliderDef& capsule : env_.capsules)
  {
    if (capsule.name != name) continue;
    moveCollider(capsule, center, orientation, h);
    return Status::success();
  }
  return Status::failure("collider = " + quoteReceived(name) + ": no box or capsule collider has that name");
}

namespace
{
bool hasCollider(const Environment& env, const std::string& name)
{
  auto named = [&](const auto& colliders) {
    return std::any_of(colliders.begin(), colliders.end(), [&](const auto& c) { return c.name == name; });
  };
  return named(env.spheres) || named(env.boxes) || named(env.capsules);
}

template <typename Collider>
Status addTo(Environment& env, std::vector<Collider>& colliders, const Collider& def)
{
  if (Status s = validate(def); !s) return s;
  if (Status s = validateBodyName(def.name); !s) return s;  // the rules of body names
  if (hasCollider(env, def.name))
    return Status::failure("name = " + quoteReceived(def.name) +
                           " is taken: sphere, box and capsule names must be unique");
  colliders.push_back(def);
  return Status::success();
}

template <typename Collider>
bool eraseNamed(std::vector<Collider>& colliders, const std::string& name)
{
  const auto it = std::find_if(colliders.begin(), colliders.end(), [&](const Collider& c) { return c.name == name; });
  if (it == colliders.end()) return false;
  colliders.erase(it);
  return true;
}
}  // namespace

Status World::addCollider(const BoxColliderDef& def)
{
  return addTo(env_, env_.boxes, def);
}

Status World::addCollider(const CapsuleColliderDef& def)
{
  return addTo(env_, env_.capsules, def);
}

Status World::removeCollider(const std::string& name)
{
  if (eraseNamed(env_.spheres, name) || eraseNamed(env_.boxes, name) || eraseNamed(env_.capsules, name))
    return Status::success();
  return Status::failure("name = " + quoteReceived(name) + ": no sphere, box or capsule collider has that name");
}

bool World::colliderPose(const std::string& name, Eigen::Vector3d& center, Eigen::Quaterniond& orientation) const
{
  auto found = [&](const auto& collider) {
    center = collider.center;
    orientation = collider.orientation;
    return true;
  };
  for (const BoxColliderDef& box : env_.boxes)
  {
    if (box.name == name) return found(box);
  }
  for (const CapsuleColliderDef& capsule : env_.capsules)
  {
    if (capsule.name == name) return found(capsule);
  }
  return false;
}

Status World::setWind(const Eigen::Vector3d& wind)
{
  if (Status s = checkRange("wind", wind, limits::kWindComponent); !s) return s;
  env_.air.wind = wind;
  return Status::success();
}

Status World::setGravity(const Eigen::Vector3d& gravity)
{
  if (Status s = checkRange("gravity", gravity, limits::kGravityComponent); !s) return s;
  env_.gravity = gravity;
  return Status::success();
}

Status World::setGlobalDamping(double damping)
{
  if (Status s = checkRange("global_damping", damping, limits::kGlobalDamping); !s) return s;
  env_.damping = damping;
  return Status::success();
}

void World::step()
{
  for (const std::unique_ptr<Body>& body : bodies_)
    body->step(def_.dt, env_);
  // Surfaces that enable self_collision collide with themselves and each other after the step.
  colliding_bodies_.clear();
  colliding_index_.clear();
  for (std::size_t b = 0; b < bodies_.size(); ++b)
  {
    if (bodies_[b]->kind() != BodyKind::SpringNetwork) continue;
    auto* spring_body = static_cast<SpringNetworkBody*>(bodies_[b].get());
    if (!spring_body->definition().self_collision.enabled || spring_body->frozen()) continue;
    colliding_bodies_.push_back(spring_body);
    colliding_index_.push_back(static_cast<int>(b));
  }
  collision_report_.bodies.resize(bodies_.size());
  self_collision_.resolve(def_.dt, colliding_bodies_, colliding_index_, collision_report_);
  ++step_count_;
}

void World::reset()
{
  for (const std::unique_ptr<Body>& body : bodies_)
    body->reset();
  collision_report_ = CollisionReport{};
  collision_report_.bodies.resize(bodies_.size());
  self_collision_.forgetTopology();
}

Status World::addEmitter(const EmitterDef& def)
{
  if (Status s = validate(def, def_.max_particles_per_body, def_.dt); !s) return s;
  return addBody(std::make_unique<EmitterBody>(def));
}

Status World::addSpringNetwork(const SpringNetworkDef& def)
{
  if (Status s = validate(def, def_.max_particles_per_body); !s) return s;
  // Every integrator field the body does not set is the world's default.
  return addBody(std::make_unique<SpringNetworkBody>(def, def_.integrator));
}

Status World::addRope(const RopeDef& def)
{
  if (Status s = validate(def, def_.max_particles_per_body); !s) return s;
  return addSpringNetwork(buildRope(def));
}

Status World::addClothGrid(const ClothGridDef& def)
{
  if (Status s = validate(def, def_.max_particles_per_body); !s) return s;
  return addSpringNetwork(buildClothGrid(def));
}

Status World::addMeshCloth(const MeshClothDef& def)
{
  if (Status s = validate(def, def_.max_particles_per_body); !s) return s;
  return addSpringNetwork(buildMeshCloth(def));
}

Status World::addJelly(const JellyDef& def)
{
  if (Status s = validate(def, def_.max_particles_per_body); !s) return s;
  return addSpringNetwork(buildJelly(def));
}

Status World::addBody(std::unique_ptr<Body> body)
{
  if (Status s = validateBodyName(body->name()); !s) return s;
  if (findBody(body->name()))
    return Status::failure("name = " + quoteReceived(body->name()) + " is already taken: body names must be unique");
  // The world's particle cap counts every body's full capacity (what it allocated).
  long long held = 0;
  for (const std::unique_ptr<Body>& other : bodies_)
    held += other->particles().capacity();
  const long long needed = body->particles().capacity();
  if (held + needed > def_.max_particles_per_world)
    return Status::failure(
        "body " + quoteReceived(body->name()) + " needs " + std::to_string(needed) +
        " particles and the world already holds " + std::to_string(held) + ": at most " +
        std::to_string(def_.max_particles_per_world) + " particles in one world (max_particles_per_world, in [" +
        std::to_string(static_cast<long long>(limits::kParticlesPerWorld.min)) + ", " +
        std::to_string(static_cast<long long>(limits::kParticlesPerWorld.max)) + "]); remove a body first");
  body->setWorkers(workers_.get());
  bodies_.push_back(std::move(body));
  self_collision_.forgetTopology();
  return Status::success();
}

Status World::removeBody(const std::string& name)
{
  auto it = std::find_if(bodies_.begin(), bodies_.end(), [&](const auto& b) { return b->name() == name; });
  if (it == bodies_.end()) return Status::failure("name = " + quoteReceived(name) + ": no body has that name");
  bodies_.erase(it);
  self_collision_.forgetTopology();
  return Status::success();
}

const Body* World::findBody(const std::string& name) const
{
  for (const std::unique_ptr<Body>& body : bodies_)
  {
    if (body->name() == name) return body.get();
  }
  return nullptr;
}

Body* World::findBody(const std::string& name)
{
  return const_cast<Body*>(static_cast<const World*>(this)->findBody(name));
}

SpringNetworkBody* World::findSpringBody(const std::string& name)
{
  Body* body = findBody(name);
  return body && body->kind() == BodyKind::SpringNetwork ? static_cast<SpringNetworkBody*>(body) : nullptr;
}

const SpringNetworkBody* World::findSpringBody(const std::string& name) const
{
  return const_cast<World*>(this)->findSpringBody(name);
}

int World::particleCount() const
{
  int count = 0;
  for (const std::unique_ptr<Body>& body : bodies_)
    count += body->particles().size();
  return count;
}

std::uint64_t deriveSeed(std::uint64_t world_seed, const std::string& body_name)
{
  return fnv1a64(body_name.data(), body_name.size()) ^ world_seed;
}

}  // namespace core
}  // namespace particle_sim
