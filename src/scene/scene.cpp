#include "particle_sim/scene/scene.h"

#include <yaml-cpp/yaml.h>

#include <fstream>
#include <iomanip>
#include <set>
#include <sstream>

namespace particle_sim
{
namespace scene
{
namespace
{
using core::Status;

// A scene error carries its own message; thrown only inside this file and turned into a Status
// by parseScene(), so it never crosses the layer.
struct SceneError
{
  std::string message;
};

std::string location(const std::string& source, const YAML::Node& node)
{
  const YAML::Mark mark = node.Mark();
  if (mark.line < 0) return source + ": ";
  return source + ":" + std::to_string(mark.line + 1) + ": ";
}

// Reads the keys of one YAML mapping, checking types, and refuses any key it was not asked for.
class MapReader
{
public:
  MapReader(const YAML::Node& node, std::string path, const std::string& source)
    : node_(node), path_(std::move(path)), source_(source)
  {
    if (!node_.IsMap()) fail(node_, path_ + " must be a mapping of key: value");
  }

  bool has(const std::string& key) const { return static_cast<bool>(node_[key]); }

  template <typename T>
  void read(const std::string& key, T& value)
  {
    known_.insert(key);
    const YAML::Node child = node_[key];
    if (!child) return;
    value = convert<T>(child, field(key));
  }

  void read(const std::string& key, Eigen::Vector3d& value)
  {
    known_.insert(key);
    const YAML::Node child = node_[key];
    if (!child) return;
    if (!child.IsSequence() || child.size() != 3)
      fail(child, field(key) + " = " + text(child) + " must be a list of 3 numbers [x, y, z]");
    for (int i = 0; i < 3; ++i) value[i] = convert<double>(child[i], field(key) + "[" + std::to_string(i) + "]");
  }

  template <typename T>
  void require(const std::string& key, T& value)
  {
    if (!has(key)) fail(node_, path_ + " needs the key '" + key + "'");
    read(key, value);
  }

  YAML::Node child(const std::string& key)
  {
    known_.insert(key);
    return node_[key];
  }

  // Refuses every key that no read() asked for, listing the accepted ones.
  void finish() const
  {
    for (const auto& entry : node_)
    {
      const std::string key = entry.first.as<std::string>();
      if (known_.count(key)) continue;
      std::string allowed;
      for (const std::string& k : known_) allowed += (allowed.empty() ? "" : ", ") + k;
      fail(entry.first, field(key) + " is not a known key; allowed keys: " + allowed);
    }
  }

