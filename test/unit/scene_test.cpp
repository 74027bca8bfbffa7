// Scene files: every shipped scene loads and builds; each kind of bad input is refused with a
// message naming the key, the value and what is allowed; toYaml() round-trips.

#include <gtest/gtest.h>

#include <filesystem>

#include "particle_sim/scene/scene.h"

using namespace particle_sim;

namespace
{
scene::SceneDef parseOk(const std::string& text)
{
  scene::SceneDef def;
  const core::Status status = scene::parseScene(text, "test.yaml", def);
  EXPECT_TRUE(status.ok) << status.message;
  return def;
}

// Parses `text`, expects a refusal and returns its message.
std::string refusal(const std::string& text)
{
  scene::SceneDef def;
  const core::Status status = scene::parseScene(text, "test.yaml", def);
  EXPECT_FALSE(status.ok) << "accepted:\n" << text;
  return status.message;
}

constexpr const char* kEmitterHead = "bodies:\n  - name: f\n    kind: emitter\n    type: fountain\n";

::testing::AssertionResult contains(const std::string& message, const std::string& part)
{
  if (message.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << message << "' does not contain '" << part << "'";
}
}  // namespace

TEST(SceneFiles, EveryShippedSceneLoadsAndBuilds)
{
  int count = 0;
  for (const auto& entry :
       std::filesystem::recursive_directory_iterator(std::string(PARTICLE_SIM_SOURCE_DIR) + "/config/scenes"))
  {
    if (entry.path().extension() != ".yaml") continue;
    ++count;
    scene::SceneDef def;
    const core::Status loaded = scene::loadSceneFile(entry.path().string(), def);
    ASSERT_TRUE(loaded.ok) << loaded.message;
    std::unique_ptr<core::World> world;
    const core::Status built = scene::buildWorld(def, world);
    ASSERT_TRUE(built.ok) << entry.path() << ": " << built.message;
    EXPECT_FALSE(world->bodies().empty()) << entry.path();
    for (int k = 0; k < 100; ++k) world->step();
  }
  EXPECT_GE(count, 8);  // one per emitter, the demo, ropes and a network
}

TEST(SceneFiles, ReadsWorldAndEmitterValues)
{
  const scene::SceneDef def = parseOk(
      "world:\n  gravity: [0, 0, -3.5]\n  dt: 0.002\n  seed: 9\n"
      "  ground: {height: 0.25, restitution: 0.1, friction: 0.7}\n"
      "  spheres:\n    - {name: s, center: [1, 2, 3], radius: 0.5}\n"
      "bodies:\n  - {name: w, kind: emitter, type: waterfall, origin: [0, 0, 4], rate: 20, lifetime: 1.5}\n");
  EXPECT_EQ(def.world.gravity, Eigen::Vector3d(0, 0, -3.5));
  EXPECT_EQ(def.world.dt, 0.002);
  EXPECT_EQ(def.world.ground.height, 0.25);
  EXPECT_EQ(def.world.ground.contact.friction, 0.7);
  ASSERT_EQ(def.world.spheres.size(), 1u);
  EXPECT_EQ(def.world.spheres[0].center, Eigen::Vector3d(1, 2, 3));
  ASSERT_EQ(def.bodies.size(), 1u);
  const auto& e = std::get<core::EmitterDef>(def.bodies[0]);
  EXPECT_EQ(e.type, core::EmitterType::Waterfall);
  EXPECT_EQ(e.speed, 0.0);  // the waterfall's default vertical speed
  EXPECT_EQ(e.rate, 20.0);
  EXPECT_EQ(e.lifetime, 1.5);
  EXPECT_EQ(e.seed, core::deriveSeed(9, "w"));
}

TEST(SceneFiles, RefusesUnknownKeysNamingThemAndTheAllowedOnes)
{
  const std::string m = refusal(std::string(kEmitterHead) + "    rtae: 10\n");
  EXPECT_TRUE(contains(m, "test.yaml:5"));
  EXPECT_TRUE(contains(m, "bodies[0].rtae is not a known key"));
  EXPECT_TRUE(contains(m, "rate"));
  EXPECT_TRUE(contains(refusal("world:\n  gravty: [0, 0, -9.81]\n"), "world.gravty is not a known key"));
  EXPECT_TRUE(contains(refusal("wrld: {}\n"), "wrld is not a known key"));
}

TEST(SceneFiles, RefusesWrongTypes)
{
  EXPECT_TRUE(contains(refusal(std::string(kEmitterHead) + "    rate: fast\n"), "bodies[0].rate = 'fast' must be a number"));
  EXPECT_TRUE(contains(refusal(std::string(kEmitterHead) + "    origin: [0, 1]\n"), "must be a list of 3 numbers"));
  EXPECT_TRUE(contains(refusal(std::string(kEmitterHead) + "    max_particles: 1.5\n"), "must be an integer"));
  EXPECT_TRUE(contains(refusal("world:\n  ground: {enabled: maybe}\n"), "must be true or false"));
  EXPECT_TRUE(contains(refusal("bodies: {name: x}\n"), "bodies must be a list"));
}

TEST(SceneFiles, RefusesOutOfRangeAndNonFiniteValues)
{
  EXPECT_TRUE(contains(refusal(std::string(kEmitterHead) + "    rate: -3\n"),
                       "bodies[0].rate = -3 is out of range: must be >= 0"));
  EXPECT_TRUE(contains(refusal(std::string(kEmitterHead) + "    lifetime: 0\n"), "lifetime = 0 is out of range"));
  EXPECT_TRUE(contains(refusal(std::string(kEmitterHead) + "    origin: [0, .nan, 0]\n"), "origin = [0, nan, 0] is not finite"));
  EXPECT_TRUE(contains(refusal(std::string(kEmitterHead) + "    speed: .inf\n"), "speed = inf is not a finite number"));
  EXPECT_TRUE(contains(refusal("world:\n  dt: 0.5\n"), "world.dt = 0.5 is out of range: must be in [0, 0.1]"));
  EXPECT_TRUE(contains(refusal("world:\n  ground: {restitution: 1.5}\n"), "ground.restitution = 1.5"));
  EXPECT_TRUE(contains(refusal("world:\n  spheres:\n    - {center: [0, 0, 0], radius: -1}\n"), "radius = -1"));
  EXPECT_TRUE(contains(refusal("world:\n  max_particles_per_body: 100\n" + std::string(kEmitterHead) +
                               "    max_particles: 500\n"),
                       "max_particles = 500 is out of range: must be in [1, 100]"));
}

TEST(SceneFiles, RefusesUnknownKindsTypesDuplicatesMissingKeysAndBadYaml)
{
  EXPECT_TRUE(contains(refusal("bodies:\n  - {name: a, kind: blob}\n"), "kind = 'blob' is not a body kind"));
  EXPECT_TRUE(contains(refusal("bodies:\n  - {name: a, kind: emitter, type: geyser}\n"),
                       "type = 'geyser' is not an emitter type; allowed: fountain, waterfall, semi_sphere, explosion"));
  EXPECT_TRUE(contains(refusal("bodies:\n  - {name: a, kind: emitter, type: fountain}\n"
                               "  - {name: a, kind: emitter, type: fountain}\n"),
                       "name = 'a' is already taken"));
  EXPECT_TRUE(contains(refusal("bodies:\n  - {kind: emitter, type: fountain}\n"), "needs the key 'name'"));
  EXPECT_TRUE(contains(refusal("bodies: [\n"), "not valid YAML"));
  EXPECT_TRUE(contains(refusal(""), "the scene is empty"));
}

TEST(SceneFiles, LoadFileReportsAMissingFile)
{
  scene::SceneDef def;
  const core::Status status = scene::loadSceneFile("/nonexistent/scene.yaml", def);
  EXPECT_FALSE(status.ok);
  EXPECT_TRUE(contains(status.message, "/nonexistent/scene.yaml: cannot open"));
}

TEST(SceneFiles, ToYamlRoundTripsEveryDefinition)
{
  scene::SceneDef original;
  ASSERT_TRUE(scene::loadSceneFile(std::string(PARTICLE_SIM_SOURCE_DIR) + "/config/scenes/demo.yaml", original).ok);
  scene::SceneDef again;
  const core::Status status = scene::parseScene(scene::toYaml(original), "round-trip", again);
  ASSERT_TRUE(status.ok) << status.message;
  EXPECT_EQ(scene::toYaml(again), scene::toYaml(original));
  ASSERT_EQ(again.bodies.size(), original.bodies.size());
  const auto& a = std::get<core::EmitterDef>(original.bodies[3]);
  const auto& b = std::get<core::EmitterDef>(again.bodies[3]);
  EXPECT_EQ(a.origin, b.origin);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.burst_count, b.burst_count);
  EXPECT_EQ(again.world.spheres[0].radius, original.world.spheres[0].radius);

