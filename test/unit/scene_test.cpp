// Scene files: every shipped scene loads and builds; each kind of bad input is refused with a
// message naming the key, the value and what is allowed; toYaml() round-trips.

#include "particle_sim/scene/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <utility>
#include <vector>

#include "particle_sim/core/integrators/rk4.h"
#include "particle_sim/core/integrators/verlet.h"
#include "particle_sim/scene/obj_mesh.h"
#include "scene_test_helpers.h"
#include "shipped_scenes.h"

using namespace particle_sim;
using particle_sim_test::contains;
using particle_sim_test::expectRoundTrip;
using particle_sim_test::kShippedScenesDir;
using particle_sim_test::occurrences;
using particle_sim_test::parseOk;
using particle_sim_test::refusal;
using particle_sim_test::shippedScenes;

namespace
{
constexpr const char* kEmitterHead = "bodies:\n  - name: f\n    kind: emitter\n    type: fountain\n";

}  // namespace

TEST(SceneFiles, EveryShippedSceneLoadsAndBuilds)
{
  int count = 0;
  for (const std::string& name : shippedScenes())
  {
    ++count;
    scene::SceneDef def;
    const core::Status loaded = scene::loadSceneFile(kShippedScenesDir + "/" + name, def);
    ASSERT_TRUE(loaded.ok) << loaded.message;
    std::unique_ptr<core::World> world;
    const core::Status built = scene::buildWorld(def, world);
    ASSERT_TRUE(built.ok) << name << ": " << built.message;
    EXPECT_FALSE(world->bodies().empty()) << name;
    for (int k = 0; k < 100; ++k)
      world->step();
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
  EXPECT_TRUE(
      contains(refusal(std::string(kEmitterHead) + "    rate: fast\n"), "bodies[0].rate = 'fast' must be a number"));
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
  EXPECT_TRUE(contains(refusal(std::string(kEmitterHead) + "    origin: [0, .nan, 0]\n"),
                       "origin = [0, nan, 0] is not finite"));
  EXPECT_TRUE(contains(refusal(std::string(kEmitterHead) + "    speed: .inf\n"), "speed = inf is not a finite number"));
  EXPECT_TRUE(contains(refusal("world:\n  dt: 0.5\n"), "world.dt = 0.5 is out of range: must be in [0, 0.1]"));
  EXPECT_TRUE(contains(refusal("world:\n  ground: {restitution: 1.5}\n"), "ground.restitution = 1.5"));
  EXPECT_TRUE(contains(refusal("world:\n  spheres:\n    - {center: [0, 0, 0], radius: -1}\n"), "radius = -1"));
  EXPECT_TRUE(contains(
      refusal("world:\n  max_particles_per_body: 100\n" + std::string(kEmitterHead) + "    max_particles: 500\n"),
      "max_particles = 500 is out of range: must be in [1, 100]"));
}

TEST(SceneFiles, WorldParticleCapIsReadAndBoundsTheBodiesTogether)
{
  // Two pools of 2000 particles: within a cap of 4000, beyond one of 3999.
  const std::string bodies =
      "bodies:\n  - {name: a, kind: emitter, type: fountain, max_particles: 2000}\n"
      "  - {name: b, kind: emitter, type: fountain, max_particles: 2000}\n";
  for (int cap : {4000, 3999})
  {
    scene::SceneDef def;
    ASSERT_TRUE(
        scene::parseScene("world: {max_particles_per_world: " + std::to_string(cap) + "}\n" + bodies, "test.yaml", def)
            .ok);
    EXPECT_EQ(def.world.max_particles_per_world, cap);
    std::unique_ptr<core::World> world;
    const core::Status built = scene::buildWorld(def, world);
    EXPECT_EQ(built.ok, cap == 4000) << built.message;
    if (!built.ok)
    {
      EXPECT_TRUE(contains(built.message, "at most 3999 particles in one world"));
    }
  }
  EXPECT_TRUE(contains(refusal("world:\n  max_particles_per_world: 0\n"), "max_particles_per_world = 0"));
}

TEST(SceneFiles, WorldThreadsAreReadWrittenAndBounded)
{
  scene::SceneDef def;
  ASSERT_TRUE(scene::parseScene("world: {threads: 2}\n", "test.yaml", def).ok);
  EXPECT_EQ(def.world.threads, 2);
  scene::SceneDef defaults;
  ASSERT_TRUE(scene::parseScene("world: {}\n", "test.yaml", defaults).ok);
  EXPECT_EQ(defaults.world.threads, 0);  // one per core
  std::unique_ptr<core::World> world;
  ASSERT_TRUE(scene::buildWorld(def, world).ok);
  EXPECT_EQ(world->workers().threads(), 2);
  ASSERT_TRUE(scene::buildWorld(defaults, world).ok);
  EXPECT_EQ(world->workers().threads(), core::WorkerPool::coreCount());
  scene::SceneDef again;
  ASSERT_TRUE(scene::parseScene(scene::toYaml(def), "again.yaml", again).ok);
  EXPECT_EQ(again.world.threads, 2);
  EXPECT_TRUE(contains(refusal("world:\n  threads: -1\n"), "threads = -1 is out of range: must be in [0, 256]"));
  EXPECT_TRUE(contains(refusal("world:\n  threads: 257\n"), "threads = 257 is out of range: must be in [0, 256]"));
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

  // Every shipped scene: ropes, networks, cloth (grid and mesh, written back inline), jelly, frames.
  for (const std::string& name : shippedScenes())
  {
    ASSERT_TRUE(scene::loadSceneFile(kShippedScenesDir + "/" + name, original).ok) << name;
    const core::Status status = scene::parseScene(scene::toYaml(original), "round-trip", again);
    ASSERT_TRUE(status.ok) << name << ": " << status.message;
    EXPECT_EQ(scene::toYaml(again), scene::toYaml(original)) << name;
    EXPECT_EQ(again.frame_pins.size(), original.frame_pins.size()) << name;
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
  // A body's definition holds only what it sets; the world gives it its default when it is added.
  EXPECT_FALSE(a.integrator.type || a.integrator.cg_tolerance || a.integrator.verlet_damping);
  const auto& b = std::get<core::RopeDef>(def.bodies[1]);
  EXPECT_EQ(b.integrator.type, core::kVerletIntegrator);
  EXPECT_EQ(b.integrator.verlet_damping, 0.99);
  EXPECT_FALSE(b.integrator.cg_tolerance);
  std::unique_ptr<core::World> world;
  ASSERT_TRUE(scene::buildWorld(def, world).ok);
  EXPECT_EQ(world->findSpringBody("a")->integrator().type, core::kRk4Integrator);  // the world's default
  EXPECT_EQ(world->findSpringBody("a")->integrator().cg_tolerance, 1.0e-5);
  EXPECT_EQ(world->findSpringBody("b")->integrator().type, core::kVerletIntegrator);
  EXPECT_EQ(world->findSpringBody("b")->integrator().verlet_damping, 0.99);
  EXPECT_EQ(world->findSpringBody("b")->integrator().cg_tolerance, 1.0e-5);  // the world's
}

// Writing: a body writes only the integrator keys it sets, the world all of them.
TEST(SceneFiles, WritesOnlyTheIntegratorKeysABodySets)
{
  const scene::SceneDef def = parseOk(
      "world: {integrator: rk4, cg_tolerance: 1.0e-5, cg_velocity_tolerance: 2.0e-4}\n"
      "bodies:\n  - {name: a, kind: rope}\n  - {name: b, kind: jelly, integrator: verlet}\n");
  const std::string written = scene::toYaml(def);
  auto count = [&](const std::string& key) { return occurrences(written, key + ":"); };
  EXPECT_EQ(count("integrator"), 2) << written;  // the world's and b's
  for (const char* key : {"verlet_damping", "cg_tolerance", "cg_velocity_tolerance", "cg_max_iterations",
                          "max_substeps", "linear_solver"})
    EXPECT_EQ(count(key), 1) << key << " in\n" << written;  // the world's only
  scene::SceneDef again;
  ASSERT_TRUE(scene::parseScene(written, "written", again).ok);
  EXPECT_EQ(std::get<core::JellyDef>(again.bodies[1]).integrator.type, core::kVerletIntegrator);
  EXPECT_EQ(again.world.integrator.cg_tolerance, 1.0e-5);
  EXPECT_EQ(again.world.integrator.cg_velocity_tolerance, 2.0e-4);
}

TEST(SceneFiles, ReadsAndWritesTheLinearSolver)
{
  // world.linear_solver is every implicit body's default; a body may set its own; both read back.
  const scene::SceneDef def = parseOk(
      "world: {linear_solver: cg}\n"
      "bodies:\n  - {name: a, kind: rope}\n  - {name: b, kind: rope, linear_solver: direct}\n");
  EXPECT_EQ(def.world.integrator.linear_solver, core::LinearSolverType::ConjugateGradient);
  EXPECT_FALSE(std::get<core::RopeDef>(def.bodies[0]).integrator.linear_solver.has_value());
  EXPECT_EQ(std::get<core::RopeDef>(def.bodies[1]).integrator.linear_solver, core::LinearSolverType::Direct);
  scene::SceneDef again;
  ASSERT_TRUE(scene::parseScene(scene::toYaml(def), "written", again).ok);
  EXPECT_EQ(again.world.integrator.linear_solver, core::LinearSolverType::ConjugateGradient);
  EXPECT_EQ(std::get<core::RopeDef>(again.bodies[1]).integrator.linear_solver, core::LinearSolverType::Direct);
  EXPECT_EQ(parseOk("bodies: []\n").world.integrator.linear_solver, core::IntegratorDef().linear_solver);
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
  EXPECT_TRUE(
      contains(refusal(rope + "    integrator: euler\n"),
               "integrator = 'euler' is not an integrator; allowed: symplectic_euler, verlet, implicit_euler, rk4"));
  EXPECT_TRUE(contains(refusal(rope + "    verlet_damping: 1.5\n"), "verlet_damping = 1.5 is out of range"));
  EXPECT_TRUE(contains(refusal("world:\n  cg_max_iterations: 0\n"), "cg_max_iterations = 0 is out of range"));
  EXPECT_TRUE(contains(refusal(rope + "    linear_solver: lu\n"),
                       "bodies[0].linear_solver = 'lu' is not a linear solver; allowed: auto, cg, direct, multigrid"));

  const std::string net = "bodies:\n  - name: n\n    kind: spring_network\n";
  EXPECT_TRUE(contains(refusal(net + "    particles: []\n"), "particles must be a non-empty list"));
  EXPECT_TRUE(contains(refusal(net + "    particles: [{position: [0, 0, 0]}]\n    springs: [{particles: [0, 3]}]\n"),
                       "springs[0].j = 3 is out of range: must be in [0, 0]"));
  EXPECT_TRUE(contains(refusal(net + "    particles: [{position: [0, 0, 0]}, {position: [1, 0, 0]}]\n"
                                     "    springs: [{particles: [0]}]\n"),
                       "must be two particle indices"));
  EXPECT_TRUE(
      contains(refusal(net + "    particles: [{position: [0, 0, 0], mass: 0}]\n"), "masses[0] = 0 is out of range"));
  EXPECT_TRUE(contains(refusal(net + "    particles: [{position: [0, 0, 0]}, {position: [1, 0, 0]}]\n"
                                     "    springs: [{particles: [0, 1], class: twist}]\n"),
                       "class = 'twist' is not a spring class"));
}

TEST(SceneFiles, ReadsGridClothWithNamedPinsFramePinsAirAndFrames)
{
  const scene::SceneDef def = parseOk(
      "world:\n  air: {drag: 2, wind: [1, 2, 3]}\n"
      "  spheres:\n    - {name: tool, center: [0, 0, 1], radius: 0.1, frame: tool0}\n"
      "frames:\n  - {name: gripper, center: [0, 0, 2], radius: 0.5, period: 4}\n"
      "bodies:\n  - name: c\n    kind: cloth\n    resolution: [4, 3]\n    edge_v: [0, 0, -1]\n"
      "    shear: {stiffness: 7}\n    pins: [corner_00, 5]\n    max_strain: 0.1\n    strain_iterations: 7\n"
      "    frame_pins:\n      - {pin: corner_11, frame: gripper, offset: [0, 0, -0.1]}\n");
  EXPECT_EQ(def.world.air.drag, 2.0);
  EXPECT_EQ(def.world.air.wind, Eigen::Vector3d(1, 2, 3));
  ASSERT_EQ(def.frame_spheres.size(), 1u);
  EXPECT_EQ(def.frame_spheres[0].frame, "tool0");
  ASSERT_EQ(def.frames.size(), 1u);
  EXPECT_LT((def.frames[0].position(1.0) - Eigen::Vector3d(0, 0.5, 2)).norm(), 1e-15);  // a quarter turn
  const auto& c = std::get<core::ClothGridDef>(def.bodies[0]);
  EXPECT_EQ(c.nu, 4);
  EXPECT_EQ(c.nv, 3);
  EXPECT_EQ(c.shear.stiffness, 7.0);
  EXPECT_EQ(c.named_pins, std::vector<std::string>{"corner_00"});
  EXPECT_EQ(c.pins, (std::vector<int>{5, 11}));  // 11 = corner_11 of a 4 x 3 grid, from the frame pin
  EXPECT_EQ(c.strain_limit.max_strain, 0.1);
  EXPECT_EQ(c.strain_limit.iterations, 7);
  ASSERT_EQ(def.frame_pins.size(), 1u);
  EXPECT_EQ(def.frame_pins[0].index, 11);
  EXPECT_EQ(def.frame_pins[0].offset, Eigen::Vector3d(0, 0, -0.1));

  // Built, the frame pin starts where the scripted frame is at t = 0.
  std::unique_ptr<core::World> world;
  ASSERT_TRUE(scene::buildWorld(def, world).ok);
  EXPECT_TRUE((world->findSpringBody("c")->pinTarget(11) - Eigen::Vector3d(0.5, 0, 1.9)).norm() < 1e-12);
  ASSERT_TRUE(scene::applyScriptedFrames(def, 2.0, *world).ok);  // half a turn
  EXPECT_TRUE((world->findSpringBody("c")->pinTarget(11) - Eigen::Vector3d(-0.5, 0, 1.9)).norm() < 1e-12);
}

// The step every front-end shares: the frame pin and the sphere go where the scripted frame is at
// the end of the step (t + dt), and the world advances one step.
TEST(SceneStep, MovesScriptedFollowersToTheEndOfTheStepThenStepsTheWorld)
{
  const scene::SceneDef def = parseOk(
      "world: {dt: 0.1, spheres: [{name: ball, center: [9, 9, 9], radius: 0.1, frame: gripper}]}\n"
      "frames:\n  - {name: gripper, center: [0, 0, 2], radius: 0.5, period: 4}\n"
      "bodies:\n"
      "  - name: c\n    kind: cloth\n    resolution: [4, 3]\n"
      "    frame_pins:\n      - {pin: corner_11, frame: gripper, offset: [0, 0, -0.1]}\n");
  std::unique_ptr<core::World> world;
  ASSERT_TRUE(scene::buildWorld(def, world).ok);
  ASSERT_TRUE(scene::stepScene(def, *world).ok);
  EXPECT_EQ(world->stepCount(), 1u);
  // At t = dt = 0.1 s the frame has turned 2π · 0.1 / 4 around its centre, on a 0.5 m radius.
  const double angle = 2.0 * M_PI * 0.1 / 4.0;
  const Eigen::Vector3d frame(0.5 * std::cos(angle), 0.5 * std::sin(angle), 2.0);
  EXPECT_LT((world->findSpringBody("c")->pinTarget(11) - (frame + Eigen::Vector3d(0, 0, -0.1))).norm(), 1e-12);
  EXPECT_LT((world->findSpringBody("c")->particles().position.col(11) - (frame + Eigen::Vector3d(0, 0, -0.1))).norm(),
            1e-12);  // a pinned particle ends the step on its target
  EXPECT_LT((world->environment().spheres[0].center - frame).norm(), 1e-12);
}

// What particle_sim_run --integrator and the bench set: the world's default and every spring body.
TEST(SceneStep, EditIntegratorsReachesTheWorldAndEverySpringBody)
{
  scene::SceneDef def = parseOk(
      "world: {integrator: implicit_euler}\n"
      "bodies:\n  - {name: f, kind: emitter, type: fountain}\n  - {name: r, kind: rope}\n"
      "  - {name: n, kind: spring_network, particles: [{position: [0, 0, 1]}]}\n"
      "  - {name: g, kind: cloth}\n"
      "  - {name: m, kind: cloth, vertices: [[0, 0, 1], [1, 0, 1], [0, 1, 1]], triangles: [[0, 1, 2]]}\n"
      "  - {name: j, kind: jelly}\n");
  int edited = 0;
  scene::editIntegrators(def, [&](core::IntegratorDef& integrator) {
    integrator.type = core::kRk4Integrator;
    ++edited;
  });
  EXPECT_EQ(edited, 6);  // the world and five spring bodies; the emitter has no integrator
  EXPECT_EQ(def.world.integrator.type, core::kRk4Integrator);
  std::unique_ptr<core::World> world;
  ASSERT_TRUE(scene::buildWorld(def, world).ok);
  for (const char* name : {"r", "n", "g", "m", "j"})
  {
    ASSERT_NE(world->findSpringBody(name), nullptr) << name;
    EXPECT_EQ(world->findSpringBody(name)->integrator().type, core::kRk4Integrator) << name;
  }
}

TEST(SceneFiles, ReadsMeshClothFromAnObjFileRelativeToTheScene)
{
  scene::SceneDef def;
  const core::Status status =
      scene::loadSceneFile(std::string(PARTICLE_SIM_SOURCE_DIR) + "/config/scenes/cloth_mesh.yaml", def);
  ASSERT_TRUE(status.ok) << status.message;
  const auto& m = std::get<core::MeshClothDef>(def.bodies[0]);
  EXPECT_EQ(m.vertices.size(), 121u);
  EXPECT_EQ(m.triangles.size(), 216u);
  EXPECT_EQ(m.vertices[0], Eigen::Vector3d(0, 0, 1.3));  // the disc centre, moved by origin
}

TEST(SceneFiles, ReadsJelly)
{
  const scene::SceneDef def = parseOk(
      "bodies:\n  - {name: j, kind: jelly, size: [1, 2, 3], resolution: [2, 3, 4], velocity: [0, 0, -1], "
      "bend: {stiffness: 0}}\n");
  const auto& j = std::get<core::JellyDef>(def.bodies[0]);
  EXPECT_EQ(j.size, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(j.nz, 4);
  EXPECT_EQ(j.velocity.z(), -1.0);
  EXPECT_EQ(j.bend.stiffness, 0.0);
}

TEST(SceneFiles, RefusesBadClothJellyFramesAndMeshes)
{
  const std::string cloth = "bodies:\n  - name: c\n    kind: cloth\n";
  EXPECT_TRUE(contains(refusal(cloth + "    pins: [middle]\n"), "pins[0] = 'middle' is not a pin name"));
  EXPECT_TRUE(contains(refusal(cloth + "    resolution: [1, 5]\n"), "resolution[0] = 1 is out of range"));
  EXPECT_TRUE(contains(refusal(cloth + "    resolution: [5]\n"), "resolution must be [nu, nv]"));
  EXPECT_TRUE(contains(refusal(cloth + "    edge_v: [2, 0, 0]\n"), "must be non-zero and not parallel"));
  EXPECT_TRUE(contains(refusal(cloth + "    model: baraff\n"), "model = 'baraff' is not a cloth model"));
  EXPECT_TRUE(contains(refusal(cloth + "    max_strain: -0.1\n"), "max_strain = -0.1 is out of range"));
  EXPECT_TRUE(contains(refusal(cloth + "    frame_pins: [{pin: corner_99, frame: f}]\n"),
                       "pin = 'corner_99' is neither an index nor a pin name"));
  EXPECT_TRUE(contains(refusal(cloth + "    mesh: /nonexistent.obj\n"), "/nonexistent.obj: cannot open the mesh file"));
  EXPECT_TRUE(contains(refusal(cloth + "    vertices: [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\n    triangles: [[0, 1, 5]]\n"),
                       "triangles[0] uses vertex 5, out of range"));
  const std::string jelly = "bodies:\n  - name: j\n    kind: jelly\n";
  EXPECT_TRUE(contains(refusal(jelly + "    size: [1, 0, 1]\n"), "size[1] = 0 is out of range"));
  EXPECT_TRUE(contains(refusal(jelly + "    resolution: [100, 100, 100]\n"), "over the cap"));
  EXPECT_TRUE(contains(refusal("world:\n  air: {drag: -1}\n"), "air.drag = -1 is out of range"));
  EXPECT_TRUE(contains(refusal("frames:\n  - {name: f, period: 0}\n"), "period = 0 is out of range"));
  EXPECT_TRUE(contains(refusal("frames:\n  - {name: f}\n  - {name: f}\n"), "name = 'f' is already taken"));
}

TEST(SceneFiles, ReadsWritesAndChecksTheTearStrain)
{
  // A grid cloth and a rope that tear past 30 %, a mesh cloth, a jelly and a network that tear too,
  // and a rope that does not (no key: 0).
  const std::string text =
      "bodies:\n"
      "  - {name: c, kind: cloth, resolution: [4, 4], tear_strain: 0.3}\n"
      "  - {name: r, kind: rope, tear_strain: 0.3}\n"
      "  - {name: m, kind: cloth, vertices: [[0, 0, 0], [1, 0, 0], [0, 1, 0]], triangles: [[0, 1, 2]], "
      "tear_strain: 0.5}\n"
      "  - {name: j, kind: jelly, tear_strain: 2}\n"
      "  - {name: n, kind: spring_network, particles: [{position: [0, 0, 0]}, {position: [1, 0, 0]}], "
      "springs: [{particles: [0, 1]}], tear_strain: 0.1}\n"
      "  - {name: plain, kind: rope}\n";
  // The six bodies above, in order, with their tear strains (the plain rope's default, 0).
  auto expectTearStrains = [](const scene::SceneDef& scene_def) {
    ASSERT_EQ(scene_def.bodies.size(), 6u);
    EXPECT_EQ(std::get<core::ClothGridDef>(scene_def.bodies[0]).tear_strain, 0.3);
    EXPECT_EQ(std::get<core::RopeDef>(scene_def.bodies[1]).tear_strain, 0.3);
    EXPECT_EQ(std::get<core::MeshClothDef>(scene_def.bodies[2]).tear_strain, 0.5);
    EXPECT_EQ(std::get<core::JellyDef>(scene_def.bodies[3]).tear_strain, 2.0);
    EXPECT_EQ(std::get<core::SpringNetworkDef>(scene_def.bodies[4]).tear_strain, 0.1);
    EXPECT_EQ(std::get<core::RopeDef>(scene_def.bodies[5]).tear_strain, 0.0);
  };
  const scene::SceneDef def = parseOk(text);
  expectTearStrains(def);

  // Written back by the bodies that set it (only those), and read back the same.
  expectRoundTrip(def, "tear_strain", 5, expectTearStrains);

  // The built bodies carry it.
  std::unique_ptr<core::World> world;
  ASSERT_TRUE(scene::buildWorld(def, world).ok);
  EXPECT_EQ(world->findSpringBody("c")->definition().tear_strain, 0.3);
  EXPECT_EQ(world->findSpringBody("r")->definition().tear_strain, 0.3);
  EXPECT_EQ(world->findSpringBody("plain")->definition().tear_strain, 0.0);

  // Out of its range, in the file (named by the entry and the key, with the range), for every kind.
  EXPECT_TRUE(contains(refusal("bodies:\n  - {name: r, kind: rope, tear_strain: -1}\n"),
                       "test.yaml:2: bodies[0].tear_strain = -1 is out of range: must be in [0, 100]"));
  EXPECT_TRUE(contains(refusal("bodies:\n  - {name: c, kind: cloth, tear_strain: -1}\n"),
                       "bodies[0].tear_strain = -1 is out of range: must be in [0, 100]"));
  EXPECT_TRUE(contains(refusal("bodies:\n  - {name: j, kind: jelly, tear_strain: 101}\n"),
                       "bodies[0].tear_strain = 101 is out of range: must be in [0, 100]"));
  EXPECT_TRUE(contains(refusal("bodies:\n  - {name: n, kind: spring_network, particles: [{position: [0, 0, 0]}], "
                               "tear_strain: -1}\n"),
                       "bodies[0].tear_strain = -1 is out of range: must be in [0, 100]"));
  EXPECT_TRUE(contains(refusal("bodies:\n  - {name: r, kind: rope, tear_strain: .nan}\n"),
                       "bodies[0].tear_strain = nan is not a finite number"));
  EXPECT_TRUE(contains(refusal("bodies:\n  - {name: r, kind: rope, tear_strain: far}\n"),
                       "bodies[0].tear_strain = 'far' must be a number"));
  // A body with rod or plate bending cannot tear (yet): a rope of a material that bends is refused
  // in the file, naming the entry and the key.
  const std::string bending = refusal("bodies:\n  - {name: r, kind: rope, material: nylon_rope, tear_strain: 0.3}\n");
  EXPECT_TRUE(contains(bending, "test.yaml:2: bodies[0].tear_strain = 0.3: ")) << bending;
  EXPECT_TRUE(contains(bending, "cannot tear yet")) << bending;
}

TEST(SceneFiles, ReadsWritesAndChecksSelfCollision)
{
  // A grid cloth, a rope (the default thickness), a mesh cloth, a jelly and a network that collide
  // with themselves and each other, a rope that gives a thickness but leaves it off, and one without
  // the key (off).
  const std::string text =
      "bodies:\n"
      "  - {name: c, kind: cloth, resolution: [4, 4], self_collision: {enabled: true, thickness: 0.006}}\n"
      "  - {name: r, kind: rope, self_collision: {enabled: true}}\n"
      "  - {name: m, kind: cloth, vertices: [[0, 0, 0], [1, 0, 0], [0, 1, 0]], triangles: [[0, 1, 2]], "
      "self_collision: {thickness: 0.01, enabled: true}}\n"
      "  - {name: j, kind: jelly, self_collision: {enabled: true, thickness: 0.02}}\n"
      "  - {name: n, kind: spring_network, particles: [{position: [0, 0, 0]}, {position: [1, 0, 0]}], "
      "springs: [{particles: [0, 1]}], self_collision: {enabled: true, thickness: 0.001}}\n"
      "  - {name: off, kind: rope, self_collision: {enabled: false, thickness: 0.03}}\n"
      "  - {name: plain, kind: rope}\n";
  const double kDefault = core::SelfCollisionDef{}.thickness;  // [m]
  // The first five bodies above, in order, with their thicknesses [m]; the last is off.
  auto expectSelfCollision = [&](const scene::SceneDef& scene_def) {
    ASSERT_EQ(scene_def.bodies.size(), 7u);
    const core::SelfCollisionDef c = std::get<core::ClothGridDef>(scene_def.bodies[0]).self_collision;
    const core::SelfCollisionDef r = std::get<core::RopeDef>(scene_def.bodies[1]).self_collision;
    const core::SelfCollisionDef m = std::get<core::MeshClothDef>(scene_def.bodies[2]).self_collision;
    const core::SelfCollisionDef j = std::get<core::JellyDef>(scene_def.bodies[3]).self_collision;
    const core::SelfCollisionDef n = std::get<core::SpringNetworkDef>(scene_def.bodies[4]).self_collision;
    EXPECT_TRUE(c.enabled && r.enabled && m.enabled && j.enabled && n.enabled);
    EXPECT_EQ(c.thickness, 0.006);
    EXPECT_EQ(r.thickness, kDefault);
    EXPECT_EQ(m.thickness, 0.01);
    EXPECT_EQ(j.thickness, 0.02);
    EXPECT_EQ(n.thickness, 0.001);
    EXPECT_FALSE(std::get<core::RopeDef>(scene_def.bodies[5]).self_collision.enabled);
    EXPECT_FALSE(std::get<core::RopeDef>(scene_def.bodies[6]).self_collision.enabled);
  };
  const scene::SceneDef def = parseOk(text);
  expectSelfCollision(def);
  EXPECT_EQ(std::get<core::RopeDef>(def.bodies[5]).self_collision.thickness, 0.03);  // read, though off

  // Written back by the bodies that enable it (only those), and read back the same.
  expectRoundTrip(def, "self_collision", 5, expectSelfCollision);

  // The built bodies carry it.
  std::unique_ptr<core::World> world;
  ASSERT_TRUE(scene::buildWorld(def, world).ok);
  EXPECT_TRUE(world->findSpringBody("c")->definition().self_collision.enabled);
  EXPECT_EQ(world->findSpringBody("c")->definition().self_collision.thickness, 0.006);
  EXPECT_TRUE(world->findSpringBody("j")->definition().self_collision.enabled);
  EXPECT_EQ(world->findSpringBody("r")->definition().self_collision.thickness, kDefault);
  EXPECT_FALSE(world->findSpringBody("plain")->definition().self_collision.enabled);

  // A thickness out of its range, in the file (named by the entry and the key, with the range and
  // the unit), for every kind.
  EXPECT_TRUE(
      contains(refusal("bodies:\n  - {name: r, kind: rope, self_collision: {enabled: true, thickness: 1}}\n"),
               "test.yaml:2: bodies[0].self_collision.thickness = 1 is out of range: must be in [0.0001, 0.5] m"));
  EXPECT_TRUE(contains(refusal("bodies:\n  - {name: c, kind: cloth, self_collision: {enabled: true, thickness: 0}}\n"),
                       "bodies[0].self_collision.thickness = 0 is out of range: must be in [0.0001, 0.5] m"));
  EXPECT_TRUE(contains(refusal("bodies:\n  - {name: m, kind: cloth, vertices: [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "
                               "triangles: [[0, 1, 2]], self_collision: {enabled: true, thickness: 0.6}}\n"),
                       "bodies[0].self_collision.thickness = 0.6 is out of range: must be in [0.0001, 0.5] m"));
  EXPECT_TRUE(
      contains(refusal("bodies:\n  - {name: j, kind: jelly, self_collision: {enabled: true, thickness: -0.01}}\n"),
               "bodies[0].self_collision.thickness = -0.01 is out of range: must be in [0.0001, 0.5] m"));
  EXPECT_TRUE(contains(refusal("bodies:\n  - {name: n, kind: spring_network, particles: [{position: [0, 0, 0]}], "
                               "self_collision: {enabled: true, thickness: 0.00001}}\n"),
                       "bodies[0].self_collision.thickness = 1e-05 is out of range: must be in [0.0001, 0.5] m"));
  EXPECT_TRUE(
      contains(refusal("bodies:\n  - {name: r, kind: rope, self_collision: {enabled: true, thickness: .nan}}\n"),
               "bodies[0].self_collision.thickness = nan is not a finite number"));
  // Wrong types, unknown sub-keys and a value that is not a mapping, each at its own line.
  EXPECT_TRUE(contains(refusal("bodies:\n  - {name: r, kind: rope, self_collision: {enabled: true, thickness: far}}\n"),
                       "test.yaml:2: bodies[0].self_collision.thickness = 'far' must be a number"));
  EXPECT_TRUE(contains(refusal("bodies:\n  - name: r\n    kind: rope\n    self_collision:\n      enabled: maybe\n"),
                       "test.yaml:5: bodies[0].self_collision.enabled = 'maybe' must be true or false"));
  EXPECT_TRUE(contains(refusal("bodies:\n  - name: c\n    kind: cloth\n    self_collision:\n      enabled: true\n"
                               "      radius: 0.01\n"),
                       "test.yaml:6: bodies[0].self_collision.radius is not a known key; allowed keys: enabled, "
                       "thickness"));
  EXPECT_TRUE(contains(refusal("bodies:\n  - {name: j, kind: jelly, self_collision: true}\n"),
                       "bodies[0].self_collision must be a mapping of key: value"));
  // Emitters do not collide with themselves: the key is not theirs.
  EXPECT_TRUE(contains(refusal(std::string(kEmitterHead) + "    self_collision: {enabled: true}\n"),
                       "bodies[0].self_collision is not a known key"));
}

TEST(ObjMesh, ParsesVerticesFacesPolygonsAndTextureCoordinates)
{
  scene::ObjMesh mesh;
  const core::Status status = scene::parseObj(
      "# a quad and a triangle\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
      "f 1/1 2/2 3/3 4/4\nf -4/1 -2/3 -1/4\n",
      "quad.obj", mesh);
  ASSERT_TRUE(status.ok) << status.message;
  ASSERT_EQ(mesh.vertices.size(), 4u);
  ASSERT_EQ(mesh.triangles.size(), 3u);  // the quad as a fan of two, then the triangle
  EXPECT_EQ(mesh.triangles[0], Eigen::Vector3i(0, 1, 2));
  EXPECT_EQ(mesh.triangles[1], Eigen::Vector3i(0, 2, 3));
  EXPECT_EQ(mesh.triangles[2], Eigen::Vector3i(0, 2, 3));  // negative indices count back
  ASSERT_EQ(mesh.uvs.size(), 4u);
  EXPECT_EQ(mesh.uvs[2], Eigen::Vector2d(1, 1));

  scene::ObjMesh plain;
  ASSERT_TRUE(scene::parseObj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\n", "plain.obj", plain).ok);
  EXPECT_TRUE(plain.uvs.empty());  // no texture coordinates in the file

  EXPECT_TRUE(contains(scene::parseObj("v 0 0\n", "bad.obj", mesh).message, "bad.obj:1: a vertex needs three numbers"));
  EXPECT_TRUE(contains(scene::parseObj("v 0 0 0\nf 1 2 3\n", "bad.obj", mesh).message,
                       "bad.obj:2: face corner '2' names no vertex"));
  EXPECT_TRUE(contains(scene::parseObj("v 0 0 0\n", "bad.obj", mesh).message, "no triangles"));
}

TEST(SceneFiles, RefusesDuplicateKeysWithFileAndLine)
{
  const std::string m = refusal("world:\n  dt: 0.01\n  dt: 0.02\n");
  EXPECT_TRUE(contains(m, "test.yaml:3: world.dt is given twice (first on line 2)")) << m;
  EXPECT_TRUE(contains(refusal(std::string(kEmitterHead) + "    rate: 10\n    rate: 20\n"),
                       "test.yaml:6: bodies[0].rate is given twice (first on line 5)"));
  EXPECT_TRUE(contains(refusal("bodies:\n  - {name: r, kind: rope, stretch: {stiffness: 1, stiffness: 2}}\n"),
                       "bodies[0].stretch.stiffness is given twice"));
  EXPECT_TRUE(contains(refusal("world: {}\nworld: {}\n"), "test.yaml:2: world is given twice"));
}

TEST(SceneFiles, AcceptsWorldGlobalDampingInItsRange)
{
  const scene::SceneDef def = parseOk("world:\n  global_damping: 0.5\n");
  EXPECT_EQ(def.world.global_damping, 0.5);
  std::unique_ptr<core::World> world;
  ASSERT_TRUE(scene::buildWorld(def, world).ok);
  EXPECT_EQ(world->environment().damping, 0.5);
  EXPECT_TRUE(contains(refusal("world:\n  global_damping: 1e9\n"),
                       "world.global_damping = 1e+09 is out of range: must be in [0, 100] 1/s"));
  EXPECT_TRUE(contains(refusal("world:\n  air: {wind: [0, 0, 1e308]}\n"),
                       "air.wind.z = 1e+308 is out of range: must be in [-100, 100] m/s"));
  EXPECT_TRUE(contains(refusal("bodies:\n  - {name: r, kind: rope, stretch: {stiffness: 1e200}}\n"),
                       "stretch.stiffness = 1e+200 is out of range: must be in [0, 1e+09] N/m"));
}

// Every unknown-key message lists exactly the keys its reader accepts: each listed key, given,
// is never refused as unknown (it may be refused for its value), and the world's list has the
// integrator and global damping.
TEST(SceneFiles, EveryKeyAnUnknownKeyMessageListsIsAccepted)
{
  const std::string rope = "bodies:\n  - name: r\n    kind: rope\n";
  const std::string net = "bodies:\n  - name: n\n    kind: spring_network\n    particles:\n";
  const std::string cloth = "bodies:\n  - name: c\n    kind: cloth\n";
  const std::vector<std::pair<std::string, std::string>> readers = {
      {"world", "world:\n  KEY\n"},
      {"world.ground", "world:\n  ground:\n    KEY\n"},
      {"world.spheres[0]", "world:\n  spheres:\n    - center: [0, 0, 0]\n      radius: 1\n      KEY\n"},
      {"world.air", "world:\n  air:\n    KEY\n"},
      {"frames[0]", "frames:\n  - name: f\n    KEY\n"},
      {"bodies[0]", std::string(kEmitterHead) + "    KEY\n"},
      {"bodies[0]", rope + "    KEY\n"},
      {"bodies[0].stretch", rope + "    stretch:\n      KEY\n"},
      {"bodies[0]", net + "      - {position: [0, 0, 0]}\n      - {position: [1, 0, 0]}\n    KEY\n"},
      {"bodies[0].particles[0]", net + "      - position: [0, 0, 0]\n        KEY\n"},
      {"bodies[0].springs[0]", net + "      - {position: [0, 0, 0]}\n      - {position: [1, 0, 0]}\n    springs:\n"
                                     "      - particles: [0, 1]\n        KEY\n"},
      {"bodies[0]", cloth + "    KEY\n"},
      {"bodies[0]", cloth + "    model: baraff_witkin\n    KEY\n"},
      {"bodies[0]", cloth + "    vertices: [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\n    triangles: [[0, 1, 2]]\n    KEY\n"},
      {"bodies[0].frame_pins[0]", cloth + "    frame_pins:\n      - pin: 0\n        frame: f\n        KEY\n"},
      {"bodies[0]", "bodies:\n  - name: j\n    kind: jelly\n    KEY\n"},
  };
  const std::string marker = "allowed keys: ";
  for (const auto& [path, text] : readers)
  {
    auto with = [&, text = text](const std::string& line) {
      std::string out = text;
      out.replace(out.find("KEY"), 3, line);
      return out;
    };
    // The entry without the key is valid (where it has other keys), so that only the added key can
    // be refused.
    std::string base = text;
    base.erase(base.find("KEY"), 4);
    base.erase(base.find_last_not_of(' ') + 1);
    if (base.back() != ':' && base.substr(base.size() - 2) != ":\n") parseOk(base);

    const std::string m = refusal(with("no_such_key: 1"));
    ASSERT_TRUE(contains(m, path + ".no_such_key is not a known key")) << m;
    std::vector<std::string> allowed;
    std::stringstream list(m.substr(m.find(marker) + marker.size()));
    for (std::string key; std::getline(list, key, ',');)
      allowed.push_back(key.substr(key.find_first_not_of(' ')));
    ASSERT_GE(allowed.size(), 2u) << m;
    for (const std::string& key : allowed)
    {
      scene::SceneDef def;
      const core::Status status = scene::parseScene(with(key + ": 1"), "test.yaml", def);
      EXPECT_FALSE(contains(status.message, key + " is not a known key"))
          << path << ": '" << key << "' is listed as allowed but refused: " << status.message;
    }
    if (path == "world")
    {
      EXPECT_TRUE(contains(m, "integrator")) << m;
      EXPECT_TRUE(contains(m, "global_damping")) << m;
    }
  }
}

TEST(ObjMesh, RefusesWhatIsNotARegularFileOrIsTooLarge)
{
  scene::ObjMesh mesh;
  const core::Status device = scene::loadObjFile("/dev/zero", mesh);
  EXPECT_FALSE(device.ok);
  EXPECT_TRUE(contains(device.message, "/dev/zero: is not a regular file"));
  EXPECT_TRUE(contains(scene::loadObjFile("/tmp", mesh).message, "/tmp: is not a regular file"));

  // A sparse file one byte over the limit: refused by its size, before anything is read.
  const std::string big = (std::filesystem::temp_directory_path() / "particle_sim_too_big.obj").string();
  {
    std::ofstream out(big);
  }
  std::filesystem::resize_file(big, scene::kMaxObjFileBytes + 1);
  const core::Status too_big = scene::loadObjFile(big, mesh);
  std::filesystem::remove(big);
  EXPECT_FALSE(too_big.ok);
  EXPECT_TRUE(contains(too_big.message, "is 67108865 bytes, over the limit of 67108864 bytes"));

  // A scene naming a device gets the same refusal at the mesh key's line.
  EXPECT_TRUE(contains(refusal("bodies:\n  - name: c\n    kind: cloth\n    mesh: /dev/zero\n"),
                       "test.yaml:4: /dev/zero: is not a regular file"));
}

TEST(ObjMesh, RefusesTooManyVerticesOrTrianglesAndZeroAreaTriangles)
{
  scene::ObjMesh mesh;
  std::string vertices;
  for (std::size_t k = 0; k <= scene::kMaxObjVertices; ++k)
    vertices += "v 0 0 0\n";
  EXPECT_TRUE(
      contains(scene::parseObj(vertices, "many.obj", mesh).message, "many.obj:1000001: more than 1000000 vertices"));
  EXPECT_TRUE(mesh.vertices.size() <= scene::kMaxObjVertices);

  std::string triangles = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  for (std::size_t k = 0; k <= scene::kMaxObjTriangles; ++k)
    triangles += "f 1 2 3\n";
  EXPECT_TRUE(
      contains(scene::parseObj(triangles, "many.obj", mesh).message, "many.obj:2000004: more than 2000000 triangles"));

  // Three corners on one line, and a corner used twice: no area, no normal.
  EXPECT_TRUE(contains(scene::parseObj("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "flat.obj", mesh).message,
                       "flat.obj:4: the face has a triangle of zero area (vertices 1, 2, 3"));
  EXPECT_TRUE(contains(scene::parseObj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2\n", "flat.obj", mesh).message,
                       "flat.obj:4: the face has a triangle of zero area"));
  // Inline vertices in a scene are checked alike.
  EXPECT_TRUE(contains(refusal("bodies:\n  - name: c\n    kind: cloth\n"
                               "    vertices: [[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]]\n"
                               "    triangles: [[0, 1, 3], [0, 1, 2]]\n"),
                       "triangles[1] = [0, 1, 2] has zero area"));
}

// A received string echoed in a scene error is cut after 64 characters, at a character boundary.
TEST(SceneFiles, EchoedValuesAreCutAtACharacterBoundary)
{
  std::string long_value;
  for (int k = 0; k < 200; ++k)
    long_value += "\xC3\xA9";  // 'é', two bytes
  const std::string m = refusal(std::string(kEmitterHead) + "    rate: " + long_value + "\n");
  EXPECT_TRUE(contains(m, "bodies[0].rate = '")) << m;
  EXPECT_TRUE(contains(m, "...' (200 characters) must be a number")) << m;
  EXPECT_LT(m.size(), 250u) << m;
  const std::size_t start = m.find("rate = '") + 8;
  const std::string shown = m.substr(start, m.find("...'") - start);
  EXPECT_EQ(shown.size(), 128u) << "64 whole two-byte characters";
  const std::string kind = refusal("bodies:\n  - {name: a, kind: " + long_value + "}\n");
  EXPECT_TRUE(contains(kind, "(200 characters) is not a body kind")) << kind;
}

TEST(SceneFiles, ReadsBoxesAndCapsulesFollowingFramesAndWritesThemBack)
{
  const std::string text =
      "world:\n  dt: 0.01\n"
      "  boxes:\n    - {name: table, center: [0, 0, 0.4], size: [1.2, 0.8, 0.05], friction: 0.6}\n"
      "    - {name: pad, center: [0, 0, 2], size: [0.1, 0.02, 0.1], orientation: [0, 0, 0.7071067811865476, "
      "0.7071067811865476], frame: gripper}\n"
      "  capsules:\n    - {name: finger, center: [1, 0, 1], length: 0.3, radius: 0.02, frame: tool0}\n"
      "frames:\n  - {name: gripper, center: [0, 0, 2], radius: 0.5, period: 4}\n";
  const scene::SceneDef def = parseOk(text);
  ASSERT_EQ(def.world.boxes.size(), 2u);
  EXPECT_EQ(def.world.boxes[0].half_extents, Eigen::Vector3d(0.6, 0.4, 0.025));
  EXPECT_EQ(def.world.boxes[0].contact.friction, 0.6);
  EXPECT_NEAR(def.world.boxes[1].orientation.angularDistance(
                  Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2.0, Eigen::Vector3d::UnitZ()))),
              0.0, 1e-12);
  ASSERT_EQ(def.world.capsules.size(), 1u);
  EXPECT_EQ(def.world.capsules[0].half_length, 0.15);
  EXPECT_EQ(def.world.capsules[0].radius, 0.02);
  ASSERT_EQ(def.frame_colliders.size(), 2u);
  EXPECT_EQ(def.frame_colliders[0].collider, "pad");
  EXPECT_EQ(def.frame_colliders[1].frame, "tool0");

  // Written and read again: the same colliders and followers.
  const scene::SceneDef again = parseOk(scene::toYaml(def));
  ASSERT_EQ(again.world.boxes.size(), 2u);
  EXPECT_EQ(again.world.boxes[1].center, def.world.boxes[1].center);
  EXPECT_EQ(again.world.boxes[1].half_extents, def.world.boxes[1].half_extents);
  EXPECT_EQ(again.world.boxes[1].orientation.coeffs(), def.world.boxes[1].orientation.coeffs());
  EXPECT_EQ(again.world.capsules[0].half_length, def.world.capsules[0].half_length);
  ASSERT_EQ(again.frame_colliders.size(), 2u);
  EXPECT_EQ(again.frame_colliders[0].frame, "gripper");

  // Built, the pad starts on the scripted frame at rest; each step moves it to the frame's next
  // position with the frame's velocity (the circle's, 2π · 0.5 m / 4 s, to the chord's accuracy),
  // keeping its own orientation. The tf-only capsule stays where the file puts it.
  std::unique_ptr<core::World> world;
  ASSERT_TRUE(scene::buildWorld(def, world).ok);
  const core::BoxColliderDef& pad = world->environment().boxes[1];
  EXPECT_LT((pad.center - def.frames[0].position(0.0)).norm(), 1e-15);
  EXPECT_EQ(pad.motion.velocity, Eigen::Vector3d::Zero());
  ASSERT_TRUE(scene::stepScene(def, *world).ok);
  EXPECT_LT((pad.center - def.frames[0].position(0.01)).norm(), 1e-15);
  const double speed = 2.0 * M_PI * 0.5 / 4.0;
  EXPECT_NEAR(pad.motion.velocity.norm(), speed, 1e-4);
  EXPECT_NEAR(pad.motion.velocity.y(), speed, 1e-3);  // at t = 0 the circle runs along +y
  EXPECT_EQ(pad.orientation.coeffs(), def.world.boxes[1].orientation.coeffs());
  EXPECT_EQ(world->environment().capsules[0].center, Eigen::Vector3d(1, 0, 1));
}

TEST(SceneFiles, RefusesBadBoxesAndCapsulesNamingTheField)
{
  EXPECT_TRUE(contains(refusal("world:\n  boxes: [{center: [0, 0, 0]}]\n"), "world.boxes[0] needs the key 'size'"));
  EXPECT_TRUE(contains(refusal("world:\n  boxes: [{center: [0, 0, 0], size: [1, 1, 0]}]\n"),
                       "box 'box_0'.half_extents[2] = 0 is out of range"));
  EXPECT_TRUE(contains(refusal("world:\n  boxes: [{center: [0, 0, 0], size: [1, 1, 1], orientation: [0, 0, 0, 2]}]\n"),
                       "is not a unit quaternion"));
  EXPECT_TRUE(contains(refusal("world:\n  boxes: [{center: [0, 0, 0], size: [1, 1, 1], orientation: [0, 0, 1]}]\n"),
                       "world.boxes[0].orientation must be a list of 4 numbers [x, y, z, w]"));
  EXPECT_TRUE(contains(refusal("world:\n  capsules: [{center: [0, 0, 0], length: 1, radius: 0.1, colour: red}]\n"),
                       "world.capsules[0].colour is not a known key"));
  EXPECT_TRUE(contains(refusal("world:\n  capsules: [{center: [0, 0, 0], length: -1, radius: 0.1}]\n"),
                       "capsule 'capsule_0'.half_length = -0.5 is out of range"));
}

TEST(SceneFiles, AFrameWithWaypointsPassesThemWithMinimumJerkAndIsWrittenBack)
{
  // Through (0,0,1) at 1 s and (1,0,1) at 3 s, then (1,0,2) at 4 s: on each waypoint at its time,
  // halfway at the middle of a leg (s(1/2) = 1/2), at a quarter 10/64 − 15/256 + 6/1024 of the way
  // (s(u) = 10u³ − 15u⁴ + 6u⁵), still before the first and after the last, and with zero velocity
  // at a waypoint (central difference).
  const scene::SceneDef def = parseOk(
      "frames:\n  - name: hand\n    waypoints:\n      - {t: 1, position: [0, 0, 1]}\n"
      "      - {t: 3, position: [1, 0, 1]}\n      - {t: 4, position: [1, 0, 2]}\n");
  ASSERT_EQ(def.frames.size(), 1u);
  const scene::ScriptedFrameDef& hand = def.frames[0];
  ASSERT_EQ(hand.waypoints.size(), 3u);
  EXPECT_EQ(hand.position(0.0), Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(hand.position(1.0), Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(hand.position(3.0), Eigen::Vector3d(1, 0, 1));
  EXPECT_EQ(hand.position(9.0), Eigen::Vector3d(1, 0, 2));
  EXPECT_NEAR(hand.position(2.0).x(), 0.5, 1e-15);
  const double quarter = 10.0 / 64.0 - 15.0 / 256.0 + 6.0 / 1024.0;
  EXPECT_NEAR(hand.position(1.5).x(), quarter, 1e-15);
  EXPECT_NEAR(hand.position(3.5).z(), 1.5, 1e-15);
  const double dt = 1e-4;
  EXPECT_LT((hand.position(3.0 + dt) - hand.position(3.0 - dt)).norm() / (2 * dt), 1e-6);

  const scene::SceneDef again = parseOk(scene::toYaml(def));
  ASSERT_EQ(again.frames[0].waypoints.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k)
  {
    EXPECT_EQ(again.frames[0].waypoints[k].t, hand.waypoints[k].t);
    EXPECT_EQ(again.frames[0].waypoints[k].position, hand.waypoints[k].position);
  }
}

TEST(SceneFiles, RefusesBadWaypointsNamingTheField)
{
  const std::string frame = "frames:\n  - name: f\n    waypoints: ";
  EXPECT_TRUE(contains(refusal(frame + "[]\n"), "frames[0].waypoints must be a non-empty list of {t, position}"));
  EXPECT_TRUE(contains(refusal(frame + "[{t: 1}]\n"), "frames[0].waypoints[0] needs the key 'position'"));
  EXPECT_TRUE(contains(refusal(frame + "[{t: 1, position: [0, 0, 0]}, {t: 1, position: [1, 0, 0]}]\n"),
                       "frames[0].waypoints[1].t = 1 s must be later than the waypoint before it (1 s)"));
  EXPECT_TRUE(contains(refusal(frame + "[{t: 0, position: [0, 0]}]\n"),
                       "frames[0].waypoints[0].position = [0, 0] must be a list of 3 numbers"));
  EXPECT_TRUE(contains(refusal(frame + "[{t: 0, position: [0, 0, 0]}]\n    radius: 1\n"),
                       "frames[0].radius is a circle's; a frame with waypoints follows them only"));
}
