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
  EXPECT_GE(count, 5);  // one per emitter and the demo
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
}