  // Ropes and networks too.
  for (const char* name : {"rope_bridge", "spring_network"})
  {
    ASSERT_TRUE(scene::loadSceneFile(std::string(PARTICLE_SIM_SOURCE_DIR) + "/config/scenes/" + name + ".yaml", original).ok);
    const core::Status status = scene::parseScene(scene::toYaml(original), "round-trip", again);
    ASSERT_TRUE(status.ok) << status.message;
    EXPECT_EQ(scene::toYaml(again), scene::toYaml(original)) << name;
  }
}

TEST(SceneFiles, ReadsRopesWithWorldIntegratorDefaultsAndOverrides)
{
  const scene::SceneDef def = parseOk(
      "world:\n  integrator: rk4\n  cg_tolerance: 1.0e-5\n"
      "bodies:\n"
      "  - name: a\n    kind: rope\n    particles: 8\n    start: [0, 0, 1]\n    end: [0, 0, 3]\n    mass: 0.4\n"
      "    rest_length: 2.5\n    stretch: {stiffness: 300, damping: 0.2}\n    bend: {stiffness: 5}\n    pins: [0, -1]\n"
      "  - name: b\n    kind: rope\n    integrator: verlet\n    verlet_damping: 0.99\n");
  ASSERT_EQ(def.bodies.size(), 2u);
  const auto& a = std::get<core::RopeDef>(def.bodies[0]);
  EXPECT_EQ(a.particles, 8);
  EXPECT_EQ(a.end, Eigen::Vector3d(0, 0, 3));
  EXPECT_EQ(a.rest_length, 2.5);
  EXPECT_EQ(a.stretch_stiffness, 300.0);
  EXPECT_EQ(a.bend_stiffness, 5.0);
  EXPECT_EQ(a.pins, (std::vector<int>{0, -1}));
  EXPECT_EQ(a.integrator.type, core::IntegratorType::Rk4);  // the world's default
  EXPECT_EQ(a.integrator.cg_tolerance, 1.0e-5);
  const auto& b = std::get<core::RopeDef>(def.bodies[1]);
  EXPECT_EQ(b.integrator.type, core::IntegratorType::Verlet);
  EXPECT_EQ(b.integrator.verlet_damping, 0.99);
}

