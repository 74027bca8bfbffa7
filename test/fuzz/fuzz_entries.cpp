#include "fuzz_entries.h"

#include <fuzzer/FuzzedDataProvider.h>  // test/fuzz/include: the same copy for clang and gcc

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>

#include "particle_sim/core/world.h"
#include "particle_sim/ros/grasps.h"
#include "particle_sim/ros/request_conversions.h"
#include "particle_sim/ros/spring_constants.h"
#include "particle_sim/scene/obj_mesh.h"
#include "particle_sim/scene/scene.h"

namespace particle_sim
{
namespace fuzz
{
namespace
{
// A fuzzed scene reads as if it were a file of config/scenes/, so that its relative mesh paths
// reach the shipped meshes.
const std::string kSceneSource = std::string(PARTICLE_SIM_SOURCE_DIR) + "/config/scenes/fuzz_input.yaml";

// Longest text field and longest list of a decoded request.
constexpr std::size_t kMaxTextLength = 200;
constexpr std::uint8_t kMaxListLength = 8;
// Most requests decoded from one input.
constexpr int kMaxRequests = 32;

// How the bytes become request fields, on top of FuzzedDataProvider: a double is 8 raw bytes from
// the front (so NaN, infinities and every exact value are reachable), a text is
// ConsumeRandomLengthString (front), integers and choices are ConsumeIntegral (back).
class RequestDecoder
{
public:
  explicit RequestDecoder(FuzzedDataProvider& in) : in_(in) {}
  bool empty() const { return in_.remaining_bytes() == 0; }

  void real(double& value)
  {
    std::vector<std::uint8_t> bytes = in_.ConsumeBytes<std::uint8_t>(sizeof(double));
    bytes.resize(sizeof(double), 0);
    std::memcpy(&value, bytes.data(), sizeof(double));
  }
  void count(std::uint32_t& value) { value = in_.ConsumeIntegral<std::uint32_t>(); }
  void integer(std::int32_t& value) { value = in_.ConsumeIntegral<std::int32_t>(); }
  void seed(std::uint64_t& value) { value = in_.ConsumeIntegral<std::uint64_t>(); }
  void flag(bool& value) { value = in_.ConsumeBool(); }
  void choice(std::uint8_t& value, std::uint8_t max) { value = in_.ConsumeIntegralInRange<std::uint8_t>(0, max); }
  void text(std::string& value) { value = in_.ConsumeRandomLengthString(kMaxTextLength); }

private:
  FuzzedDataProvider& in_;
};

// The inverse of RequestDecoder: front bytes in order, back bytes in the order they are consumed
// (ConsumeIntegral reads from the end, most significant byte first).
class RequestEncoder
{
public:
  void real(double& value)
  {
    std::uint8_t bytes[sizeof(double)];
    std::memcpy(bytes, &value, sizeof(double));
    front_.insert(front_.end(), bytes, bytes + sizeof(double));
  }
  void count(std::uint32_t& value) { back(value, sizeof(value)); }
  void integer(std::int32_t& value)
  {
    back(static_cast<std::uint64_t>(static_cast<std::int64_t>(value) - std::numeric_limits<std::int32_t>::min()),
         sizeof(value));
  }
  void seed(std::uint64_t& value) { back(value, sizeof(value)); }
  void flag(bool& value) { back(value ? 1 : 0, 1); }
  void choice(std::uint8_t& value, std::uint8_t /*max*/) { back(value, 1); }
  void text(std::string& value)
  {
    // A backslash is written twice; a backslash and another character end the text, unless it
    // is kMaxTextLength long (then the decoder stops by itself).
    const std::string kept = value.substr(0, kMaxTextLength);
    for (char c : kept)
    {
      front_.push_back(static_cast<std::uint8_t>(c));
      if (c == '\\') front_.push_back(static_cast<std::uint8_t>(c));
    }
    if (kept.size() < kMaxTextLength)
    {
      front_.push_back('\\');
      front_.push_back(';');
    }
  }

  std::vector<std::uint8_t> bytes() const
  {
    std::vector<std::uint8_t> all = front_;
    all.insert(all.end(), back_.rbegin(), back_.rend());
    return all;
  }

private:
  void back(std::uint64_t raw, std::size_t size)
  {
    for (std::size_t i = size; i-- > 0;)
      back_.push_back(static_cast<std::uint8_t>(raw >> (8 * i)));
  }

