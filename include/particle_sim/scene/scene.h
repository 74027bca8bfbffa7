#pragma once

#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "particle_sim/core/emitter.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/status.h"
#include "particle_sim/core/world.h"

namespace particle_sim
{
namespace scene
{
/// One body entry of a scene file, as the core definition it builds.
using BodyDef = std::variant<core::EmitterDef, core::RopeDef, core::SpringNetworkDef>;

/// A whole scene: world settings and named bodies, in file order.
struct SceneDef
{
  core::WorldDef world;
  std::vector<BodyDef> bodies;
};

/// Parses scene YAML text. Unknown keys, wrong types and out-of-range or non-finite values are
/// refused with a message that starts with `source:line:` and names the key, the value and what is
/// allowed. Values are checked by the same core validate() functions the node's services use.
core::Status parseScene(const std::string& yaml_text, const std::string& source, SceneDef& scene);

/// Reads and parses a scene file.
core::Status loadSceneFile(const std::string& path, SceneDef& scene);

/// Builds a world with every body of `scene`.
core::Status buildWorld(const SceneDef& scene, std::unique_ptr<core::World>& world);

/// Adds one body definition to a world (used by buildWorld and by the node's spawn services).
core::Status addBody(const BodyDef& body, core::World& world);

/// Writes `scene` back as YAML that parseScene() reads into the same definitions.
std::string toYaml(const SceneDef& scene);

}  // namespace scene
}  // namespace particle_sim
