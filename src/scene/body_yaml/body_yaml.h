#pragma once
// YAML reading and writing of the scene's parts, side by side: one unit per body kind
// (emitter.cpp, rope.cpp, spring_network.cpp, cloth.cpp, jelly.cpp), the world and scripted frames
// (world.cpp), and the pieces they share (common.cpp). Private to the scene layer: scene.cpp
// orchestrates them (parseScene, toYaml).

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <string>
#include <vector>

#include "../map_reader.h"
#include "particle_sim/scene/scene.h"

namespace particle_sim
{
namespace scene
{
namespace body_yaml
{
// ---- Shared pieces (common.cpp)

// Fails at `reader`'s node with a core validation message, prefixed by the entry's path.
void check(const MapReader& reader, const std::string& prefix, const Status& status);

// The integrator keys (integrator, verlet_damping, cg_tolerance, cg_velocity_tolerance,
// cg_max_iterations, max_substeps, linear_solver).
// A body reads and writes only the keys it sets (the world applies its default to the others);
// the world reads its keys over the built-in defaults and writes them all.
void readIntegrator(MapReader& reader, core::BodyIntegratorDef& integrator);
void writeIntegrator(YAML::Node node, const core::BodyIntegratorDef& integrator);
void readIntegrator(MapReader& reader, core::IntegratorDef& integrator);
void writeIntegrator(YAML::Node node, const core::IntegratorDef& integrator);

// Reads {stiffness, damping} of one spring class; writes it as a flow mapping.
void readSpringConstants(MapReader& parent, const std::string& key, double& stiffness, double& damping,
                         const std::string& source);
YAML::Node springConstants(double stiffness, double damping);
// The stretch, shear (when `shear` is given) and bend constants of a cloth: each value the file
// gives is set, the others keep the cloth model's default.
void readClothConstants(MapReader& reader, core::ClothConstants& stretch, core::ClothConstants* shear,
                        core::ClothConstants& bend, const std::string& source);

// A list of integer particle indices.
std::vector<int> readIndexList(MapReader& reader, const std::string& key);
YAML::Node indexList(const std::vector<int>& values);
// Pins given by index (negative counts from the end) or, where `names` is given, by name.
void readPins(MapReader& reader, std::vector<int>& indices, std::vector<std::string>* names);

// A rope's, cloth's or jelly's tear_strain and self_collision, checked where its builder's validate()
// does not look: when either is set (tear_strain not 0, self_collision enabled), core::validate() of
// the network `build()` gives (their ranges, and that only a body of springs can tear), so that a
// refusal names the entry and its file line. A spring network is validated as a whole already.
template <typename BodyDef, typename Build>
void checkNetworkKeys(const MapReader& reader, const BodyDef& def, int max_particles, Build build)
{
  if (def.tear_strain != 0.0 || def.self_collision.enabled)
    check(reader, reader.field(""), core::validate(build(), max_particles));
}

// The self_collision key of ropes, cloth, jelly and spring networks: a mapping {enabled, thickness
// [m]}, each optional (core::SelfCollisionDef's defaults), no other key. Written only when enabled.
void readSelfCollision(MapReader& reader, core::SelfCollisionDef& self_collision, const std::string& source);
void writeSelfCollision(YAML::Node node, const core::SelfCollisionDef& self_collision);

// Provot's strain limit keys (max_strain, strain_iterations) of cloth and jelly.
void readStrainLimit(MapReader& reader, core::StrainLimitDef& limit);
void writeStrainLimit(YAML::Node node, const core::StrainLimitDef& limit);

// [x, y, z] as a flow sequence.
YAML::Node vector3(const Eigen::Vector3d& v);

// ---- World settings and scripted frames (world.cpp)

void readWorld(const YAML::Node& node, const std::string& source, SceneDef& scene);
void readFrames(const YAML::Node& node, const std::string& source, SceneDef& scene);
// Writes root["world"] and root["frames"].
void writeWorld(YAML::Node root, const SceneDef& scene);

// ---- One unit per body kind: read (entry `reader` of the bodies list) and write

core::EmitterDef readEmitter(MapReader& reader, const core::WorldDef& world);
YAML::Node writeEmitter(const core::EmitterDef& def);

core::RopeDef readRope(MapReader& reader, const core::WorldDef& world, const std::string& source);
YAML::Node writeRope(const core::RopeDef& def);

core::SpringNetworkDef readSpringNetwork(MapReader& reader, const core::WorldDef& world, const std::string& source);
YAML::Node writeSpringNetwork(const core::SpringNetworkDef& def);

// A grid or a mesh cloth; adds its frame pins to `scene`.
BodyDef readCloth(MapReader& reader, SceneDef& scene, const std::string& source);
YAML::Node writeClothGrid(const SceneDef& scene, const core::ClothGridDef& def);
YAML::Node writeMeshCloth(const SceneDef& scene, const core::MeshClothDef& def);

core::JellyDef readJelly(MapReader& reader, SceneDef& scene, const std::string& source);
YAML::Node writeJelly(const core::JellyDef& def);

}  // namespace body_yaml
}  // namespace scene
}  // namespace particle_sim
