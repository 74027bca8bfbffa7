#include "body_yaml.h"

namespace particle_sim
{
namespace scene
{
namespace body_yaml
{
namespace
{
void readContact(MapReader& reader, core::ContactDef& contact)
{
  reader.read("restitution", contact.restitution);
  reader.read("friction", contact.friction);
  reader.read("bounce_speed", contact.bounce_speed);
}

// `orientation: [x, y, z, w]`, a unit quaternion (ROS's order).
void readOrientation(MapReader& reader, Eigen::Quaterniond& orientation)
{
  const YAML::Node node = reader.child("orientation");
  if (!node) return;
  if (!node.IsSequence() || node.size() != 4)
    reader.fail(node, reader.field("orientation") + " must be a list of 4 numbers [x, y, z, w] (a unit quaternion)");
  double c[4];
  for (int i = 0; i < 4; ++i)
  {
    try
    {
      c[i] = node[i].as<double>();
    }
    catch (const YAML::Exception&)
    {
      reader.fail(node[i], reader.field("orientation") + "[" + std::to_string(i) + "] must be a number");
    }
  }
  orientation = Eigen::Quaterniond(c[3], c[0], c[1], c[2]);
}

YAML::Node orientation(const Eigen::Quaterniond& q)
{
  YAML::Node node;
  node.SetStyle(YAML::EmitterStyle::Flow);
  for (double c : {q.x(), q.y(), q.z(), q.w()})
    node.push_back(c);
  return node;
}

// The frame a box or capsule follows, if any (the node's tf frame or a scripted frame).
void readColliderFrame(MapReader& reader, const std::string& collider, SceneDef& scene)
{
  std::string frame;
  reader.read("frame", frame);
  if (!frame.empty()) scene.frame_colliders.push_back({collider, frame});
}

void writeColliderFrame(YAML::Node node, const std::string& collider, const SceneDef& scene)
{
  for (const FrameColliderDef& follower : scene.frame_colliders)
  {
    if (follower.collider == collider) node["frame"] = follower.frame;
  }
}

// Reads the list world.<key>: `read_one(entry, i)` for each entry, with its own reader.
template <typename ReadOne>
void readList(MapReader& reader, const std::string& key, const std::string& source, ReadOne read_one)
{
  const YAML::Node list = reader.child(key);
  if (!list) return;
  if (!list.IsSequence()) reader.fail(list, "world." + key + " must be a list of " + key);
  for (std::size_t i = 0; i < list.size(); ++i)
  {
    MapReader entry(list[i], "world." + key + "[" + std::to_string(i) + "]", source);
    read_one(entry, i);
  }
}

YAML::Node contact(YAML::Node node, const core::ContactDef& c)
{
  node["restitution"] = c.restitution;
  node["friction"] = c.friction;
  node["bounce_speed"] = c.bounce_speed;
  return node;
}
}  // namespace

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
  reader.read("max_particles_per_world", world.max_particles_per_world);
  reader.read("threads", world.threads);

