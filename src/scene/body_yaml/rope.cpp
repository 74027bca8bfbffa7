#include "body_yaml.h"

namespace particle_sim
{
namespace scene
{
namespace body_yaml
{
core::RopeDef readRope(MapReader& reader, const core::WorldDef& world, const std::string& source)
{
  core::RopeDef def;
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

YAML::Node writeRope(const core::RopeDef& def)
{
  YAML::Node node;
  node["name"] = def.name;
  node["kind"] = "rope";
  node["particles"] = def.particles;
  node["start"] = vector3(def.start);
  node["end"] = vector3(def.end);
  node["mass"] = def.mass;
  node["rest_length"] = def.rest_length;
  node["stretch"] = springConstants(def.stretch_stiffness, def.stretch_damping);
  node["bend"] = springConstants(def.bend_stiffness, def.bend_damping);
  node["pins"] = indexList(def.pins);
  node["contact_thickness"] = def.contact_thickness;
  writeIntegrator(node, def.integrator);
  return node;
}

}  // namespace body_yaml
}  // namespace scene
}  // namespace particle_sim