  std::string field(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  const YAML::Node& node() const { return node_; }
  [[noreturn]] void fail(const YAML::Node& at, const std::string& message) const
  {
    throw SceneError{location(source_, at) + message};
  }

private:
  static std::string text(const YAML::Node& node)
  {
    if (node.IsScalar()) return "'" + node.Scalar() + "'";
    YAML::Emitter out;
    out << YAML::Flow << node;
    return out.c_str();
  }

  template <typename T>
  T convert(const YAML::Node& child, const std::string& name) const
  {
    if (!child.IsScalar()) fail(child, name + " = " + text(child) + " must be " + typeName<T>());
    try
    {
      return child.as<T>();
    }
    catch (const YAML::Exception&)
    {
      fail(child, name + " = " + text(child) + " must be " + typeName<T>());
    }
  }

  template <typename T>
  static const char* typeName()
  {
    if constexpr (std::is_same_v<T, bool>)
      return "true or false";
    else if constexpr (std::is_same_v<T, std::string>)
      return "a string";
    else if constexpr (std::is_floating_point_v<T>)
      return "a number";
    else if constexpr (std::is_unsigned_v<T>)
      return "a non-negative integer";
    else
      return "an integer";
  }

  YAML::Node node_;
  std::string path_;
  const std::string& source_;
  std::set<std::string> known_;
};

// Fails at `reader`'s node with a core validation message, prefixed by the entry's path.
void check(const MapReader& reader, const std::string& prefix, const Status& status)
{
  if (!status) reader.fail(reader.node(), prefix + status.message);
}

void readContact(MapReader& reader, core::ContactDef& contact)
{
  reader.read("restitution", contact.restitution);
  reader.read("friction", contact.friction);
}

// The integrator keys, read at world level (the default) and per body (an override).
void readIntegrator(MapReader& reader, core::IntegratorDef& integrator)
{
  if (reader.has("integrator"))
  {
    std::string name;
    reader.read("integrator", name);
    if (!core::parseIntegratorType(name, integrator.type))
      reader.fail(reader.node()["integrator"], reader.field("integrator") + " = '" + name +
                                                   "' is not an integrator; allowed: " + core::integratorTypeNames());
  }
  reader.read("verlet_damping", integrator.verlet_damping);
  reader.read("cg_tolerance", integrator.cg_tolerance);
  reader.read("cg_max_iterations", integrator.cg_max_iterations);
}

void readWorld(const YAML::Node& node, const std::string& source, core::WorldDef& world)
{
  MapReader reader(node, "world", source);
  readIntegrator(reader, world.integrator);
  reader.read("gravity", world.gravity);
  reader.read("dt", world.dt);
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
      s.finish();
      check(s, "", core::validate(sphere));
      world.spheres.push_back(sphere);
    }
  }
  reader.finish();
  check(reader, "world.", core::validate(world));
}

core::EmitterDef readEmitter(MapReader& reader, const core::WorldDef& world)
{
  core::EmitterDef def;
  reader.require("name", def.name);

  std::string type;
  reader.require("type", type);
  if (!core::parseEmitterType(type, def.type))
    reader.fail(reader.node()["type"], reader.field("type") + " = '" + type +
                                           "' is not an emitter type; allowed: " + core::emitterTypeNames());
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
  reader.finish();
  check(reader, reader.field(""), core::validate(def, world.max_particles_per_body));
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
    reader.fail(particles ? particles : reader.node(), reader.field("particles") +
                                                           " must be a non-empty list of {position, mass, velocity}");
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
          s.fail(springs[k]["class"], s.field("class") + " = '" + name + "' is not a spring class; allowed: stretch, shear, bend");
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
  reader.finish();
  check(reader, reader.field(""), core::validate(def, world.max_particles_per_body));
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
    else
      reader.fail(node[i]["kind"], reader.field("kind") + " = '" + kind +
                                       "' is not a body kind; allowed: emitter, rope, spring_network");

    const std::string name = std::visit([](const auto& def) { return def.name; }, scene.bodies.back());
    if (!names.insert(name).second)
      reader.fail(node[i], reader.field("name") + " = '" + name + "' is already taken: body names must be unique");
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
    if (const YAML::Node world = reader.child("world")) readWorld(world, source, scene.world);
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
  world = std::move(built);
  return Status::success();
}

namespace
{
YAML::Node vector3(const Eigen::Vector3d& v)
{
  YAML::Node node;
  node.SetStyle(YAML::EmitterStyle::Flow);
  for (int i = 0; i < 3; ++i) node.push_back(v[i]);
  return node;
}

void integrator(YAML::Node node, const core::IntegratorDef& i)
{
  node["integrator"] = core::toString(i.type);
  node["verlet_damping"] = i.verlet_damping;
  node["cg_tolerance"] = i.cg_tolerance;
  node["cg_max_iterations"] = i.cg_max_iterations;
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
  for (int v : values) node.push_back(v);
  return node;
}

YAML::Node contact(YAML::Node node, const core::ContactDef& c)
{
  node["restitution"] = c.restitution;
  node["friction"] = c.friction;
  return node;
}
}  // namespace

std::string toYaml(const SceneDef& scene)
{
  YAML::Node root;
  const core::WorldDef& w = scene.world;
  root["world"]["gravity"] = vector3(w.gravity);
  root["world"]["dt"] = w.dt;
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
    root["world"]["spheres"].push_back(contact(sphere, s.contact));
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
      integrator(node, net->integrator);
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
