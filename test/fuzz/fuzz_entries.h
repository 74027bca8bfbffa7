#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "particle_sim/Grasp.h"
#include "particle_sim/PinParticle.h"
#include "particle_sim/SetSpringConstants.h"
#include "particle_sim/SetWind.h"
#include "particle_sim/SpawnCloth.h"
#include "particle_sim/SpawnCollider.h"
#include "particle_sim/SpawnEmitter.h"
#include "particle_sim/SpawnJelly.h"
#include "particle_sim/SpawnRope.h"
#include "particle_sim/core/status.h"
#include "particle_sim/ros/parameters.h"

// The entry functions of the fuzz targets (test/fuzz/targets/, built with clang and libFuzzer by
// scripts/fuzz) and of their regression replay (test/unit/fuzz_regressions_test.cpp, built with gcc
// by scripts/test). Each feeds one input to a reader of user input and then runs what the reader
// built, as the node and particle_sim_run do, so that a definition that passes validation but
// breaks the core is found too. An input never makes them fail on purpose: what they look for is a
// crash, a leak or undefined behaviour, which the sanitizers report.
namespace particle_sim
{
namespace fuzz
{
/// Largest body the fuzzed worlds accept [particles] (the node's ~max_particles_per_body): small
/// enough that a few steps of the biggest body take milliseconds under the sanitizers.
constexpr int kMaxParticlesPerBody = 2000;
/// Steps run after a scene or mesh is built, and the most steps of one fuzzed ~step request.
constexpr int kMaxSteps = 8;
/// Most conjugate-gradient iterations of an implicit solve and most substeps of an explicit step
/// in a fuzzed world (the scene's own values when smaller): a scene may ask for thousands, which
/// makes one input take a minute under the sanitizers and says nothing new.
constexpr int kMaxCgIterations = 50;
constexpr int kMaxSubsteps = 8;

/// Scene YAML text: parseScene (as if read from config/scenes/, so that relative mesh paths reach
/// the shipped meshes), buildWorld (bodies up to kMaxParticlesPerBody, solver work capped),
/// kMaxSteps of stepScene, and toYaml read back by parseScene.
int runSceneYaml(const std::uint8_t* data, std::size_t size);

/// OBJ text: parseObj, then a spring cloth of the mesh (and a Baraff–Witkin one when the mesh
/// has texture coordinates) added to a world and stepped kMaxSteps times.
int runObjMesh(const std::uint8_t* data, std::size_t size);

/// Node settings and then a sequence of service requests, decoded from the bytes (RequestCodec):
/// the settings are checked by validate(NodeSettings) and build the world as the node does; each
/// request goes through the node's conversion (request_conversions, spring_constants) and, when
/// that yields a definition or a change, into the world, which ~step requests advance.
int runRequests(const std::uint8_t* data, std::size_t size);

/// The answer to each request of runRequests: success and message, in order.
struct RequestAnswer
{
  std::string service;
  bool success = false;
  std::string message;
};
/// runRequests, returning every answer (what the unit tests check; the fuzz target ignores them).
std::vector<RequestAnswer> answerRequests(const std::uint8_t* data, std::size_t size);

/// One request of the sequence runRequests decodes. `service` says which field is used.
struct Request
{
  enum class Service : std::uint8_t
  {
    SpawnEmitter,
    SpawnRope,
    SpawnCloth,
    SpawnJelly,
    SetWind,
    PinParticle,
    UnpinParticle,
    SetSpringConstants,
    RemoveBody,
    Step,
    Reset,
    Grasp,
    Release,
    SpawnCollider,
    RemoveCollider,
    Count  ///< not a service: the number of them
  };
  Service service = Service::Step;
  SpawnEmitter::Request spawn_emitter;
  SpawnRope::Request spawn_rope;
  SpawnCloth::Request spawn_cloth;
  SpawnJelly::Request spawn_jelly;
  SetWind::Request set_wind;
  PinParticle::Request pin_particle;
  std::string body;        ///< UnpinParticle, RemoveBody
  std::int32_t index = 0;  ///< UnpinParticle
  SetSpringConstants::Request set_spring_constants;
  std::uint32_t steps = 1;  ///< Step, in [1, kMaxSteps]
  Grasp::Request grasp;     ///< Grasp (the gripper frame is taken to be at the sim frame's origin)
  std::string grasp_name;   ///< Release
  SpawnCollider::Request spawn_collider;
  std::string collider;  ///< RemoveCollider
};

/// The bytes runRequests decodes into `settings` (node parameters; scene_path is not read) and
/// `requests`: what the seed corpus of README's service calls is written with, and what a test
/// uses to check that the decoding reaches the conversions.
std::vector<std::uint8_t> encodeRequests(const ros_interface::NodeSettings& settings,
                                         const std::vector<Request>& requests);

/// A named sequence of requests of the seed corpus of the requests target.
struct RequestSeed
{
  std::string name;
  std::vector<Request> requests;
};
/// The README's service calls (section "Services") as one session, each spawn request with the
/// .srv defaults, each other service once, and ropes and cloth of materials (a preset, a preset
/// with a value replaced, by value): the seed corpus of the requests target
/// (scripts/fuzz writes them with encodeRequests and the default NodeSettings).
std::vector<RequestSeed> requestSeeds();

/// The names of the fuzz targets, each with its entry function: the folders of
/// test/fuzz_regressions/ and the programs scripts/fuzz builds.
struct Target
{
  const char* name;
  int (*entry)(const std::uint8_t* data, std::size_t size);
};
const std::vector<Target>& targets();

}  // namespace fuzz
}  // namespace particle_sim
