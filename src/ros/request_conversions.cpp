#include "particle_sim/ros/request_conversions.h"

#include <limits>

#include "particle_sim/core/world.h"
#include "particle_sim/ros/eigen_messages.h"
#include "particle_sim/ros/material_conversions.h"
#include "particle_sim/ros/message_text.h"

namespace particle_sim
{
namespace ros_interface
{
namespace
{
// A count field of a request (uint32) as the core's int: a value beyond int is refused as
// received instead of being clamped (which would show the clamped value in the core's message);
// the core checks the rest of the range.
core::Status readCount(const char* field, std::uint32_t value, int& count)
{
  constexpr auto kMax = static_cast<std::uint32_t>(std::numeric_limits<int>::max());
  if (value > kMax)
    return core::Status::failure(std::string(field) + " = " + std::to_string(value) +
                                 " is out of range: must be at most " + std::to_string(kMax));
  count = static_cast<int>(value);
  return core::Status::success();
}

// A count field where 0 keeps the definition's default.
core::Status readCountOrDefault(const char* field, std::uint32_t value, int& count)
{
  if (value == 0) return core::Status::success();
  return readCount(field, value, count);
}

// The self_collision fields of a spawn request: on or off, and the thickness [m], 0 keeping the
// default (core::SelfCollisionDef); the core checks its range when the body is added.
void toSelfCollision(bool enabled, double thickness, core::SelfCollisionDef& def)
{
  def.enabled = enabled;
  if (thickness != 0.0) def.thickness = thickness;
}

std::string formatVector(const Eigen::Vector3d& v)
{
  return "[" + formatReceived(v.x()) + ", " + formatReceived(v.y()) + ", " + formatReceived(v.z()) + "]";
}
}  // namespace

core::Status parseIntegratorField(const std::string& name, core::BodyIntegratorDef& integrator)
{
  if (name.empty()) return core::Status::success();
  core::IntegratorType type;
  if (core::parseIntegratorType(name, type))
  {
    integrator.type = type;
    return core::Status::success();
  }
  return core::Status::failure("integrator = " + quoteName(name) +
                               " is not an integrator; allowed: " + core::integratorTypeNames());
}

core::Status toEmitterDef(const SpawnEmitter::Request& req, std::uint64_t world_seed, core::EmitterDef& def)
{
  def.name = req.name;
  if (!core::parseEmitterType(req.type, def.type))
    return core::Status::failure("type = " + quoteName(req.type) +
                                 " is not an emitter type; allowed: " + core::emitterTypeNames());
  def.origin = toEigen(req.origin);
  def.rate = req.rate;
  if (core::Status s = readCount("burst_count", req.burst_count, def.burst_count); !s) return s;
  def.speed = req.speed;
  def.spread = req.spread;
  if (req.lifetime != 0.0) def.lifetime = req.lifetime;
  if (req.mass != 0.0) def.particle_mass = req.mass;
  if (core::Status s = readCountOrDefault("max_particles", req.max_particles, def.max_particles); !s) return s;
  def.seed = req.seed != 0 ? req.seed : core::deriveSeed(world_seed, def.name);
  return core::Status::success();
}

core::Status toRopeDef(const SpawnRope::Request& req, const core::IntegratorDef& default_integrator, core::RopeDef& def,
                       const std::string& default_material)
{
  def.name = req.name;
  if (core::Status s = ropeMaterialOf(req, default_material, def.material); !s) return s;
  if (core::Status s = readCountOrDefault("particles", req.particles, def.particles); !s) return s;
  def.start = toEigen(req.start);
  def.end = toEigen(req.end);
  def.rest_length = req.rest_length;
  // A material gives the mass and constants (the request has none: ropeMaterialOf).
  if (!def.material)
  {
    if (req.mass != 0.0) def.mass = req.mass;
    def.stretch_stiffness = req.stretch_stiffness;
    def.stretch_damping = req.stretch_damping;
    def.bend_stiffness = req.bend_stiffness;
    def.bend_damping = req.bend_damping;
  }
  def.pins.assign(req.pins.begin(), req.pins.end());
  def.tear_strain = req.tear_strain;
  toSelfCollision(req.self_collision, req.self_collision_thickness, def.self_collision);
  def.integrator = core::settingEveryField(default_integrator);
  return parseIntegratorField(req.integrator, def.integrator);
}

core::Status toClothGridDef(const SpawnCloth::Request& req, const core::IntegratorDef& default_integrator,
                            core::ClothGridDef& def, const std::string& default_material)
{
  def.name = req.name;
  if (core::Status s = clothMaterialOf(req, default_material, def.material); !s) return s;
  // The model: the request's; empty = springs, or Baraff–Witkin for a material (the model that
  // carries its bending rigidity; the spring model refuses one > 0).
  if (req.model.empty() && def.material) def.model = core::ClothModel::BaraffWitkin;
  if (!req.model.empty() && !core::parseClothModel(req.model, def.model))
    return core::Status::failure("model = " + quoteName(req.model) +
                                 " is not a cloth model; allowed: springs, baraff_witkin");
  if (req.b_u != 0.0) def.b_u = req.b_u;
  if (req.b_v != 0.0) def.b_v = req.b_v;
  def.origin = toEigen(req.origin);
  def.edge_u = toEigen(req.edge_u);
  def.edge_v = toEigen(req.edge_v);
  if (core::Status s = readCountOrDefault("nu", req.nu, def.nu); !s) return s;
  if (core::Status s = readCountOrDefault("nv", req.nv, def.nv); !s) return s;
  // A material gives the mass and constants (the request has none: clothMaterialOf).
  if (!def.material)
  {
    if (req.mass != 0.0) def.mass = req.mass;
    def.stretch = {req.stretch_stiffness, req.stretch_damping};
    def.shear = {req.shear_stiffness, req.shear_damping};
    def.bend = {req.bend_stiffness, req.bend_damping};
  }
  def.pins.assign(req.pins.begin(), req.pins.end());
  def.named_pins = req.named_pins;
  def.strain_limit.max_strain = req.max_strain;
  def.tear_strain = req.tear_strain;
  toSelfCollision(req.self_collision, req.self_collision_thickness, def.self_collision);
  def.integrator = core::settingEveryField(default_integrator);
  return parseIntegratorField(req.integrator, def.integrator);
}

core::Status toJellyDef(const SpawnJelly::Request& req, const core::IntegratorDef& default_integrator,
                        core::JellyDef& def)
{
  def.name = req.name;
  def.origin = toEigen(req.origin);
  def.size = toEigen(req.size);
  if (core::Status s = readCountOrDefault("nx", req.nx, def.nx); !s) return s;
  if (core::Status s = readCountOrDefault("ny", req.ny, def.ny); !s) return s;
  if (core::Status s = readCountOrDefault("nz", req.nz, def.nz); !s) return s;
  if (req.mass != 0.0) def.mass = req.mass;
  def.stretch = {req.stretch_stiffness, req.stretch_damping};
  def.shear = {req.shear_stiffness, req.shear_damping};
  def.bend = {req.bend_stiffness, req.bend_damping};
  def.velocity = toEigen(req.velocity);
  def.pins.assign(req.pins.begin(), req.pins.end());
  def.strain_limit.max_strain = req.max_strain;
  def.tear_strain = req.tear_strain;
  toSelfCollision(req.self_collision, req.self_collision_thickness, def.self_collision);
  def.integrator = core::settingEveryField(default_integrator);
  return parseIntegratorField(req.integrator, def.integrator);
}

core::Status toColliderDef(const SpawnCollider::Request& req, bool& is_box, core::BoxColliderDef& box,
                           core::CapsuleColliderDef& capsule)
{
  if (req.shape != SpawnCollider::Request::SHAPE_BOX && req.shape != SpawnCollider::Request::SHAPE_CAPSULE)
    return core::Status::failure("shape = " + quoteName(req.shape) + " is not a collider shape; allowed: box, capsule");
  is_box = req.shape == SpawnCollider::Request::SHAPE_BOX;
  const geometry_msgs::Quaternion& q = req.pose.orientation;
  const Eigen::Quaterniond orientation = q.x == 0.0 && q.y == 0.0 && q.z == 0.0 && q.w == 0.0
                                             ? Eigen::Quaterniond::Identity()
                                             : Eigen::Quaterniond(q.w, q.x, q.y, q.z);
  core::ContactDef contact;
  contact.restitution = req.restitution;
  contact.friction = req.friction;
  const Eigen::Vector3d size = toEigen(req.size);
  if (is_box)
  {
    if (req.length != 0.0 || req.radius != 0.0)
      return core::Status::failure("length and radius are a capsule's; a box takes size (length = " +
                                   formatReceived(req.length) + ", radius = " + formatReceived(req.radius) + ")");
    box.name = req.name;
    box.center = toEigen(req.pose.position);
    box.orientation = orientation;
    box.half_extents = 0.5 * size;
    box.contact = contact;
    return core::Status::success();
  }
  if (!size.isZero())
    return core::Status::failure("size = " + formatVector(size) + " is a box's; a capsule takes length and radius");
  capsule.name = req.name;
  capsule.center = toEigen(req.pose.position);
  capsule.orientation = orientation;
  capsule.half_length = 0.5 * req.length;
  capsule.radius = req.radius;
  capsule.contact = contact;
  return core::Status::success();
}

core::Status parseSpringClassSelection(const std::string& name, std::optional<core::SpringClass>& spring_class)
{
  if (name == "all")
  {
    spring_class.reset();
    return core::Status::success();
  }
  core::SpringClass parsed;
  if (!core::parseSpringClass(name, parsed))
    return core::Status::failure("spring_class = " + quoteName(name) +
                                 " is not a spring class; allowed: stretch, shear, bend, all");
  spring_class = parsed;
  return core::Status::success();
}

Eigen::Vector3d toWind(const SetWind::Request& req)
{
  return toEigen(req.wind);
}

core::Status toPinSpec(const PinParticle::Request& req, const core::SpringNetworkBody& body, PinSpec& spec)
{
  // The particle: by index, or the one nearest to a finite point.
  spec.point = toEigen(req.point);
  const int count = body.particles().size();
  spec.index = req.index;
  if (spec.index == -1)
  {
    if (!spec.point.allFinite())
      return core::Status::failure("point = " + formatVector(spec.point) + " m is not finite");
    spec.index = body.nearestParticle(spec.point);
  }
  else if (spec.index < 0 || spec.index >= count)
  {
    return core::Status::failure("index = " + std::to_string(spec.index) + " is out of range: must be in [0, " +
                                 std::to_string(count - 1) + "], or -1 for the particle nearest to point");
  }

  // What it is held to.
  switch (req.target)
  {
    case PinParticle::Request::TARGET_CURRENT:
      spec.target = PinTarget::Current;
      spec.point = body.particles().position.col(spec.index);
      return core::Status::success();
    case PinParticle::Request::TARGET_POINT:
      spec.target = PinTarget::Point;
      return core::Status::success();
    case PinParticle::Request::TARGET_FRAME:
      spec.target = PinTarget::Frame;
      spec.frame = req.frame;
      spec.offset = toEigen(req.offset);
      if (spec.frame.empty()) return core::Status::failure("frame is empty: name the tf frame to follow");
      if (!spec.offset.allFinite())
        return core::Status::failure("offset = " + formatVector(spec.offset) + " m is not finite");
      return core::Status::success();
    default:
      return core::Status::failure("target = " + std::to_string(req.target) +
                                   " is out of range: 0 (current), 1 (point) or 2 (frame)");
  }
}

core::Status inRequestTerms(SpawnRequest request, core::Status status)
{
  if (status) return status;
  struct Rename
  {
    const char* core_field;
    const char* request_field;
  };
  // The spring constants and the self-collision thickness of every spring body, then what differs per request.
  static const Rename kSprings[] = {{"stretch.stiffness", "stretch_stiffness"}, {"stretch.damping", "stretch_damping"},
                                    {"shear.stiffness", "shear_stiffness"},     {"shear.damping", "shear_damping"},
                                    {"bend.stiffness", "bend_stiffness"},       {"bend.damping", "bend_damping"}};
  static const Rename kSelfCollision[] = {{"self_collision.thickness", "self_collision_thickness"}};
  static const Rename kEmitter[] = {{"particle_mass", "mass"}};
  static const Rename kCloth[] = {{"resolution[0]", "nu"}, {"resolution[1]", "nv"}};
  static const Rename kJelly[] = {{"resolution[0]", "nx"}, {"resolution[1]", "ny"}, {"resolution[2]", "nz"}};

  auto rename = [&status](const Rename& r) {
    const std::string prefix = std::string(r.core_field) + " ";
    if (status.message.compare(0, prefix.size(), prefix) != 0) return false;
    status.message = r.request_field + status.message.substr(std::string(r.core_field).size());
    return true;
  };
  for (const Rename& r : kSprings)
    if (request != SpawnRequest::Emitter && rename(r)) return status;
  for (const Rename& r : kSelfCollision)
    if (request != SpawnRequest::Emitter && rename(r)) return status;
  if (request == SpawnRequest::Emitter)
    for (const Rename& r : kEmitter)
      if (rename(r)) return status;
  if (request == SpawnRequest::Cloth)
    for (const Rename& r : kCloth)
      if (rename(r)) return status;
  if (request == SpawnRequest::Jelly)
    for (const Rename& r : kJelly)
      if (rename(r)) return status;
  return status;
}

}  // namespace ros_interface
}  // namespace particle_sim
