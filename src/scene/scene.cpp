#include "particle_sim/scene/scene.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <set>
#include <sstream>

#include "map_reader.h"
#include "particle_sim/core/validation.h"
#include "particle_sim/scene/obj_mesh.h"

namespace particle_sim
{
namespace scene
{
namespace
{
// Fails at `reader`'s node with a core validation message, prefixed by the entry's path.
void check(const MapReader& reader, const std::string& prefix, const Status& status)
{
  if (!status) reader.fail(reader.node(), prefix + status.message);
}

void readContact(MapReader& reader, core::ContactDef& contact)
{
  reader.read("restitution", contact.restitution);
  reader.read("friction", contact.friction);
  reader.read("bounce_speed", contact.bounce_speed);
}

// The integrator keys, read at world level (the default) and per body (an override).
void readIntegrator(MapReader& reader, core::IntegratorDef& integrator)
{
  std::string name;
  reader.read("integrator", name);
  if (reader.has("integrator"))
  {
    if (!core::parseIntegratorType(name, integrator.type))
      reader.fail(reader.node()["integrator"], reader.field("integrator") + " = " + core::quoteReceived(name) +
                                                   " is not an integrator; allowed: " + core::integratorTypeNames());
  }
  reader.read("verlet_damping", integrator.verlet_damping);
  reader.read("cg_tolerance", integrator.cg_tolerance);
  reader.read("cg_max_iterations", integrator.cg_max_iterations);
  reader.read("max_substeps", integrator.max_substeps);
}

void readWorld(const YAML::Node& node, const std::string& source, SceneDef& scene)
{
  core::WorldDef& world = scene.world;
  MapReader reader(node, "world", source);
  readIntegrator(reader, world.integrator);
  reader.read("gravity", world.gravity);
  reader.read("dt", world.dt);
  reader.read("global_damping", world.global_damping);
  reader.read("seed", world.seed);
  reader.read("max_particles_per_body", world.max_particles_per_body);

  if (const YAML::Node ground = reader.child("ground"))
  {
    MapReader g(ground, "world.ground", source);
    g.read("enabled", world.ground.enabled);
    g.read("height", world.ground.height);
    readContact(g, world.ground.contact);
    g.finish();
  }
  if (const YAML::Node spheres = reader.child("spheres"))
  {
    if (!spheres.IsSequence()) reader.fail(spheres, "world.spheres must be a list of spheres");
    for (std::size_t i = 0; i < spheres.size(); ++i)
    {
      MapReader s(spheres[i], "world.spheres[" + std::to_string(i) + "]", source);
      core::SphereColliderDef sphere;
      sphere.name = "sphere_" + std::to_string(i);
      s.read("name", sphere.name);
      s.require("center", sphere.center);
      s.require("radius", sphere.radius);
      readContact(s, sphere.contact);
      std::string frame;
      s.read("frame", frame);
      if (!frame.empty()) scene.frame_spheres.push_back({sphere.name, frame});
      s.finish();
      check(s, "", core::validate(sphere));
      world.spheres.push_back(sphere);
    }
  }
  if (const YAML::Node air = reader.child("air"))
  {
    MapReader a(air, "world.air", source);
    a.read("drag", world.air.drag);
    a.read("wind", world.air.wind);
    a.finish();
  }
  reader.finish();
  check(reader, "world.", core::validate(world));
}

void readFrames(const YAML::Node& node, const std::string& source, SceneDef& scene)
{
  if (!node.IsSequence()) throw SceneError{location(source, node) + "frames must be a list of frames"};
  for (std::size_t i = 0; i < node.size(); ++i)
  {
    MapReader reader(node[i], "frames[" + std::to_string(i) + "]", source);
    ScriptedFrameDef frame;
    reader.require("name", frame.name);
    reader.read("center", frame.center);
    reader.read("radius", frame.radius);
    reader.read("period", frame.period);
    reader.read("phase", frame.phase);
    reader.finish();
    if (frame.name.empty()) reader.fail(node[i], reader.field("name") + " is empty");
    check(reader, reader.field(""), core::checkFinite("center", frame.center));
    check(reader, reader.field(""), core::checkMin("radius", frame.radius, 0.0));
    check(reader, reader.field(""), core::checkPositive("period", frame.period));
    check(reader, reader.field(""), core::checkFinite("phase", frame.phase));
    if (findFrame(scene, frame.name))
      reader.fail(node[i], reader.field("name") + " = " + core::quoteReceived(frame.name) + " is already taken");
    scene.frames.push_back(frame);
  }
}

core::EmitterDef readEmitter(MapReader& reader, const core::WorldDef& world)
{
  core::EmitterDef def;
  reader.require("name", def.name);

  std::string type;
  reader.require("type", type);
  if (!core::parseEmitterType(type, def.type))
    reader.fail(reader.node()["type"], reader.field("type") + " = " + core::quoteReceived(type) +
                                           " is not an emitter type; allowed: " + core::emitterTypeNames());
  // The waterfall pours over an edge: no vertical speed unless the scene asks for one.
  if (def.type == core::EmitterType::Waterfall) def.speed = 0.0;
  // An explosion is one burst unless the scene asks for a rate.
  if (def.type == core::EmitterType::Explosion)
  {
    def.rate = 0.0;
    def.burst_count = 500;
  }

  def.seed = core::deriveSeed(world.seed, def.name);
  reader.read("origin", def.origin);
  reader.read("rate", def.rate);
  reader.read("burst_count", def.burst_count);
  reader.read("speed", def.speed);
  reader.read("spread", def.spread);
  reader.read("lifetime", def.lifetime);
  reader.read("particle_mass", def.particle_mass);
  reader.read("max_particles", def.max_particles);
  reader.read("seed", def.seed);
  reader.read("contact_thickness", def.contact_thickness);
  reader.finish();
  check(reader, reader.field(""), core::validate(def, world.max_particles_per_body, world.dt));
  return def;
}

// Reads {stiffness, damping} of one spring class.
void readSpringConstants(MapReader& parent, const std::string& key, double& stiffness, double& damping,
                         const std::string& source)
{
  const YAML::Node node = parent.child(key);
  if (!node) return;
  MapReader reader(node, parent.field(key), source);
  reader.read("stiffness", stiffness);
  reader.read("damping", damping);
  reader.finish();
}

std::vector<int> readIndexList(MapReader& reader, const std::string& key)
{
  std::vector<int> values;
  const YAML::Node node = reader.child(key);
  if (!node) return values;
  if (!node.IsSequence()) reader.fail(node, reader.field(key) + " must be a list of particle indices");
  for (std::size_t i = 0; i < node.size(); ++i)
  {
    int value = 0;
    if (!node[i].IsScalar() || !YAML::convert<int>::decode(node[i], value))
      reader.fail(node[i], reader.field(key) + "[" + std::to_string(i) + "] must be an integer particle index");
    values.push_back(value);
  }
  return values;
}

core::RopeDef readRope(MapReader& reader, const core::WorldDef& world, const std::string& source)
{
  core::RopeDef def;
  def.integrator = world.integrator;
  reader.require("name", def.name);
  reader.read("particles", def.particles);
  reader.read("start", def.start);
  reader.read("end", def.end);
  reader.read("mass", def.mass);
  reader.read("rest_length", def.rest_length);
  readSpringConstants(reader, "stretch", def.stretch_stiffness, def.stretch_damping, source);
  readSpringConstants(reader, "bend", def.bend_stiffness, def.bend_damping, source);
  def.pins = readIndexList(reader, "pins");
  readIntegrator(reader, def.integrator);
  reader.read("contact_thickness", def.contact_thickness);
  reader.finish();
  check(reader, reader.field(""), core::validate(def, world.max_particles_per_body));
  return def;
}

core::SpringNetworkDef readSpringNetwork(MapReader& reader, const core::WorldDef& world, const std::string& source)
{
  core::SpringNetworkDef def;
  def.integrator = world.integrator;
  reader.require("name", def.name);

  const YAML::Node particles = reader.child("particles");
  if (!particles || !particles.IsSequence() || particles.size() == 0)
    reader.fail(particles ? particles : reader.node(),
                reader.field("particles") + " must be a non-empty list of {position, mass, velocity}");
  bool any_velocity = false;
  std::vector<Eigen::Vector3d> velocities;
  for (std::size_t i = 0; i < particles.size(); ++i)
  {
    MapReader p(particles[i], reader.field("particles") + "[" + std::to_string(i) + "]", source);
    Eigen::Vector3d position = Eigen::Vector3d::Zero(), velocity = Eigen::Vector3d::Zero();
    double mass = 0.1;
    p.require("position", position);
    p.read("mass", mass);
    any_velocity = any_velocity || p.has("velocity");
    p.read("velocity", velocity);
    p.finish();
    def.positions.push_back(position);
    def.masses.push_back(mass);
    velocities.push_back(velocity);
  }
  if (any_velocity) def.velocities = velocities;

  if (const YAML::Node springs = reader.child("springs"))
  {
    if (!springs.IsSequence()) reader.fail(springs, reader.field("springs") + " must be a list of springs");
    for (std::size_t k = 0; k < springs.size(); ++k)
    {
      MapReader s(springs[k], reader.field("springs") + "[" + std::to_string(k) + "]", source);
      std::vector<int> ends = readIndexList(s, "particles");
      if (ends.size() != 2) s.fail(springs[k], s.field("particles") + " must be two particle indices [i, j]");
      core::Spring spring;
      spring.i = ends[0];
      spring.j = ends[1];
      // The rest length is a number [m] or "initial": the distance at the start.
      const YAML::Node rest_node = s.child("rest_length");
      const bool initial_rest = !rest_node || (rest_node.IsScalar() && rest_node.Scalar() == "initial");
      if (!initial_rest) s.read("rest_length", spring.rest_length);
      s.read("stiffness", spring.stiffness);
      s.read("damping", spring.damping);
      if (s.has("class"))
      {
        std::string name;
        s.read("class", name);
        if (!core::parseSpringClass(name, spring.spring_class))
          s.fail(springs[k]["class"], s.field("class") + " = " + core::quoteReceived(name) +
                                          " is not a spring class; allowed: stretch, shear, bend");
      }
      s.finish();
      const int n = static_cast<int>(def.positions.size());
      if (initial_rest && spring.i >= 0 && spring.i < n && spring.j >= 0 && spring.j < n)
        spring.rest_length = (def.positions[spring.j] - def.positions[spring.i]).norm();
      def.springs.push_back(spring);
    }
  }
  def.pins = readIndexList(reader, "pins");
  readIntegrator(reader, def.integrator);
  reader.read("contact_thickness", def.contact_thickness);
  reader.finish();
  check(reader, reader.field(""), core::validate(def, world.max_particles_per_body));
  return def;
}

// Pins given by index (negative counts from the end) or, where `names` is given, by name.
void readPins(MapReader& reader, std::vector<int>& indices, std::vector<std::string>* names)
{
  const YAML::Node node = reader.child("pins");
  if (!node) return;
  if (!node.IsSequence()) reader.fail(node, reader.field("pins") + " must be a list of particle indices");
  for (std::size_t i = 0; i < node.size(); ++i)
  {
    int value = 0;
    if (node[i].IsScalar() && YAML::convert<int>::decode(node[i], value))
      indices.push_back(value);
    else if (names && node[i].IsScalar())
      names->push_back(node[i].Scalar());
    else
      reader.fail(node[i], reader.field("pins") + "[" + std::to_string(i) + "] must be an integer particle index" +
                               (names ? std::string(" or a pin name") : std::string()));
  }
}

void readStrainLimit(MapReader& reader, core::StrainLimitDef& limit)
{
  reader.read("max_strain", limit.max_strain);
  reader.read("strain_iterations", limit.iterations);
}

// Reads one entry of `frame_pins`, resolving its pin (a name of a grid cloth or an index) to indices.
struct FramePinEntry
{
  YAML::Node node;
  std::string pin;
  std::string frame;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
};

std::vector<FramePinEntry> readFramePinEntries(MapReader& reader, const std::string& source)
{
  std::vector<FramePinEntry> entries;
  const YAML::Node node = reader.child("frame_pins");
  if (!node) return entries;
  if (!node.IsSequence()) reader.fail(node, reader.field("frame_pins") + " must be a list of {pin, frame, offset}");
  for (std::size_t i = 0; i < node.size(); ++i)
  {
    MapReader entry(node[i], reader.field("frame_pins") + "[" + std::to_string(i) + "]", source);
    FramePinEntry e;
    e.node = node[i];
    entry.require("pin", e.pin);
    entry.require("frame", e.frame);
    entry.read("offset", e.offset);
    entry.finish();
    check(entry, entry.field(""), core::checkFinite("offset", e.offset));
    entries.push_back(e);
  }
  return entries;
}

// Turns frame pin entries into FramePinDefs of body `body` with `count` particles, adding each
// pinned index to `pins`. `resolve_name` maps a pin name to indices (false: unknown name).
template <typename ResolveName>
void addFramePins(MapReader& reader, const std::vector<FramePinEntry>& entries, const std::string& body, int count,
                  ResolveName resolve_name, std::vector<int>& pins, SceneDef& scene)
{
  for (const FramePinEntry& e : entries)
  {
    std::vector<int> indices;
    int index = 0;
    if (YAML::convert<int>::decode(e.node["pin"], index))
      indices.push_back(index < 0 ? count + index : index);
    else if (!resolve_name(e.pin, indices))
      reader.fail(e.node["pin"], reader.field("frame_pins") + ": pin = " + core::quoteReceived(e.pin) +
                                     " is neither an index nor a pin name");
    for (int i : indices)
    {
      if (i < 0 || i >= count)
        reader.fail(e.node["pin"], reader.field("frame_pins") + ": pin = " + e.pin + " is out of range: the body has " +
                                       std::to_string(count) + " particles");
      if (std::find(pins.begin(), pins.end(), i) == pins.end()) pins.push_back(i);
      scene.frame_pins.push_back({body, i, e.frame, e.offset});
    }
  }
}

void readClothConstants(MapReader& reader, core::SpringConstants& stretch, core::SpringConstants* shear,
                        core::SpringConstants& bend, const std::string& source)
{
  readSpringConstants(reader, "stretch", stretch.stiffness, stretch.damping, source);
  if (shear) readSpringConstants(reader, "shear", shear->stiffness, shear->damping, source);
  readSpringConstants(reader, "bend", bend.stiffness, bend.damping, source);
}

// A cloth's contact_thickness: a number [m], or "auto" (also when absent) for
// core::clothContactThickness(). True when a number was given.
bool readContactThickness(MapReader& reader, double& thickness)
{
  const YAML::Node node = reader.child("contact_thickness");
  if (!node || (node.IsScalar() && node.Scalar() == "auto")) return false;
  reader.read("contact_thickness", thickness);
  return true;
}

std::string resolvePath(const std::string& source, const std::string& path)
{
  const std::filesystem::path p(path);
  if (p.is_absolute()) return path;
  return (std::filesystem::path(source).parent_path() / p).string();
}

// What grid and mesh cloth start with: name, model with its default constants, the world's
// integrator and, for a Baraff–Witkin cloth, its rest stretch b_u, b_v.
template <typename ClothDef>
void startCloth(MapReader& reader, const std::string& name, core::ClothModel model,
                const core::IntegratorDef& integrator, ClothDef& def)
{
  def = ClothDef(model);  // the model's default constants
  def.name = name;
  def.integrator = integrator;
  if (model != core::ClothModel::BaraffWitkin) return;
  reader.read("b_u", def.b_u);
  reader.read("b_v", def.b_v);
}

BodyDef readCloth(MapReader& reader, SceneDef& scene, const std::string& source)
{
  const core::WorldDef& world = scene.world;
  std::string name, model_name = "springs";
  reader.require("name", name);
  reader.read("model", model_name);
  core::ClothModel model = core::ClothModel::Springs;
  if (!core::parseClothModel(model_name, model))
    reader.fail(reader.node()["model"], reader.field("model") + " = " + core::quoteReceived(model_name) +
                                            " is not a cloth model; allowed: springs, baraff_witkin");
  const bool baraff_witkin = model == core::ClothModel::BaraffWitkin;
  const std::vector<FramePinEntry> frame_pins = readFramePinEntries(reader, source);

  // A triangle mesh (an OBJ file, or vertices and triangles inline) or a regular grid.
  if (reader.has("mesh") || reader.has("vertices"))
  {
    core::MeshClothDef def;
    startCloth(reader, name, model, world.integrator, def);
    if (reader.has("mesh"))
    {
      std::string file;
      reader.read("mesh", file);
      ObjMesh mesh;
      if (Status s = loadObjFile(resolvePath(source, file), mesh); !s) reader.fail(reader.node()["mesh"], s.message);
      double scale = 1.0;
      Eigen::Vector3d origin = Eigen::Vector3d::Zero();
      reader.read("scale", scale);
      reader.read("origin", origin);
      check(reader, reader.field(""), core::checkPositive("scale", scale));
      check(reader, reader.field(""), core::checkFinite("origin", origin));
      for (const Eigen::Vector3d& v : mesh.vertices)
        def.vertices.push_back(origin + scale * v);
      def.triangles = mesh.triangles;
      def.uvs = mesh.uvs;
    }
    else
    {
      const YAML::Node vertices = reader.child("vertices"), triangles = reader.child("triangles");
      for (std::size_t i = 0; vertices.IsSequence() && i < vertices.size(); ++i)
      {
        if (!vertices[i].IsSequence() || vertices[i].size() != 3)
          reader.fail(vertices[i], reader.field("vertices") + "[" + std::to_string(i) + "] must be [x, y, z]");
        def.vertices.emplace_back(vertices[i][0].as<double>(), vertices[i][1].as<double>(),
                                  vertices[i][2].as<double>());
      }
      for (std::size_t i = 0; triangles && triangles.IsSequence() && i < triangles.size(); ++i)
      {
        if (!triangles[i].IsSequence() || triangles[i].size() != 3)
          reader.fail(triangles[i], reader.field("triangles") + "[" + std::to_string(i) + "] must be [i, j, k]");
        def.triangles.emplace_back(triangles[i][0].as<int>(), triangles[i][1].as<int>(), triangles[i][2].as<int>());
      }
      const YAML::Node uvs = reader.child("uvs");
      for (std::size_t i = 0; uvs && uvs.IsSequence() && i < uvs.size(); ++i)
      {
        if (!uvs[i].IsSequence() || uvs[i].size() != 2)
          reader.fail(uvs[i], reader.field("uvs") + "[" + std::to_string(i) + "] must be [u, v]");
        def.uvs.emplace_back(uvs[i][0].as<double>(), uvs[i][1].as<double>());
      }
    }
    reader.read("mass", def.mass);
    readClothConstants(reader, def.stretch, baraff_witkin ? &def.shear : nullptr, def.bend, source);
    readPins(reader, def.pins, nullptr);
    readStrainLimit(reader, def.strain_limit);
    readIntegrator(reader, def.integrator);
    const bool thickness_given = readContactThickness(reader, def.contact_thickness);
    reader.finish();
    check(reader, reader.field(""), core::validate(def, world.max_particles_per_body));
    if (!thickness_given)
      def.contact_thickness = core::clothContactThickness(def.vertices, def.triangles, world.spheres);
    addFramePins(
        reader, frame_pins, name, static_cast<int>(def.vertices.size()),
        [](const std::string&, std::vector<int>&) { return false; }, def.pins, scene);
    return def;
  }

  core::ClothGridDef def;
  startCloth(reader, name, model, world.integrator, def);
  reader.read("origin", def.origin);
  reader.read("edge_u", def.edge_u);
  reader.read("edge_v", def.edge_v);
  if (const YAML::Node resolution = reader.child("resolution"))
  {
    if (!resolution.IsSequence() || resolution.size() != 2)
      reader.fail(resolution, reader.field("resolution") + " must be [nu, nv]");
    def.nu = resolution[0].as<int>();
    def.nv = resolution[1].as<int>();
  }
  reader.read("mass", def.mass);
  readClothConstants(reader, def.stretch, &def.shear, def.bend, source);
  readPins(reader, def.pins, &def.named_pins);
  readStrainLimit(reader, def.strain_limit);
  readIntegrator(reader, def.integrator);
  const bool thickness_given = readContactThickness(reader, def.contact_thickness);
  reader.finish();
  check(reader, reader.field(""), core::validate(def, world.max_particles_per_body));
  if (!thickness_given)
  {
    const core::SpringNetworkDef net = core::buildClothGrid(def);
    def.contact_thickness = core::clothContactThickness(net.positions, net.triangles, world.spheres);
  }
  addFramePins(
      reader, frame_pins, name, def.nu * def.nv,
      [&](const std::string& pin, std::vector<int>& indices) {
        return core::namedGridPins(pin, def.nu, def.nv, indices);
      },
      def.pins, scene);
  return def;
}

core::JellyDef readJelly(MapReader& reader, SceneDef& scene, const std::string& source)
{
  core::JellyDef def;
  def.integrator = scene.world.integrator;
  reader.require("name", def.name);
  reader.read("origin", def.origin);
  reader.read("size", def.size);
  if (const YAML::Node resolution = reader.child("resolution"))
  {
    if (!resolution.IsSequence() || resolution.size() != 3)
      reader.fail(resolution, reader.field("resolution") + " must be [nx, ny, nz]");
    def.nx = resolution[0].as<int>();
    def.ny = resolution[1].as<int>();
    def.nz = resolution[2].as<int>();
  }
  reader.read("mass", def.mass);
  reader.read("velocity", def.velocity);
  readClothConstants(reader, def.stretch, &def.shear, def.bend, source);
  readPins(reader, def.pins, nullptr);
  readStrainLimit(reader, def.strain_limit);
  readIntegrator(reader, def.integrator);
  reader.read("contact_thickness", def.contact_thickness);
  reader.finish();
  check(reader, reader.field(""), core::validate(def, scene.world.max_particles_per_body));
  return def;
}

void readBodies(const YAML::Node& node, const std::string& source, SceneDef& scene)
{
  if (!node.IsSequence()) throw SceneError{location(source, node) + "bodies must be a list of bodies"};
  std::set<std::string> names;
  for (std::size_t i = 0; i < node.size(); ++i)
  {
    MapReader reader(node[i], "bodies[" + std::to_string(i) + "]", source);
    std::string kind;
    reader.require("kind", kind);
    if (kind == "emitter")
      scene.bodies.emplace_back(readEmitter(reader, scene.world));
    else if (kind == "rope")
      scene.bodies.emplace_back(readRope(reader, scene.world, source));
    else if (kind == "spring_network")
      scene.bodies.emplace_back(readSpringNetwork(reader, scene.world, source));
    else if (kind == "cloth")
      scene.bodies.emplace_back(readCloth(reader, scene, source));
    else if (kind == "jelly")
      scene.bodies.emplace_back(readJelly(reader, scene, source));
    else
      reader.fail(node[i]["kind"], reader.field("kind") + " = " + core::quoteReceived(kind) +
                                       " is not a body kind; allowed: emitter, rope, spring_network, cloth, jelly");

    const std::string name = std::visit([](const auto& def) { return def.name; }, scene.bodies.back());
    if (!names.insert(name).second)
      reader.fail(node[i], reader.field("name") + " = " + core::quoteReceived(name) +
                               " is already taken: body names must be unique");
  }
}
}  // namespace

Status parseScene(const std::string& yaml_text, const std::string& source, SceneDef& scene)
{
  scene = SceneDef{};
  try
  {
    const YAML::Node root = YAML::Load(yaml_text);
    if (root.IsNull()) return Status::failure(source + ": the scene is empty; it needs at least 'world' or 'bodies'");
    MapReader reader(root, "", source);
    if (const YAML::Node world = reader.child("world")) readWorld(world, source, scene);
    if (const YAML::Node frames = reader.child("frames")) readFrames(frames, source, scene);
    if (const YAML::Node bodies = reader.child("bodies")) readBodies(bodies, source, scene);
    reader.finish();
  }
  catch (const SceneError& error)
  {
    return Status::failure(error.message);
  }
  catch (const YAML::Exception& error)
  {
    return Status::failure(source + ":" + std::to_string(error.mark.line + 1) + ": not valid YAML: " + error.msg);
  }
  return Status::success();
}

Status loadSceneFile(const std::string& path, SceneDef& scene)
{
  std::ifstream in(path);
  if (!in) return Status::failure(path + ": cannot open the scene file");
  std::stringstream text;
  text << in.rdbuf();
  return parseScene(text.str(), path, scene);
}

Status addBody(const BodyDef& body, core::World& world)
{
  if (const auto* emitter = std::get_if<core::EmitterDef>(&body)) return world.addEmitter(*emitter);
  if (const auto* rope = std::get_if<core::RopeDef>(&body)) return world.addRope(*rope);
  if (const auto* cloth = std::get_if<core::ClothGridDef>(&body)) return world.addClothGrid(*cloth);
  if (const auto* mesh = std::get_if<core::MeshClothDef>(&body)) return world.addMeshCloth(*mesh);
  if (const auto* jelly = std::get_if<core::JellyDef>(&body)) return world.addJelly(*jelly);
  return world.addSpringNetwork(std::get<core::SpringNetworkDef>(body));
}

Status buildWorld(const SceneDef& scene, std::unique_ptr<core::World>& world)
{
  if (Status s = core::validate(scene.world); !s) return s;
  auto built = std::make_unique<core::World>(scene.world);
  for (const BodyDef& body : scene.bodies)
  {
    if (Status s = addBody(body, *built); !s) return s;
  }
  // Frame pins start on their frame where it is scripted (the node does the rest through tf);
  // spheres that follow a frame must exist.
  for (const FrameSphereDef& follower : scene.frame_spheres)
  {
    const auto& spheres = scene.world.spheres;
    if (std::none_of(spheres.begin(), spheres.end(), [&](const auto& s) { return s.name == follower.sphere; }))
      return Status::failure("sphere '" + follower.sphere + "' follows frame '" + follower.frame +
                             "' but does not exist");
  }
  if (Status s = applyScriptedFrames(scene, 0.0, *built); !s) return s;
  world = std::move(built);
  return Status::success();
}

namespace
{
YAML::Node vector3(const Eigen::Vector3d& v)
{
  YAML::Node node;
  node.SetStyle(YAML::EmitterStyle::Flow);
  for (int i = 0; i < 3; ++i)
    node.push_back(v[i]);
  return node;
}

void integrator(YAML::Node node, const core::IntegratorDef& i)
{
  node["integrator"] = core::toString(i.type);
  node["verlet_damping"] = i.verlet_damping;
  node["cg_tolerance"] = i.cg_tolerance;
  node["cg_max_iterations"] = i.cg_max_iterations;
  node["max_substeps"] = i.max_substeps;
}

YAML::Node springConstants(double stiffness, double damping)
{
  YAML::Node node;
  node.SetStyle(YAML::EmitterStyle::Flow);
  node["stiffness"] = stiffness;
  node["damping"] = damping;
  return node;
}

YAML::Node indexList(const std::vector<int>& values)
{
  YAML::Node node(YAML::NodeType::Sequence);
  node.SetStyle(YAML::EmitterStyle::Flow);
  for (int v : values)
    node.push_back(v);
  return node;
}

void strainLimit(YAML::Node node, const core::StrainLimitDef& limit)
{
  node["max_strain"] = limit.max_strain;
  node["strain_iterations"] = limit.iterations;
}

// Frame pins of `body` whose index is `index`.
YAML::Node framePins(const SceneDef& scene, const std::string& body)
{
  YAML::Node list(YAML::NodeType::Sequence);
  for (const FramePinDef& pin : scene.frame_pins)
  {
    if (pin.body != body) continue;
    YAML::Node entry;
    entry.SetStyle(YAML::EmitterStyle::Flow);
    entry["pin"] = pin.index;
    entry["frame"] = pin.frame;
    entry["offset"] = vector3(pin.offset);
    list.push_back(entry);
  }
  return list;
}

// The keys grid and mesh cloth share: mass, stretch, bend, pins, frame pins, strain limit, integrator.
template <typename ClothDef>
void clothTail(YAML::Node node, const SceneDef& scene, const ClothDef& cloth, const YAML::Node& pins)
{
  node["mass"] = cloth.mass;
  node["stretch"] = springConstants(cloth.stretch.stiffness, cloth.stretch.damping);
  node["bend"] = springConstants(cloth.bend.stiffness, cloth.bend.damping);
  node["pins"] = pins;
  node["frame_pins"] = framePins(scene, cloth.name);
  strainLimit(node, cloth.strain_limit);
  integrator(node, cloth.integrator);
  node["contact_thickness"] = cloth.contact_thickness;
}

YAML::Node contact(YAML::Node node, const core::ContactDef& c)
{
  node["restitution"] = c.restitution;
  node["friction"] = c.friction;
  node["bounce_speed"] = c.bounce_speed;
  return node;
}
}  // namespace

std::string toYaml(const SceneDef& scene)
{
  YAML::Node root;
  const core::WorldDef& w = scene.world;
  root["world"]["gravity"] = vector3(w.gravity);
  root["world"]["dt"] = w.dt;
  root["world"]["global_damping"] = w.global_damping;
  root["world"]["seed"] = w.seed;
  root["world"]["max_particles_per_body"] = w.max_particles_per_body;
  integrator(root["world"], w.integrator);
  YAML::Node ground;
  ground["enabled"] = w.ground.enabled;
  ground["height"] = w.ground.height;
  root["world"]["ground"] = contact(ground, w.ground.contact);
  for (const core::SphereColliderDef& s : w.spheres)
  {
    YAML::Node sphere;
    sphere["name"] = s.name;
    sphere["center"] = vector3(s.center);
    sphere["radius"] = s.radius;
    for (const FrameSphereDef& follower : scene.frame_spheres)
    {
      if (follower.sphere == s.name) sphere["frame"] = follower.frame;
    }
    root["world"]["spheres"].push_back(contact(sphere, s.contact));
  }
  root["world"]["air"]["drag"] = w.air.drag;
  root["world"]["air"]["wind"] = vector3(w.air.wind);
  for (const ScriptedFrameDef& f : scene.frames)
  {
    YAML::Node frame;
    frame["name"] = f.name;
    frame["center"] = vector3(f.center);
    frame["radius"] = f.radius;
    frame["period"] = f.period;
    frame["phase"] = f.phase;
    root["frames"].push_back(frame);
  }
  for (const BodyDef& body : scene.bodies)
  {
    if (const auto* e = std::get_if<core::EmitterDef>(&body))
    {
      YAML::Node node;
      node["name"] = e->name;
      node["kind"] = "emitter";
      node["type"] = core::toString(e->type);
      node["origin"] = vector3(e->origin);
      node["rate"] = e->rate;
      node["burst_count"] = e->burst_count;
      node["speed"] = e->speed;
      node["spread"] = e->spread;
      node["lifetime"] = e->lifetime;
      node["particle_mass"] = e->particle_mass;
      node["max_particles"] = e->max_particles;
      node["seed"] = e->seed;
      node["contact_thickness"] = e->contact_thickness;
      root["bodies"].push_back(node);
    }
    else if (const auto* r = std::get_if<core::RopeDef>(&body))
    {
      YAML::Node node;
      node["name"] = r->name;
      node["kind"] = "rope";
      node["particles"] = r->particles;
      node["start"] = vector3(r->start);
      node["end"] = vector3(r->end);
      node["mass"] = r->mass;
      node["rest_length"] = r->rest_length;
      node["stretch"] = springConstants(r->stretch_stiffness, r->stretch_damping);
      node["bend"] = springConstants(r->bend_stiffness, r->bend_damping);
      node["pins"] = indexList(r->pins);
      node["contact_thickness"] = r->contact_thickness;
      integrator(node, r->integrator);
      root["bodies"].push_back(node);
    }
    else if (const auto* net = std::get_if<core::SpringNetworkDef>(&body))
    {
      YAML::Node node;
      node["name"] = net->name;
      node["kind"] = "spring_network";
      for (std::size_t i = 0; i < net->positions.size(); ++i)
      {
        YAML::Node particle;
        particle.SetStyle(YAML::EmitterStyle::Flow);
        particle["position"] = vector3(net->positions[i]);
        particle["mass"] = net->masses[i];
        if (!net->velocities.empty()) particle["velocity"] = vector3(net->velocities[i]);
        node["particles"].push_back(particle);
      }
      for (const core::Spring& spring : net->springs)
      {
        YAML::Node s;
        s.SetStyle(YAML::EmitterStyle::Flow);
        s["particles"] = indexList({spring.i, spring.j});
        s["rest_length"] = spring.rest_length;
        s["stiffness"] = spring.stiffness;
        s["damping"] = spring.damping;
        s["class"] = core::toString(spring.spring_class);
        node["springs"].push_back(s);
      }
      node["pins"] = indexList(net->pins);
      node["contact_thickness"] = net->contact_thickness;
      integrator(node, net->integrator);
      root["bodies"].push_back(node);
    }
    else if (const auto* c = std::get_if<core::ClothGridDef>(&body))
    {
      YAML::Node node;
      node["name"] = c->name;
      node["kind"] = "cloth";
      node["model"] = core::toString(c->model);
      if (c->model == core::ClothModel::BaraffWitkin)
      {
        node["b_u"] = c->b_u;
        node["b_v"] = c->b_v;
      }
      node["origin"] = vector3(c->origin);
      node["edge_u"] = vector3(c->edge_u);
      node["edge_v"] = vector3(c->edge_v);
      node["resolution"] = indexList({c->nu, c->nv});
      node["shear"] = springConstants(c->shear.stiffness, c->shear.damping);
      YAML::Node pins = indexList(c->pins);
      for (const std::string& name : c->named_pins)
        pins.push_back(name);
      clothTail(node, scene, *c, pins);
      root["bodies"].push_back(node);
    }
    else if (const auto* m = std::get_if<core::MeshClothDef>(&body))
    {
      YAML::Node node;
      node["name"] = m->name;
      node["kind"] = "cloth";
      node["model"] = core::toString(m->model);
      for (const Eigen::Vector3d& v : m->vertices)
        node["vertices"].push_back(vector3(v));
      for (const Eigen::Vector3i& t : m->triangles)
        node["triangles"].push_back(indexList({t[0], t[1], t[2]}));
      for (const Eigen::Vector2d& uv : m->uvs)
      {
        YAML::Node pair(YAML::NodeType::Sequence);
        pair.SetStyle(YAML::EmitterStyle::Flow);
        pair.push_back(uv.x());
        pair.push_back(uv.y());
        node["uvs"].push_back(pair);
      }
      if (m->model == core::ClothModel::BaraffWitkin)
      {
        node["shear"] = springConstants(m->shear.stiffness, m->shear.damping);
        node["b_u"] = m->b_u;
        node["b_v"] = m->b_v;
      }
      clothTail(node, scene, *m, indexList(m->pins));
      root["bodies"].push_back(node);
    }
    else if (const auto* j = std::get_if<core::JellyDef>(&body))
    {
      YAML::Node node;
      node["name"] = j->name;
      node["kind"] = "jelly";
      node["origin"] = vector3(j->origin);
      node["size"] = vector3(j->size);
      node["resolution"] = indexList({j->nx, j->ny, j->nz});
      node["mass"] = j->mass;
      node["velocity"] = vector3(j->velocity);
      node["stretch"] = springConstants(j->stretch.stiffness, j->stretch.damping);
      node["shear"] = springConstants(j->shear.stiffness, j->shear.damping);
      node["bend"] = springConstants(j->bend.stiffness, j->bend.damping);
      node["pins"] = indexList(j->pins);
      node["contact_thickness"] = j->contact_thickness;
      strainLimit(node, j->strain_limit);
      integrator(node, j->integrator);
      root["bodies"].push_back(node);
    }
  }
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << root;
  return std::string(out.c_str()) + "\n";
}

}  // namespace scene
}  // namespace particle_sim
