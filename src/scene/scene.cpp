#include "particle_sim/scene/scene.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <fstream>
#include <set>
#include <sstream>

#include "body_yaml/body_yaml.h"
#include "map_reader.h"

namespace particle_sim
{
namespace scene
{
namespace
{
// Each entry of `bodies` goes to the reader of its kind (body_yaml/<kind>.cpp); names are unique.
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
      scene.bodies.emplace_back(body_yaml::readEmitter(reader, scene.world));
    else if (kind == "rope")
      scene.bodies.emplace_back(body_yaml::readRope(reader, scene.world, source));
    else if (kind == "spring_network")
      scene.bodies.emplace_back(body_yaml::readSpringNetwork(reader, scene.world, source));
    else if (kind == "cloth")
      scene.bodies.emplace_back(body_yaml::readCloth(reader, scene, source));
    else if (kind == "jelly")
      scene.bodies.emplace_back(body_yaml::readJelly(reader, scene, source));
    else
      reader.fail(node[i]["kind"], reader.field("kind") + " = " + core::quoteReceived(kind) +
                                       " is not a body kind; allowed: emitter, rope, spring_network, cloth, jelly");

    const std::string name = std::visit([](const auto& def) { return def.name; }, scene.bodies.back());
    if (!names.insert(name).second)
      reader.fail(node[i], reader.field("name") + " = " + core::quoteReceived(name) +
                               " is already taken: body names must be unique");
  }
}

// The YAML of one body, from the writer of its kind.
YAML::Node writeBody(const SceneDef& scene, const BodyDef& body)
{
  if (const auto* emitter = std::get_if<core::EmitterDef>(&body)) return body_yaml::writeEmitter(*emitter);
  if (const auto* rope = std::get_if<core::RopeDef>(&body)) return body_yaml::writeRope(*rope);
  if (const auto* grid = std::get_if<core::ClothGridDef>(&body)) return body_yaml::writeClothGrid(scene, *grid);
  if (const auto* mesh = std::get_if<core::MeshClothDef>(&body)) return body_yaml::writeMeshCloth(scene, *mesh);
  if (const auto* jelly = std::get_if<core::JellyDef>(&body)) return body_yaml::writeJelly(*jelly);
  return body_yaml::writeSpringNetwork(std::get<core::SpringNetworkDef>(body));
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
    if (const YAML::Node world = reader.child("world")) body_yaml::readWorld(world, source, scene);
    if (const YAML::Node frames = reader.child("frames")) body_yaml::readFrames(frames, source, scene);
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
  for (const FrameColliderDef& follower : scene.frame_colliders)
  {
    Eigen::Vector3d center;
    Eigen::Quaterniond orientation;
    if (!built->colliderPose(follower.collider, center, orientation))
      return Status::failure("collider '" + follower.collider + "' follows frame '" + follower.frame +
                             "' but does not exist");
  }
  if (Status s = applyScriptedFrames(scene, 0.0, *built); !s) return s;
  world = std::move(built);
  return Status::success();
}

std::string toYaml(const SceneDef& scene)
{
  YAML::Node root(YAML::NodeType::Map);  // defined now, so that writeWorld's copy shares it
  body_yaml::writeWorld(root, scene);
  for (const BodyDef& body : scene.bodies)
    root["bodies"].push_back(writeBody(scene, body));
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << root;
  return std::string(out.c_str()) + "\n";
}

}  // namespace scene
}  // namespace particle_sim