  if (const YAML::Node ground = reader.child("ground"))
  {
    MapReader g(ground, "world.ground", source);
    g.read("enabled", world.ground.enabled);
    g.read("height", world.ground.height);
    readContact(g, world.ground.contact);
    g.finish();
  }
  readList(reader, "spheres", source, [&](MapReader& s, std::size_t i) {
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
  });
  readList(reader, "boxes", source, [&](MapReader& b, std::size_t i) {
    core::BoxColliderDef box;
    box.name = "box_" + std::to_string(i);
    b.read("name", box.name);
    b.require("center", box.center);
    Eigen::Vector3d size;
    b.require("size", size);
    box.half_extents = 0.5 * size;
    readOrientation(b, box.orientation);
    readContact(b, box.contact);
    readColliderFrame(b, box.name, scene);
    b.finish();
    check(b, "", core::validate(box));
    world.boxes.push_back(box);
  });
  readList(reader, "capsules", source, [&](MapReader& c, std::size_t i) {
    core::CapsuleColliderDef capsule;
    capsule.name = "capsule_" + std::to_string(i);
    c.read("name", capsule.name);
    c.require("center", capsule.center);
    double length = 0.0;
    c.require("length", length);
    capsule.half_length = 0.5 * length;
    c.require("radius", capsule.radius);
    readOrientation(c, capsule.orientation);
    readContact(c, capsule.contact);
    readColliderFrame(c, capsule.name, scene);
    c.finish();
    check(c, "", core::validate(capsule));
    world.capsules.push_back(capsule);
  });
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

// A scripted frame's waypoints: a non-empty list of {t, position}, times finite and strictly increasing.
void readWaypoints(const YAML::Node& node, const std::string& where, const std::string& source,
                   std::vector<ScriptedFrameDef::Waypoint>& waypoints)
{
  if (!node.IsSequence() || node.size() == 0)
    throw SceneError{location(source, node) + where + " must be a non-empty list of {t, position}"};
  for (std::size_t k = 0; k < node.size(); ++k)
  {
    MapReader reader(node[k], where + "[" + std::to_string(k) + "]", source);
    ScriptedFrameDef::Waypoint waypoint;
    reader.require("t", waypoint.t);
    reader.require("position", waypoint.position);
    reader.finish();
    check(reader, reader.field(""), core::checkFinite("t", waypoint.t));
    check(reader, reader.field(""), core::checkFinite("position", waypoint.position));
    if (!waypoints.empty() && !(waypoint.t > waypoints.back().t))
      reader.fail(node[k], reader.field("t") + " = " + core::formatValue(waypoint.t) +
                               " s must be later than the waypoint before it (" +
                               core::formatValue(waypoints.back().t) + " s)");
    waypoints.push_back(waypoint);
  }
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
    if (const YAML::Node waypoints = reader.child("waypoints"))
    {
      for (const char* circle_key : {"center", "radius", "period", "phase"})
      {
        if (reader.node()[circle_key])
          reader.fail(reader.node()[circle_key], reader.field(circle_key) +
                                                     " is a circle's; a frame with waypoints follows them only");
      }
      readWaypoints(waypoints, reader.field("waypoints"), source, frame.waypoints);
    }
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

void writeWorld(YAML::Node root, const SceneDef& scene)
{
  const core::WorldDef& w = scene.world;
  YAML::Node world = root["world"];
  world["gravity"] = vector3(w.gravity);
  world["dt"] = w.dt;
  world["global_damping"] = w.global_damping;
  world["seed"] = w.seed;
  world["max_particles_per_body"] = w.max_particles_per_body;
  world["max_particles_per_world"] = w.max_particles_per_world;
  world["threads"] = w.threads;
  writeIntegrator(world, w.integrator);
  YAML::Node ground;
  ground["enabled"] = w.ground.enabled;
  ground["height"] = w.ground.height;
  world["ground"] = contact(ground, w.ground.contact);
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
    world["spheres"].push_back(contact(sphere, s.contact));
  }
  for (const core::BoxColliderDef& b : w.boxes)
  {
    YAML::Node box;
    box["name"] = b.name;
    box["center"] = vector3(b.center);
    box["size"] = vector3(2.0 * b.half_extents);
    box["orientation"] = orientation(b.orientation);
    writeColliderFrame(box, b.name, scene);
    world["boxes"].push_back(contact(box, b.contact));
  }
  for (const core::CapsuleColliderDef& c : w.capsules)
  {
    YAML::Node capsule;
    capsule["name"] = c.name;
    capsule["center"] = vector3(c.center);
    capsule["length"] = 2.0 * c.half_length;
    capsule["radius"] = c.radius;
    capsule["orientation"] = orientation(c.orientation);
    writeColliderFrame(capsule, c.name, scene);
    world["capsules"].push_back(contact(capsule, c.contact));
  }
  world["air"]["drag"] = w.air.drag;
  world["air"]["wind"] = vector3(w.air.wind);
  for (const ScriptedFrameDef& f : scene.frames)
  {
    YAML::Node frame;
    frame["name"] = f.name;
    for (const ScriptedFrameDef::Waypoint& w : f.waypoints)
    {
      YAML::Node waypoint;
      waypoint["t"] = w.t;
      waypoint["position"] = vector3(w.position);
      frame["waypoints"].push_back(waypoint);
    }
    if (f.waypoints.empty())
    {
      frame["center"] = vector3(f.center);
      frame["radius"] = f.radius;
      frame["period"] = f.period;
      frame["phase"] = f.phase;
    }
    root["frames"].push_back(frame);
  }
}

}  // namespace body_yaml
}  // namespace scene
}  // namespace particle_sim
