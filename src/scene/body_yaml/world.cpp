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
  world["air"]["drag"] = w.air.drag;
  world["air"]["wind"] = vector3(w.air.wind);
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
}

}  // namespace body_yaml
}  // namespace scene
}  // namespace particle_sim