  std::vector<std::uint8_t> front_, back_;
};

// The fields of each request, in .srv order, for both directions.
template <class IO, class XYZ>
void xyz(IO& io, XYZ& v)
{
  io.real(v.x);
  io.real(v.y);
  io.real(v.z);
}

template <class IO, class T, class Field>
void list(IO& io, std::vector<T>& values, Field field)
{
  std::uint8_t size = static_cast<std::uint8_t>(std::min<std::size_t>(values.size(), kMaxListLength));
  io.choice(size, kMaxListLength);
  values.resize(size);
  for (T& value : values)
    field(value);
}

template <class IO>
void fields(IO& io, SpawnEmitter::Request& r)
{
  io.text(r.name);
  io.text(r.type);
  xyz(io, r.origin);
  io.real(r.rate);
  io.count(r.burst_count);
  io.real(r.speed);
  io.real(r.spread);
  io.real(r.lifetime);
  io.real(r.mass);
  io.count(r.max_particles);
  io.seed(r.seed);
}

template <class IO>
void fields(IO& io, RopeMaterial& m)
{
  io.text(m.preset);
  io.real(m.linear_density);
  io.real(m.axial_stiffness);
  io.real(m.bending_stiffness);
  io.real(m.damping_ratio);
}

template <class IO>
void fields(IO& io, ClothMaterial& m)
{
  io.text(m.preset);
  io.real(m.areal_density);
  io.real(m.tensile_stiffness);
  io.real(m.shear_stiffness);
  io.real(m.bending_rigidity);
  io.real(m.damping_ratio);
}

template <class IO>
void fields(IO& io, SpawnRope::Request& r)
{
  io.text(r.name);
  io.count(r.particles);
  xyz(io, r.start);
  xyz(io, r.end);
  io.real(r.mass);
  io.real(r.rest_length);
  io.real(r.stretch_stiffness);
  io.real(r.stretch_damping);
  io.real(r.bend_stiffness);
  io.real(r.bend_damping);
  list(io, r.pins, [&io](std::int32_t& pin) { io.integer(pin); });
  io.text(r.integrator);
  fields(io, r.material);
}

template <class IO>
void fields(IO& io, SpawnCloth::Request& r)
{
  io.text(r.name);
  io.text(r.model);
  xyz(io, r.origin);
  xyz(io, r.edge_u);
  xyz(io, r.edge_v);
  io.count(r.nu);
  io.count(r.nv);
  io.real(r.mass);
  io.real(r.stretch_stiffness);
  io.real(r.stretch_damping);
  io.real(r.shear_stiffness);
  io.real(r.shear_damping);
  io.real(r.bend_stiffness);
  io.real(r.bend_damping);
  list(io, r.pins, [&io](std::int32_t& pin) { io.integer(pin); });
  list(io, r.named_pins, [&io](std::string& pin) { io.text(pin); });
  io.real(r.b_u);
  io.real(r.b_v);
  io.real(r.max_strain);
  io.text(r.integrator);
  fields(io, r.material);
}

template <class IO>
void fields(IO& io, SpawnJelly::Request& r)
{
  io.text(r.name);
  xyz(io, r.origin);
  xyz(io, r.size);
  io.count(r.nx);
  io.count(r.ny);
  io.count(r.nz);
  io.real(r.mass);
  io.real(r.stretch_stiffness);
  io.real(r.stretch_damping);
  io.real(r.shear_stiffness);
  io.real(r.shear_damping);
  io.real(r.bend_stiffness);
  io.real(r.bend_damping);
  xyz(io, r.velocity);
  list(io, r.pins, [&io](std::int32_t& pin) { io.integer(pin); });
  io.real(r.max_strain);
  io.text(r.integrator);
}

template <class IO>
void fields(IO& io, PinParticle::Request& r)
{
  io.text(r.body);
  io.integer(r.index);
  io.choice(r.target, std::numeric_limits<std::uint8_t>::max());
  xyz(io, r.point);
  io.text(r.frame);
  xyz(io, r.offset);
}

template <class IO>
void fields(IO& io, SetSpringConstants::Request& r)
{
  io.text(r.body);
  io.text(r.spring_class);
  io.real(r.stiffness);
  io.real(r.damping);
}

template <class IO>
void fields(IO& io, Grasp::Request& r)
{
  io.text(r.name);
  io.text(r.body);
  io.text(r.frame);
  io.choice(r.region, std::numeric_limits<std::uint8_t>::max());
  xyz(io, r.offset);
  io.real(r.radius);
  xyz(io, r.half_extents);
  io.count(r.count);
  io.real(r.breakaway_force);
}

template <class IO>
void fields(IO& io, SpawnCollider::Request& r)
{
  io.text(r.name);
  io.text(r.shape);
  xyz(io, r.pose.position);
  io.real(r.pose.orientation.x);
  io.real(r.pose.orientation.y);
  io.real(r.pose.orientation.z);
  io.real(r.pose.orientation.w);
  xyz(io, r.size);
  io.real(r.length);
  io.real(r.radius);
  io.real(r.restitution);
  io.real(r.friction);
  io.text(r.frame);
}

// The node's parameters (scene_path aside: the fuzzed node starts with an empty world).
template <class IO>
void fields(IO& io, ros_interface::NodeSettings& s)
{
  io.real(s.rate);
  io.real(s.dt);
  io.real(s.real_time_factor);
  io.flag(s.paused);
  io.text(s.frame_id);
  io.text(s.parent_frame_id);
  list(io, s.frame_offset, [&io](double& v) { io.real(v); });
  io.flag(s.publish_clock);
  io.real(s.particle_size);
  io.integer(s.max_particles_per_body);
  io.real(s.status_period);
  io.flag(s.color_by_strain);
  io.real(s.strain_color_max);
  io.real(s.diagnostic_period);
  io.real(s.diagnostic_max_strain);
  io.text(s.rope_material);
  io.text(s.cloth_material);
}

template <class IO>
void fields(IO& io, Request& r)
{
  auto service = static_cast<std::uint8_t>(r.service);
  io.choice(service, static_cast<std::uint8_t>(Request::Service::Count) - 1);
  r.service = static_cast<Request::Service>(service);
  switch (r.service)
  {
    case Request::Service::SpawnEmitter:
      return fields(io, r.spawn_emitter);
    case Request::Service::SpawnRope:
      return fields(io, r.spawn_rope);
    case Request::Service::SpawnCloth:
      return fields(io, r.spawn_cloth);
    case Request::Service::SpawnJelly:
      return fields(io, r.spawn_jelly);
    case Request::Service::SetWind:
      return xyz(io, r.set_wind.wind);
    case Request::Service::PinParticle:
      return fields(io, r.pin_particle);
    case Request::Service::UnpinParticle:
      io.text(r.body);
      return io.integer(r.index);
    case Request::Service::SetSpringConstants:
      return fields(io, r.set_spring_constants);
    case Request::Service::RemoveBody:
      return io.text(r.body);
    case Request::Service::Step: {
      // Steps in [1, kMaxSteps]: the choice is steps − 1.
      std::uint8_t extra = static_cast<std::uint8_t>(std::clamp<std::uint32_t>(r.steps, 1, kMaxSteps) - 1);
      io.choice(extra, kMaxSteps - 1);
      r.steps = extra + 1u;
      return;
    }
    case Request::Service::Grasp:
      return fields(io, r.grasp);
    case Request::Service::Release:
      return io.text(r.grasp_name);
    case Request::Service::SpawnCollider:
      return fields(io, r.spawn_collider);
    case Request::Service::RemoveCollider:
      return io.text(r.collider);
    case Request::Service::Reset:
    case Request::Service::Count:
      return;
  }
}

// What the node does with one request (src/ros/sim_node.cpp), without a master: the conversion,
// then the world. A tf frame a pin follows is taken to be at the sim frame's origin.
// Caps the solver work of an integrator (kMaxCgIterations, kMaxSubsteps).
void capWork(core::IntegratorDef& integrator)
{
  integrator.cg_max_iterations = std::min(integrator.cg_max_iterations, kMaxCgIterations);
  integrator.max_substeps = std::min(integrator.max_substeps, kMaxSubsteps);
}

RequestAnswer serve(const Request& r, const scene::SceneDef& scene, const core::IntegratorDef& default_integrator,
                    const ros_interface::NodeSettings& settings, core::World& world, ros_interface::Grasps& grasps)
{
  using namespace ros_interface;
  auto answer = [](const char* service, const core::Status& status) {
    return RequestAnswer{service, status.ok, status.message};
  };
  switch (r.service)
  {
    case Request::Service::SpawnEmitter: {
      core::EmitterDef def;
      if (core::Status s = toEmitterDef(r.spawn_emitter, world.definition().seed, def); !s)
        return answer("spawn_emitter", s);
      return answer("spawn_emitter", inRequestTerms(SpawnRequest::Emitter, world.addEmitter(def)));
    }
    case Request::Service::SpawnRope: {
      core::RopeDef def;
      if (core::Status s = toRopeDef(r.spawn_rope, default_integrator, def, settings.rope_material); !s)
        return answer("spawn_rope", s);
      return answer("spawn_rope", inRequestTerms(SpawnRequest::Rope, world.addRope(def)));
    }
    case Request::Service::SpawnCloth: {
      core::ClothGridDef def;
      if (core::Status s = toClothGridDef(r.spawn_cloth, default_integrator, def, settings.cloth_material); !s)
        return answer("spawn_cloth", s);
      return answer("spawn_cloth", inRequestTerms(SpawnRequest::Cloth, world.addClothGrid(def)));
    }
    case Request::Service::SpawnJelly: {
      core::JellyDef def;
      if (core::Status s = toJellyDef(r.spawn_jelly, default_integrator, def); !s) return answer("spawn_jelly", s);
      return answer("spawn_jelly", inRequestTerms(SpawnRequest::Jelly, world.addJelly(def)));
    }
    case Request::Service::SetWind:
      return answer("set_wind", world.setWind(toWind(r.set_wind)));
    case Request::Service::PinParticle: {
      core::SpringNetworkBody* body = world.findSpringBody(r.pin_particle.body);
      if (!body) return answer("pin_particle", core::Status::failure("no such body"));
      PinSpec spec;
      if (core::Status s = toPinSpec(r.pin_particle, *body, spec); !s) return answer("pin_particle", s);
      if (spec.target == PinTarget::Frame) spec.point = spec.offset;
      return answer("pin_particle", body->pin(spec.index, spec.point));
    }
    case Request::Service::UnpinParticle: {
      core::SpringNetworkBody* body = world.findSpringBody(r.body);
      if (!body) return answer("unpin_particle", core::Status::failure("no such body"));
      return answer("unpin_particle", body->unpin(r.index));
    }
    case Request::Service::SetSpringConstants: {
      const SetSpringConstants::Request& q = r.set_spring_constants;
      return answer("set_spring_constants",
                    applySpringConstants(world, q.body, q.spring_class, q.stiffness, q.damping));
    }
    case Request::Service::RemoveBody: {
      const core::Status removed = world.removeBody(r.body);
      if (removed) grasps.forgetBody(r.body);
      return answer("remove_body", removed);
    }
    case Request::Service::Step: {
      // A tick: the steps, then the grasps' forces and breakaways.
      for (std::uint32_t i = 0; i < r.steps; ++i)
        scene::stepScene(scene, world);
      std::vector<HeldParticle> let_go;
      grasps.update(
          world, [](const std::string&, Eigen::Isometry3d&) { return false; }, world.simTime(), let_go);
      return answer("step", core::Status::success());
    }
    case Request::Service::Grasp: {
      GraspSpec spec;
      if (core::Status s = toGraspSpec(r.grasp, spec); !s) return answer("grasp", s);
      return answer("grasp", grasps.grasp(world, spec, Eigen::Isometry3d::Identity()));
    }
    case Request::Service::Release: {
      std::vector<HeldParticle> let_go;
      return answer("release", grasps.release(world, r.grasp_name, let_go));
    }
    case Request::Service::SpawnCollider: {
      bool is_box = true;
      core::BoxColliderDef box;
      core::CapsuleColliderDef capsule;
      if (core::Status s = toColliderDef(r.spawn_collider, is_box, box, capsule); !s)
        return answer("spawn_collider", s);
      return answer("spawn_collider", is_box ? world.addCollider(box) : world.addCollider(capsule));
    }
    case Request::Service::RemoveCollider:
      return answer("remove_collider", world.removeCollider(r.collider));
    case Request::Service::Reset:
    case Request::Service::Count:
      world.reset();
      grasps.clear();
      return answer("reset", core::Status::success());
  }
  return answer("?", core::Status::failure("unknown service"));
}
}  // namespace

int runSceneYaml(const std::uint8_t* data, std::size_t size)
{
  scene::SceneDef scene;
  if (!scene::parseScene(std::string(reinterpret_cast<const char*>(data), size), kSceneSource, scene)) return 0;
  scene.world.max_particles_per_body = std::min(scene.world.max_particles_per_body, kMaxParticlesPerBody);
  scene::editIntegrators(scene, capWork);
  std::unique_ptr<core::World> world;
  if (!scene::buildWorld(scene, world)) return 0;
  for (int i = 0; i < kMaxSteps; ++i)
    scene::stepScene(scene, *world);

  // A scene that builds is written back as YAML that reads again (scene.h: toYaml).
  scene::SceneDef again;
  if (core::Status s = scene::parseScene(scene::toYaml(scene), kSceneSource, again); !s)
  {
    std::fprintf(stderr, "toYaml of a valid scene does not read back: %s\n", s.message.c_str());
    std::abort();
  }
  return 0;
}

int runObjMesh(const std::uint8_t* data, std::size_t size)
{
  scene::ObjMesh mesh;
  if (!scene::parseObj(std::string(reinterpret_cast<const char*>(data), size), "fuzz_input.obj", mesh)) return 0;
  core::WorldDef world_def;
  world_def.max_particles_per_body = kMaxParticlesPerBody;
  capWork(world_def.integrator);
  core::World world(world_def);
  // As a scene's mesh cloth builds it: springs always, Baraff–Witkin when there are uvs.
  for (core::ClothModel model : {core::ClothModel::Springs, core::ClothModel::BaraffWitkin})
  {
    if (model == core::ClothModel::BaraffWitkin && mesh.uvs.empty()) continue;
    core::MeshClothDef def(model);
    def.name = model == core::ClothModel::Springs ? "mesh_springs" : "mesh_baraff_witkin";
    def.vertices = mesh.vertices;
    def.triangles = mesh.triangles;
    def.uvs = mesh.uvs;
    (void)world.addMeshCloth(def);
  }
  for (int i = 0; i < kMaxSteps; ++i)
    world.step();
  return 0;
}

std::vector<RequestAnswer> answerRequests(const std::uint8_t* data, std::size_t size)
{
  FuzzedDataProvider in(data, size);
  RequestDecoder decoder(in);
  std::vector<RequestAnswer> answers;

  // The node's start: parameters checked, then the (empty) scene's world with ~dt and
  // ~max_particles_per_body (src/ros/sim_node.cpp, initialize).
  ros_interface::NodeSettings settings;
  fields(decoder, settings);
  if (core::Status s = ros_interface::validate(settings); !s)
  {
    answers.push_back({"settings", false, s.message});
    return answers;
  }
  scene::SceneDef scene;
  if (settings.dt != 0.0) scene.world.dt = settings.dt;
  if (settings.max_particles_per_body != 0) scene.world.max_particles_per_body = settings.max_particles_per_body;
  scene.world.max_particles_per_body = std::min(scene.world.max_particles_per_body, kMaxParticlesPerBody);
  capWork(scene.world.integrator);
  std::unique_ptr<core::World> world;
  if (core::Status s = scene::buildWorld(scene, world); !s)
  {
    answers.push_back({"settings", false, s.message});
    return answers;
  }
  answers.push_back({"settings", true, ""});
  const core::IntegratorDef default_integrator = world->definition().integrator;

  ros_interface::Grasps grasps;
  for (int i = 0; i < kMaxRequests && !decoder.empty(); ++i)
  {
    Request request;
    fields(decoder, request);
    answers.push_back(serve(request, scene, default_integrator, settings, *world, grasps));
  }
  return answers;
}

int runRequests(const std::uint8_t* data, std::size_t size)
{
  (void)answerRequests(data, size);
  return 0;
}

std::vector<std::uint8_t> encodeRequests(const ros_interface::NodeSettings& settings,
                                         const std::vector<Request>& requests)
{
  RequestEncoder encoder;
  ros_interface::NodeSettings s = settings;
  fields(encoder, s);
  for (Request r : requests)
    fields(encoder, r);
  return encoder.bytes();
}

std::vector<RequestSeed> requestSeeds()
{
  auto point = [](double x, double y, double z) {
    geometry_msgs::Point p;
    p.x = x;
    p.y = y;
    p.z = z;
    return p;
  };
  auto vector = [](double x, double y, double z) {
    geometry_msgs::Vector3 v;
    v.x = x;
    v.y = y;
    v.z = z;
    return v;
  };
  using Service = Request::Service;
  auto request = [](Service service) {
    Request r;
    r.service = service;
    return r;
  };

  // README, "Services": the calls of the example session, in order (~step of 100 steps is cut to
  // kMaxSteps; pause and unpause do not reach the world).
  Request jet = request(Service::SpawnEmitter);
  jet.spawn_emitter.name = "jet";
  jet.spawn_emitter.type = "fountain";
  jet.spawn_emitter.origin = point(1, 0, 0);
  jet.spawn_emitter.rate = 200;
  jet.spawn_emitter.speed = 8;
  jet.spawn_emitter.spread = 1;
  Request bad = request(Service::SpawnEmitter);
  bad.spawn_emitter.name = "bad";
  bad.spawn_emitter.type = "fountain";
  bad.spawn_emitter.rate = -5;
  Request step = request(Service::Step);
  step.steps = kMaxSteps;
  Request line = request(Service::SpawnRope);
  line.spawn_rope.name = "line";
  line.spawn_rope.particles = 20;
  line.spawn_rope.start = point(0, 1, 2);
  line.spawn_rope.end = point(2, 1, 2);
  line.spawn_rope.mass = 0.2;
  line.spawn_rope.stretch_stiffness = 1000;
  line.spawn_rope.stretch_damping = 0.5;
  line.spawn_rope.pins = {0};
  Request pin_point = request(Service::PinParticle);
  pin_point.pin_particle.body = "line";
  pin_point.pin_particle.index = 19;
  pin_point.pin_particle.target = PinParticle::Request::TARGET_POINT;
  pin_point.pin_particle.point = point(2, 1, 2);
  Request pin_frame = request(Service::PinParticle);
  pin_frame.pin_particle.body = "line";
  pin_frame.pin_particle.index = 10;
  pin_frame.pin_particle.target = PinParticle::Request::TARGET_FRAME;
  pin_frame.pin_particle.frame = "gripper";
  pin_frame.pin_particle.offset = vector(0, 0, -0.05);
  Request springs = request(Service::SetSpringConstants);
  springs.set_spring_constants.body = "line";
  springs.set_spring_constants.spring_class = "stretch";
  springs.set_spring_constants.stiffness = 200;
  springs.set_spring_constants.damping = 0.1;

  // The other services, each spawn with the .srv defaults (fields left at 0 or empty).
  Request cloth = request(Service::SpawnCloth);
  cloth.spawn_cloth.name = "flag";
  cloth.spawn_cloth.edge_u = vector(1, 0, 0);
  cloth.spawn_cloth.edge_v = vector(0, 0, -1);
  cloth.spawn_cloth.named_pins = {"corner_00", "corner_10"};
  Request bw_cloth = cloth;
  bw_cloth.spawn_cloth.name = "bw_flag";
  bw_cloth.spawn_cloth.model = "baraff_witkin";
  Request jelly = request(Service::SpawnJelly);
  jelly.spawn_jelly.name = "jelly";
  jelly.spawn_jelly.origin = point(0, 0, 1);
  jelly.spawn_jelly.size = vector(0.5, 0.5, 0.5);
  Request wind = request(Service::SetWind);
  wind.set_wind.wind = vector(2, 0, 0);
  Request unpin = request(Service::UnpinParticle);
  unpin.body = "line";
  unpin.index = 0;
  Request remove = request(Service::RemoveBody);
  remove.body = "line";

  // Materials (README "Services", Materials): a rope and a cloth by preset, a preset with a value
  // replaced, and a cloth by value.
  Request nylon = request(Service::SpawnRope);
  nylon.spawn_rope.name = "nylon";
  nylon.spawn_rope.start = point(0, 0, 2);
  nylon.spawn_rope.end = point(2, 0, 2);
  nylon.spawn_rope.pins = {0};
  nylon.spawn_rope.material.preset = "nylon_rope";
  Request heavy_nylon = nylon;
  heavy_nylon.spawn_rope.name = "heavy_nylon";
  heavy_nylon.spawn_rope.material.linear_density = 0.5;
  Request cotton = cloth;
  cotton.spawn_cloth.name = "cotton";
  cotton.spawn_cloth.material.preset = "cotton";
  Request towel = bw_cloth;
  towel.spawn_cloth.name = "towel";
  towel.spawn_cloth.material.areal_density = 0.4;
  towel.spawn_cloth.material.tensile_stiffness = 8000;
  towel.spawn_cloth.material.shear_stiffness = 40;
  towel.spawn_cloth.material.bending_rigidity = 1e-4;

  // A grasp of the rope's end near the origin (the fuzzed gripper frame sits there) that breaks away,
  // and one released by name.
  Request hand = request(Service::Grasp);
  hand.grasp.name = "hand";
  hand.grasp.frame = "gripper";
  hand.grasp.region = Grasp::Request::REGION_SPHERE;
  hand.grasp.radius = 0.3;
  hand.grasp.breakaway_force = 0.5;
  Request pinch = hand;
  pinch.grasp.name = "pinch";
  pinch.grasp.region = Grasp::Request::REGION_NEAREST;
  pinch.grasp.count = 3;
  pinch.grasp.breakaway_force = 0.0;
  Request let_go = request(Service::Release);
  let_go.grasp_name = "pinch";
  Request low = line;
  low.spawn_rope.name = "low";
  low.spawn_rope.start = point(0, 0, 0.1);
  low.spawn_rope.end = point(1, 0, 0.1);

  // A table under the rope, a finger across it, the table removed.
  Request table = request(Service::SpawnCollider);
  table.spawn_collider.name = "table";
  table.spawn_collider.shape = SpawnCollider::Request::SHAPE_BOX;
  table.spawn_collider.pose.position = point(1, 0, 1.5);
  table.spawn_collider.size = vector(2.5, 1, 0.1);
  table.spawn_collider.friction = 0.5;
  Request finger = request(Service::SpawnCollider);
  finger.spawn_collider.name = "finger";
  finger.spawn_collider.shape = SpawnCollider::Request::SHAPE_CAPSULE;
  finger.spawn_collider.pose.position = point(1, 0, 2.05);
  finger.spawn_collider.pose.orientation.z = std::sqrt(0.5);
  finger.spawn_collider.pose.orientation.w = std::sqrt(0.5);
  finger.spawn_collider.length = 0.2;
  finger.spawn_collider.radius = 0.02;
  Request no_table = request(Service::RemoveCollider);
  no_table.collider = "table";

  return {{"readme_session", {jet, bad, step, line, pin_point, pin_frame, springs, step}},
          {"colliders", {line, table, finger, step, step, no_table, step}},
          {"grasp_release", {low, hand, step, step, pinch, step, let_go, step}},
          {"spawn_emitter", {jet, step}},
          {"spawn_rope", {line, step}},
          {"spawn_cloth", {cloth, step}},
          {"spawn_cloth_baraff_witkin", {bw_cloth, step}},
          {"spawn_jelly", {jelly, step}},
          {"set_wind", {cloth, wind, step}},
          {"pin_unpin", {line, pin_point, step, unpin, step}},
          {"remove_reset", {line, jet, step, remove, request(Service::Reset), step}},
          {"spawn_materials", {nylon, heavy_nylon, cotton, towel, step}}};
}

const std::vector<Target>& targets()
{
  static const std::vector<Target> kTargets = {
      {"scene_yaml", runSceneYaml}, {"obj_mesh", runObjMesh}, {"requests", runRequests}};
  return kTargets;
}

}  // namespace fuzz
}  // namespace particle_sim
