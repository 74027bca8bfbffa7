#include "body_yaml.h"

namespace particle_sim
{
namespace scene
{
namespace body_yaml
{
core::JellyDef readJelly(MapReader& reader, SceneDef& scene, const std::string& source)
{
  core::JellyDef def;
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
  readSpringConstants(reader, "stretch", def.stretch.stiffness, def.stretch.damping, source);
  readSpringConstants(reader, "shear", def.shear.stiffness, def.shear.damping, source);
  readSpringConstants(reader, "bend", def.bend.stiffness, def.bend.damping, source);
  readPins(reader, def.pins, nullptr);
  readStrainLimit(reader, def.strain_limit);
  readIntegrator(reader, def.integrator);
  reader.read("contact_thickness", def.contact_thickness);
  reader.read("tear_strain", def.tear_strain);
  readSelfCollision(reader, def.self_collision, source);
  reader.finish();
  check(reader, reader.field(""), core::validate(def, scene.world.max_particles_per_body));
  checkNetworkKeys(reader, def, scene.world.max_particles_per_body, [&] { return core::buildJelly(def); });
  return def;
}

YAML::Node writeJelly(const core::JellyDef& def)
{
  YAML::Node node;
  node["name"] = def.name;
  node["kind"] = "jelly";
  node["origin"] = vector3(def.origin);
  node["size"] = vector3(def.size);
  node["resolution"] = indexList({def.nx, def.ny, def.nz});
  node["mass"] = def.mass;
  node["velocity"] = vector3(def.velocity);
  node["stretch"] = springConstants(def.stretch.stiffness, def.stretch.damping);
  node["shear"] = springConstants(def.shear.stiffness, def.shear.damping);
  node["bend"] = springConstants(def.bend.stiffness, def.bend.damping);
  node["pins"] = indexList(def.pins);
  node["contact_thickness"] = def.contact_thickness;
  if (def.tear_strain != 0.0) node["tear_strain"] = def.tear_strain;
  writeSelfCollision(node, def.self_collision);
  writeStrainLimit(node, def.strain_limit);
  writeIntegrator(node, def.integrator);
  return node;
}

}  // namespace body_yaml
}  // namespace scene
}  // namespace particle_sim
