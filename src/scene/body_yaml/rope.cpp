#include <optional>

#include "body_yaml.h"

namespace particle_sim
{
namespace scene
{
namespace body_yaml
{
namespace
{
// The rope keys a material replaces: giving both is inconsistent.
const char* const kKeysAMaterialSets[] = {"mass", "stretch", "bend"};

// `material: nylon_rope`, `material: {preset: nylon_rope, damping_ratio: 0.05}` (the preset with
// the values given), or all four values by key.
core::RopeMaterial readRopeMaterial(MapReader& parent, const std::string& source)
{
  const YAML::Node node = parent.child("material");
  const std::string path = parent.field("material");
  auto preset = [&](const YAML::Node& at, const std::string& name, const std::string& where) {
    const std::optional<core::RopeMaterial> found = core::findRopePreset(name);
    if (!found)
      parent.fail(at, where + " = " + core::quoteReceived(name) +
                          " is not a rope material preset; presets: " + core::ropePresetNames());
    return *found;
  };
  if (node.IsScalar()) return preset(node, node.Scalar(), path);
  MapReader reader(node, path, source);
  core::RopeMaterial material;
  if (reader.has("preset"))
  {
    std::string name;
    reader.read("preset", name);
    material = preset(reader.child("preset"), name, reader.field("preset"));
    reader.read("linear_density", material.linear_density);
    reader.read("axial_stiffness", material.axial_stiffness);
    reader.read("bending_stiffness", material.bending_stiffness);
    reader.read("damping_ratio", material.damping_ratio);
  }
  else
  {
    reader.require("linear_density", material.linear_density);
    reader.require("axial_stiffness", material.axial_stiffness);
    reader.require("bending_stiffness", material.bending_stiffness);
    reader.require("damping_ratio", material.damping_ratio);
  }
  reader.finish();
  return material;
}

// What readRopeMaterial() reads back: the preset's name alone, the preset and what differs from
// it, or the four values.
YAML::Node writeRopeMaterial(const core::RopeMaterial& material)
{
  const std::optional<core::RopeMaterial> preset = core::findRopePreset(material.name);
  YAML::Node node;
  node.SetStyle(YAML::EmitterStyle::Flow);
  if (preset)
  {
    node["preset"] = material.name;
    if (material.linear_density != preset->linear_density) node["linear_density"] = material.linear_density;
    if (material.axial_stiffness != preset->axial_stiffness) node["axial_stiffness"] = material.axial_stiffness;
    if (material.bending_stiffness != preset->bending_stiffness) node["bending_stiffness"] = material.bending_stiffness;
    if (material.damping_ratio != preset->damping_ratio) node["damping_ratio"] = material.damping_ratio;
    if (node.size() == 1) return YAML::Node(material.name);
    return node;
  }
  node["linear_density"] = material.linear_density;
  node["axial_stiffness"] = material.axial_stiffness;
  node["bending_stiffness"] = material.bending_stiffness;
  node["damping_ratio"] = material.damping_ratio;
  return node;
}
}  // namespace

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
  reader.read("tear_strain", def.tear_strain);
  readSelfCollision(reader, def.self_collision, source);
  if (reader.has("material"))
  {
    for (const char* key : kKeysAMaterialSets)
    {
      if (reader.has(key))
        reader.fail(reader.child(key), reader.field("material") + " and " + reader.field(key) +
                                           " are both given: the material sets the rope's mass and spring "
                                           "constants (inconsistent); give one of them");
    }
    def.material = readRopeMaterial(reader, source);
  }
  reader.finish();
  check(reader, reader.field(""), core::validate(def, world.max_particles_per_body));
  checkNetworkKeys(reader, def, world.max_particles_per_body, [&] { return core::buildRope(def); });
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
  if (!def.material) node["mass"] = def.mass;
  node["rest_length"] = def.rest_length;
  if (def.material)
  {
    node["material"] = writeRopeMaterial(*def.material);
  }
  else
  {
    node["stretch"] = springConstants(def.stretch_stiffness, def.stretch_damping);
    node["bend"] = springConstants(def.bend_stiffness, def.bend_damping);
  }
  node["pins"] = indexList(def.pins);
  node["contact_thickness"] = def.contact_thickness;
  if (def.tear_strain != 0.0) node["tear_strain"] = def.tear_strain;
  writeSelfCollision(node, def.self_collision);
  writeIntegrator(node, def.integrator);
  return node;
}

}  // namespace body_yaml
}  // namespace scene
}  // namespace particle_sim
