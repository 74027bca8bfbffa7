#include "body_yaml.h"

namespace particle_sim
{
namespace scene
{
namespace body_yaml
{
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

YAML::Node writeEmitter(const core::EmitterDef& def)
{
  YAML::Node node;
  node["name"] = def.name;
  node["kind"] = "emitter";
  node["type"] = core::toString(def.type);
  node["origin"] = vector3(def.origin);
  node["rate"] = def.rate;
  node["burst_count"] = def.burst_count;
  node["speed"] = def.speed;
  node["spread"] = def.spread;
  node["lifetime"] = def.lifetime;
  node["particle_mass"] = def.particle_mass;
  node["max_particles"] = def.max_particles;
  node["seed"] = def.seed;
  node["contact_thickness"] = def.contact_thickness;
  return node;
}

}  // namespace body_yaml
}  // namespace scene
}  // namespace particle_sim