TEST(SceneFiles, ReadsSpringNetworksWithInitialAndGivenRestLengths)
{
  const scene::SceneDef def = parseOk(
      "bodies:\n  - name: net\n    kind: spring_network\n    particles:\n"
      "      - {position: [0, 0, 0], mass: 0.5}\n      - {position: [3, 4, 0], mass: 0.25, velocity: [1, 0, 0]}\n"
      "      - {position: [0, 0, 2]}\n"
      "    springs:\n      - {particles: [0, 1], stiffness: 10}\n"
      "      - {particles: [0, 2], rest_length: 1.5, damping: 0.1, class: bend}\n"
      "      - {particles: [1, 2], rest_length: initial}\n"
      "    pins: [2]\n");
  const auto& net = std::get<core::SpringNetworkDef>(def.bodies[0]);
  ASSERT_EQ(net.positions.size(), 3u);
  EXPECT_EQ(net.masses[1], 0.25);
  ASSERT_EQ(net.velocities.size(), 3u);
  EXPECT_EQ(net.velocities[1], Eigen::Vector3d(1, 0, 0));
  ASSERT_EQ(net.springs.size(), 3u);
  EXPECT_EQ(net.springs[0].rest_length, 5.0);  // "initial" by default: |(3, 4, 0)|
  EXPECT_EQ(net.springs[0].stiffness, 10.0);
  EXPECT_EQ(net.springs[1].rest_length, 1.5);
  EXPECT_EQ(net.springs[1].spring_class, core::SpringClass::Bend);
  EXPECT_NEAR(net.springs[2].rest_length, std::sqrt(9.0 + 16.0 + 4.0), 1e-12);
  EXPECT_EQ(net.pins, std::vector<int>{2});
}

TEST(SceneFiles, RefusesBadRopesAndNetworks)
{
  const std::string rope = "bodies:\n  - name: r\n    kind: rope\n";
  EXPECT_TRUE(contains(refusal(rope + "    particles: 1\n"), "bodies[0].particles = 1 is out of range"));
  EXPECT_TRUE(contains(refusal(rope + "    stretch: {stiffness: -2}\n"), "stretch.stiffness = -2 is out of range"));
  EXPECT_TRUE(contains(refusal(rope + "    stretch: {stifness: 2}\n"), "stretch.stifness is not a known key"));
  EXPECT_TRUE(contains(refusal(rope + "    pins: [0, 25]\n"), "pins[1] = 25 is out of range"));
  EXPECT_TRUE(contains(refusal(rope + "    pins: [first]\n"), "pins[0] must be an integer"));
  EXPECT_TRUE(contains(refusal(rope + "    integrator: euler\n"),
                       "integrator = 'euler' is not an integrator; allowed: symplectic_euler, verlet, implicit_euler, rk4"));
  EXPECT_TRUE(contains(refusal(rope + "    verlet_damping: 1.5\n"), "verlet_damping = 1.5 is out of range"));
  EXPECT_TRUE(contains(refusal("world:\n  cg_max_iterations: 0\n"), "cg_max_iterations = 0 is out of range"));

  const std::string net = "bodies:\n  - name: n\n    kind: spring_network\n";
  EXPECT_TRUE(contains(refusal(net + "    particles: []\n"), "particles must be a non-empty list"));
  EXPECT_TRUE(contains(refusal(net + "    particles: [{position: [0, 0, 0]}]\n    springs: [{particles: [0, 3]}]\n"),
                       "springs[0].j = 3 is out of range: must be in [0, 0]"));
  EXPECT_TRUE(contains(refusal(net + "    particles: [{position: [0, 0, 0]}, {position: [1, 0, 0]}]\n"
                                     "    springs: [{particles: [0]}]\n"),
                       "must be two particle indices"));
  EXPECT_TRUE(contains(refusal(net + "    particles: [{position: [0, 0, 0], mass: 0}]\n"), "masses[0] = 0 is out of range"));
  EXPECT_TRUE(contains(refusal(net + "    particles: [{position: [0, 0, 0]}, {position: [1, 0, 0]}]\n"
                                     "    springs: [{particles: [0, 1], class: twist}]\n"),
                       "class = 'twist' is not a spring class"));
}
