#include <algorithm>
#include <filesystem>
#include <optional>

#include "body_yaml.h"
#include "particle_sim/core/builders/pins.h"
#include "particle_sim/core/materials/cloth_material.h"
#include "particle_sim/core/surface.h"
#include "particle_sim/scene/obj_mesh.h"

namespace particle_sim
{
namespace scene
{
namespace body_yaml
{
namespace
{
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
      indices.push_back(core::resolvePinIndex(index, count));
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

// What grid and mesh cloth start with: name, model (constants the file does not give take its
// defaults when the cloth is built) and, for a Baraff–Witkin cloth, its rest stretch b_u, b_v.
template <typename ClothDef>
void startCloth(MapReader& reader, const std::string& name, core::ClothModel model, ClothDef& def)
{
  def = ClothDef(model);
  def.name = name;
  if (model != core::ClothModel::BaraffWitkin) return;
  reader.read("b_u", def.b_u);
  reader.read("b_v", def.b_v);
}

// The cloth's `material` key (issue 17): a preset's name (`material: cotton`), or a mapping with an
// optional `preset` whose values the other keys replace, or all values by key (areal_density,
// tensile_stiffness and shear_stiffness required without a preset; bending_rigidity and
// damping_ratio default to 0). Refused beside `mass` or any spring constant key, naming both.
std::optional<core::ClothMaterial> readClothMaterial(MapReader& reader, const std::string& source)
{
  const YAML::Node node = reader.child("material");
  if (!node) return std::nullopt;
  for (const char* key : {"mass", "stretch", "shear", "bend"})
  {
    if (reader.has(key))
      reader.fail(reader.node()[key], reader.field("material") + " and " + reader.field(key) +
                                          " are both set: a material gives the cloth its masses and constants; "
                                          "set one or the other");
  }
  auto preset = [&](const YAML::Node& at, const std::string& name) {
    const std::optional<core::ClothMaterial> found = core::findClothPreset(name);
    if (!found)
      reader.fail(at, reader.field("material") + " = " + core::quoteReceived(name) +
                          " is not a cloth material preset; allowed: " + core::clothPresetNames());
    return *found;
  };
  if (node.IsScalar()) return preset(node, node.Scalar());
  MapReader entry(node, reader.field("material"), source);
  core::ClothMaterial material;
  std::string preset_name;
  entry.read("preset", preset_name);
  if (entry.has("preset"))
    material = preset(node["preset"], preset_name);
  else
  {
    for (const char* key : {"areal_density", "tensile_stiffness", "shear_stiffness"})
      if (!entry.has(key))
        entry.fail(node, reader.field("material") + " needs the key '" + key +
                             "' (or a preset: " + core::clothPresetNames() + ")");
  }
  entry.read("areal_density", material.areal_density);
  entry.read("tensile_stiffness", material.tensile_stiffness);
  entry.read("shear_stiffness", material.shear_stiffness);
  entry.read("bending_rigidity", material.bending_rigidity);
  entry.read("damping_ratio", material.damping_ratio);
  entry.finish();
  return material;
}

// The material as read back: the preset's name when it is one unchanged, else every value (and the
// preset it started from).
YAML::Node clothMaterial(const core::ClothMaterial& material)
{
  const std::optional<core::ClothMaterial> preset = core::findClothPreset(material.name);
  if (preset && preset->areal_density == material.areal_density &&
      preset->tensile_stiffness == material.tensile_stiffness && preset->shear_stiffness == material.shear_stiffness &&
      preset->bending_rigidity == material.bending_rigidity && preset->damping_ratio == material.damping_ratio)
    return YAML::Node(material.name);
  YAML::Node node;
  node.SetStyle(YAML::EmitterStyle::Flow);
  if (preset) node["preset"] = material.name;
  node["areal_density"] = material.areal_density;
  node["tensile_stiffness"] = material.tensile_stiffness;
  node["shear_stiffness"] = material.shear_stiffness;
  node["bending_rigidity"] = material.bending_rigidity;
  node["damping_ratio"] = material.damping_ratio;
  return node;
}

// The frame_pins entries of body `body`, written back by index.
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

// The shear constants a cloth gets, as written.
template <typename ClothDef>
YAML::Node shearConstants(const ClothDef& def)
{
  const core::SpringConstants shear = def.constants(core::SpringClass::Shear);
  return springConstants(shear.stiffness, shear.damping);
}

// The keys grid and mesh cloth share: material, or mass, stretch and bend; pins, frame pins, strain limit, integrator,
// contact thickness, tear strain and self-collision (the last two only when set).
template <typename ClothDef>
void clothTail(YAML::Node node, const SceneDef& scene, const ClothDef& cloth, const YAML::Node& pins)
{
  if (cloth.material)
    node["material"] = clothMaterial(*cloth.material);  // it gives the mass and every constant
  else
  {
    node["mass"] = cloth.mass;
    const core::SpringConstants stretch = cloth.constants(core::SpringClass::Stretch);
    const core::SpringConstants bend = cloth.constants(core::SpringClass::Bend);
    node["stretch"] = springConstants(stretch.stiffness, stretch.damping);
    node["bend"] = springConstants(bend.stiffness, bend.damping);
  }
  node["pins"] = pins;
  node["frame_pins"] = framePins(scene, cloth.name);
  writeStrainLimit(node, cloth.strain_limit);
  writeIntegrator(node, cloth.integrator);
  node["contact_thickness"] = cloth.contact_thickness;
  if (cloth.tear_strain != 0.0) node["tear_strain"] = cloth.tear_strain;
  writeSelfCollision(node, cloth.self_collision);
}
}  // namespace

BodyDef readCloth(MapReader& reader, SceneDef& scene, const std::string& source)
{
  const core::WorldDef& world = scene.world;
  // A grid cloth given by its material is Baraff–Witkin unless `model` says otherwise: only that
  // model carries a bending rigidity (as ~spawn_cloth does). A mesh cloth keeps the spring default:
  // Baraff–Witkin needs texture coordinates, which not every mesh has.
  const bool grid = !reader.has("mesh") && !reader.has("vertices");
  std::string name, model_name = grid && reader.has("material") ? "baraff_witkin" : "springs";
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
    startCloth(reader, name, model, def);
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
    def.material = readClothMaterial(reader, source);
    reader.read("mass", def.mass);
    readClothConstants(reader, def.stretch, baraff_witkin ? &def.shear : nullptr, def.bend, source);
    readPins(reader, def.pins, nullptr);
    readStrainLimit(reader, def.strain_limit);
    readIntegrator(reader, def.integrator);
    const bool thickness_given = readContactThickness(reader, def.contact_thickness);
    reader.read("tear_strain", def.tear_strain);
    readSelfCollision(reader, def.self_collision, source);
    reader.finish();
    check(reader, reader.field(""), core::validate(def, world.max_particles_per_body));
    if (!thickness_given)
      def.contact_thickness = core::clothContactThickness(def.vertices, def.triangles, world.spheres);
    checkNetworkKeys(reader, def, world.max_particles_per_body, [&] { return core::buildMeshCloth(def); });
    addFramePins(
        reader, frame_pins, name, static_cast<int>(def.vertices.size()),
        [](const std::string&, std::vector<int>&) { return false; }, def.pins, scene);
    return def;
  }

  core::ClothGridDef def;
  startCloth(reader, name, model, def);
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
  def.material = readClothMaterial(reader, source);
  reader.read("mass", def.mass);
  readClothConstants(reader, def.stretch, &def.shear, def.bend, source);
  readPins(reader, def.pins, &def.named_pins);
  readStrainLimit(reader, def.strain_limit);
  readIntegrator(reader, def.integrator);
  const bool thickness_given = readContactThickness(reader, def.contact_thickness);
  reader.read("tear_strain", def.tear_strain);
  readSelfCollision(reader, def.self_collision, source);
  reader.finish();
  check(reader, reader.field(""), core::validate(def, world.max_particles_per_body));
  if (!thickness_given)
  {
    const core::SpringNetworkDef net = core::buildClothGrid(def);
    def.contact_thickness = core::clothContactThickness(net.positions, net.triangles, world.spheres);
  }
  checkNetworkKeys(reader, def, world.max_particles_per_body, [&] { return core::buildClothGrid(def); });
  addFramePins(
      reader, frame_pins, name, def.nu * def.nv,
      [&](const std::string& pin, std::vector<int>& indices) {
        return core::namedGridPins(pin, def.nu, def.nv, indices);
      },
      def.pins, scene);
  return def;
}

YAML::Node writeClothGrid(const SceneDef& scene, const core::ClothGridDef& def)
{
  YAML::Node node;
  node["name"] = def.name;
  node["kind"] = "cloth";
  node["model"] = core::toString(def.model);
  if (def.model == core::ClothModel::BaraffWitkin)
  {
    node["b_u"] = def.b_u;
    node["b_v"] = def.b_v;
  }
  node["origin"] = vector3(def.origin);
  node["edge_u"] = vector3(def.edge_u);
  node["edge_v"] = vector3(def.edge_v);
  node["resolution"] = indexList({def.nu, def.nv});
  if (!def.material) node["shear"] = shearConstants(def);
  YAML::Node pins = indexList(def.pins);
  for (const std::string& name : def.named_pins)
    pins.push_back(name);
  clothTail(node, scene, def, pins);
  return node;
}

YAML::Node writeMeshCloth(const SceneDef& scene, const core::MeshClothDef& def)
{
  YAML::Node node;
  node["name"] = def.name;
  node["kind"] = "cloth";
  node["model"] = core::toString(def.model);
  for (const Eigen::Vector3d& v : def.vertices)
    node["vertices"].push_back(vector3(v));
  for (const Eigen::Vector3i& t : def.triangles)
    node["triangles"].push_back(indexList({t[0], t[1], t[2]}));
  for (const Eigen::Vector2d& uv : def.uvs)
  {
    YAML::Node pair(YAML::NodeType::Sequence);
    pair.SetStyle(YAML::EmitterStyle::Flow);
    pair.push_back(uv.x());
    pair.push_back(uv.y());
    node["uvs"].push_back(pair);
  }
  if (def.model == core::ClothModel::BaraffWitkin)
  {
    if (!def.material) node["shear"] = shearConstants(def);
    node["b_u"] = def.b_u;
    node["b_v"] = def.b_v;
  }
  clothTail(node, scene, def, indexList(def.pins));
  return node;
}

}  // namespace body_yaml
}  // namespace scene
}  // namespace particle_sim
