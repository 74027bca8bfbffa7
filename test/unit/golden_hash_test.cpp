// Golden determinism test (Box2D's style): every shipped scene (config/scenes, subfolders
// included), run with each integrator of the core for 2 s of sim time at its own dt, ends in a full
// state whose FNV-1a 64 hash (worldStateHash in test_helpers.h: every live particle's position,
// velocity, previous position, inverse mass and age, emitters' counts, pins, the step count) is
// the one recorded in test/golden/state_hashes.txt, bit for bit. A refactoring that keeps the
// physics keeps every hash; any change of any bit of any state shows up here, named by scene and
// integrator. The pairs run on every core at once (each an independent world), so the sweep also
// checks that worlds stepped side by side share no state.
//
// The integrator is applied the way `particle_sim_run --integrator NAME` means it: to every spring
// body of the scene (rope, network, cloth, jelly), after the scene is built, keeping the body's
// other integrator settings (on the tree of 2026-11-23 this gave, for all 170 pairs, the same
// state as setting it in every body's definition before the build). Each step is scene::stepScene,
// the step every front-end shares: it first moves what follows scripted frames, then steps the
// world. A frame that only tf provides (not scripted in the scene) is not moved offline: what
// follows it stays where the scene puts it, which is what the core does without a node. A body
// that freezes (an explicit method that blows up even with its most substeps) is hashed where it
// stopped; the golden file's comments list such pairs.
//
// A deliberate physics change regenerates the golden file in its own commit, saying why:
//
//   PARTICLE_SIM_UPDATE_GOLDEN=1 $PARTICLE_SIM_BUILD/devel/lib/particle_sim/particle_sim_unit_tests
//       --gtest_filter='GoldenHash*'      (one command, on one line)
//
// With PARTICLE_SIM_UPDATE_GOLDEN=1 the test rewrites the file (source tree, test/golden/) instead
// of comparing; `git diff test/golden` then shows which scene × integrator pairs changed. A scene
// file or an integrator added later fails as "not in the golden file" until the file is
// regenerated, which then adds lines and changes none.

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "particle_sim/core/integrator.h"
#include "particle_sim/core/integrators/cg_avx2.h"
#include "particle_sim/core/integrators/implicit_euler_solver.h"
#include "particle_sim/core/world.h"
#include "particle_sim/scene/scene.h"
#include "shipped_scenes.h"
#include "test_helpers.h"

namespace core = particle_sim::core;
namespace scene = particle_sim::scene;
using particle_sim_test::Fnv1a64;
using particle_sim_test::kShippedScenesDir;
using particle_sim_test::shippedScenes;
using particle_sim_test::worldStateHash;

namespace
{
constexpr double kSimTime = 2.0;  // [s] simulated per scene and integrator
const std::string kGoldenFile = std::string(PARTICLE_SIM_SOURCE_DIR) + "/test/golden/state_hashes.txt";

// Scene × integrator pairs that are not run, each with its reason (written to the golden file as
// `scene integrator excluded: reason`). Empty: every pair runs.
struct Exclusion
{
  const char* scene;
  const char* integrator;
  const char* reason;
};
const std::vector<Exclusion> kExclusions = {};

// The core's integrator names, in its order ("symplectic_euler, verlet, ..."), so that an
// integrator added to the core is hashed too.
std::vector<std::string> coreIntegratorNames()
{
  std::vector<std::string> names;
  std::stringstream list(core::integratorTypeNames());
  std::string name;
  while (std::getline(list, name, ','))
  {
    const auto first = name.find_first_not_of(' ');
    const auto last = name.find_last_not_of(' ');
    if (first != std::string::npos) names.push_back(name.substr(first, last - first + 1));
  }
  return names;
}

std::string hex(std::uint64_t value)
{
  char text[17];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(value));
  return text;
}

// Runs `scene_def` for kSimTime with `type` on every spring body; the hash of the final state as
// 16 hex digits, or "error: ..." when the scene cannot be built or the integrator not applied.
// Bodies that froze (their state is hashed where they stopped) are added to `frozen`.
// `shared_loops` adds the loops the world's step shared between its threads.
std::string runAndHash(const scene::SceneDef& scene_def, core::IntegratorType type, std::vector<std::string>& frozen,
                       std::atomic<std::uint64_t>& shared_loops)
{
  std::unique_ptr<core::World> world;
  if (const core::Status built = scene::buildWorld(scene_def, world); !built) return "error: " + built.message;
  for (const auto& body : world->bodies())
  {
    core::SpringNetworkBody* spring_body = world->findSpringBody(body->name());
    if (!spring_body) continue;
    core::IntegratorDef integrator = spring_body->integrator();
    integrator.type = type;
    if (const core::Status set = spring_body->setIntegrator(integrator); !set) return "error: " + set.message;
  }
  // The step count of particle_sim_run --duration 2.
  const auto steps = static_cast<std::uint64_t>(std::ceil(kSimTime / world->dt() - 1e-9));
  for (std::uint64_t k = 0; k < steps; ++k)
    scene::stepScene(scene_def, *world);
  for (const auto& body : world->bodies())
    if (const core::SpringNetworkBody* spring_body = world->findSpringBody(body->name());
        spring_body && spring_body->frozen())
      frozen.push_back("body '" + body->name() + "' froze: " + spring_body->frozenReason());
  shared_loops += world->workers().sharedLoops();
  return hex(worldStateHash(*world));
}

// What follows a frame that the scene does not script (only tf provides it), for the golden file's
// notes; empty when everything the scene moves is scripted.
std::vector<std::string> tfOnlyFollowers(const scene::SceneDef& scene_def)
{
  std::vector<std::string> notes;
  for (const scene::FramePinDef& pin : scene_def.frame_pins)
    if (!scene::findFrame(scene_def, pin.frame))
      notes.push_back("pin " + std::to_string(pin.index) + " of '" + pin.body + "' follows frame '" + pin.frame + "'");
  for (const scene::FrameSphereDef& sphere : scene_def.frame_spheres)
    if (!scene::findFrame(scene_def, sphere.frame))
      notes.push_back("sphere '" + sphere.sphere + "' follows frame '" + sphere.frame + "'");
  for (const scene::FrameColliderDef& collider : scene_def.frame_colliders)
    if (!scene::findFrame(scene_def, collider.frame))
      notes.push_back("collider '" + collider.collider + "' follows frame '" + collider.frame + "'");
  return notes;
}

// Reads `scene integrator value` lines (value: a hash or "excluded: reason"); '#' starts a comment.
bool readGolden(std::map<std::string, std::string>& golden, std::string& error)
{
  std::ifstream in(kGoldenFile);
  if (!in)
  {
    error = "cannot read " + kGoldenFile;
    return false;
  }
  std::string line;
  for (int number = 1; std::getline(in, line); ++number)
  {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string scene_name, integrator, value;
    fields >> scene_name >> integrator;
    std::getline(fields >> std::ws, value);
    if (scene_name.empty() || integrator.empty() || value.empty())
    {
      error = kGoldenFile + ":" + std::to_string(number) + ": expected 'scene integrator hash', got '" + line + "'";
      return false;
    }
    if (!golden.emplace(scene_name + " " + integrator, value).second)
    {
      error = kGoldenFile + ":" + std::to_string(number) + ": '" + scene_name + " " + integrator + "' appears twice";
      return false;
    }
  }
  return true;
}

bool updateRequested()
{
  const char* update = std::getenv("PARTICLE_SIM_UPDATE_GOLDEN");
  return update && std::string(update) == "1";
}
}  // namespace

// The hash is FNV-1a 64 itself: the published test vectors of its authors.
TEST(GoldenHash, Fnv1a64MatchesTheReferenceVectors)
{
  auto hashOf = [](const std::string& text) {
    Fnv1a64 hash;
    hash.addBytes(text.data(), text.size());
    return hash.value();
  };
  EXPECT_EQ(hashOf(""), 0xcbf29ce484222325ULL);
  EXPECT_EQ(hashOf("a"), 0xaf63dc4c8601ec8cULL);
  EXPECT_EQ(hashOf("foobar"), 0x85944171f73967e8ULL);
}

// The state hash sees what positions and velocities alone do not: the step count of an empty
// world, and the target of a pinned particle that has not moved yet.
TEST(GoldenHash, StateHashSeesStepCountAndPinTargets)
{
  core::World empty(core::WorldDef{});
  const std::uint64_t before = worldStateHash(empty);
  empty.step();
  EXPECT_NE(worldStateHash(empty), before);

  core::World world(core::WorldDef{});
  core::RopeDef rope;
  rope.name = "rope";
  rope.pins = {0};
  ASSERT_TRUE(world.addRope(rope).ok);
  const std::uint64_t held = worldStateHash(world);
  ASSERT_TRUE(world.findSpringBody("rope")->setPinTarget(0, rope.start + Eigen::Vector3d(0, 0, 0.1)).ok);
  EXPECT_NE(worldStateHash(world), held);
}

// The integrator list the golden test walks is the core's, and every name in it parses back.
TEST(GoldenHash, IntegratorNamesComeFromTheCore)
{
  const std::vector<std::string> names = coreIntegratorNames();
  ASSERT_GE(names.size(), 5u) << core::integratorTypeNames();
  for (const std::string& name : names)
  {
    core::IntegratorType type;
    ASSERT_TRUE(core::parseIntegratorType(name, type)) << "'" << name << "'";
    EXPECT_EQ(core::toString(type), name);
  }
}

namespace
{
// Every pair with `threads_per_world` threads in each world (world.threads), as many worlds at once
// as there are cores (with two threads a world, most pairs share no loop: their bodies are too small
// to split, so one world at a time would leave a core idle). One thread per world may regenerate the
// file. The loops the worlds shared between their threads are counted in `shared_loops`. Only the
// pairs of `integrators` run and are compared.
void checkGoldenStates(int threads_per_world, std::uint64_t& shared_loops,
                       const std::vector<std::string>& integrators = coreIntegratorNames())
{
  const std::vector<std::string> scenes = shippedScenes();
  ASSERT_GE(scenes.size(), 30u) << "scene files not found under " << kShippedScenesDir;

  // Every pair's job: its scene, its integrator, and what it found (the hash, or why it is
  // excluded; the bodies that froze).
  struct Job
  {
    std::size_t scene;
    std::string integrator;
    std::string value;
    std::vector<std::string> frozen;
  };
  std::vector<scene::SceneDef> scene_defs(scenes.size());
  std::vector<std::vector<std::string>> tf_notes(scenes.size());  // per scene
  std::vector<Job> jobs;
  for (std::size_t s = 0; s < scenes.size(); ++s)
  {
    const core::Status loaded = scene::loadSceneFile(kShippedScenesDir + "/" + scenes[s], scene_defs[s]);
    ASSERT_TRUE(loaded.ok) << scenes[s] << ": " << loaded.message;
    scene_defs[s].world.threads = threads_per_world;
    for (const std::string& note : tfOnlyFollowers(scene_defs[s]))
      tf_notes[s].push_back(scenes[s] + ": " + note +
                            ", which only tf provides: offline it stays where the scene puts it");
    for (const std::string& integrator : integrators)
    {
      Job job{s, integrator, {}, {}};
      for (const Exclusion& exclusion : kExclusions)
        if (scenes[s] == exclusion.scene && integrator == exclusion.integrator)
          job.value = std::string("excluded: ") + exclusion.reason;
      jobs.push_back(std::move(job));
    }
  }

  // The pairs are independent worlds: the machine's cores take them in turn from a shared counter.
  // Each job writes only its own slot, so the results (and the file) keep the scene order. Running
  // two worlds at once also checks that stepping shares no state between worlds.
  std::atomic<std::size_t> next_job{0};
  std::atomic<std::uint64_t> loops{0};
  auto work = [&]() {
    for (std::size_t j = next_job++; j < jobs.size(); j = next_job++)
    {
      Job& job = jobs[j];
      if (!job.value.empty()) continue;
      core::IntegratorType type;
      if (!core::parseIntegratorType(job.integrator, type))
        job.value = "error: unknown integrator";
      else
        job.value = runAndHash(scene_defs[job.scene], type, job.frozen, loops);
    }
  };
  const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> workers;
  for (unsigned t = 1; t < threads; ++t)
    workers.emplace_back(work);
  work();
  for (std::thread& worker : workers)
    worker.join();
  shared_loops = loops;

  // Notes in scene order: a scene's frames that only tf provides, then its bodies that froze.
  std::vector<std::pair<std::string, std::string>> results;  // "scene integrator", value
  std::vector<std::string> notes;
  for (const Job& job : jobs)
  {
    if (job.integrator == integrators.front())
      notes.insert(notes.end(), tf_notes[job.scene].begin(), tf_notes[job.scene].end());
    const std::string pair = scenes[job.scene] + " " + job.integrator;
    EXPECT_EQ(job.value.rfind("error:", 0), std::string::npos) << pair << ": " << job.value;
    for (const std::string& why : job.frozen)
      notes.push_back(pair + ": " + why);
    results.emplace_back(pair, job.value);
  }
  for (const Exclusion& exclusion : kExclusions)
  {
    EXPECT_NE(std::find(scenes.begin(), scenes.end(), exclusion.scene), scenes.end())
        << "exclusion of a scene that is not shipped: " << exclusion.scene;
    EXPECT_NE(std::find(integrators.begin(), integrators.end(), exclusion.integrator), integrators.end())
        << "exclusion of an integrator the core does not have: " << exclusion.integrator;
  }

  if (updateRequested() && threads_per_world == 1 && integrators == coreIntegratorNames())
  {
    std::filesystem::create_directories(std::filesystem::path(kGoldenFile).parent_path());
    std::ofstream out(kGoldenFile);
    ASSERT_TRUE(out) << "cannot write " << kGoldenFile;
    out << "# Golden determinism hashes: FNV-1a 64 of the full state of every shipped scene after " << kSimTime
        << " s of sim time\n"
           "# at its own dt, with each integrator of the core applied to every spring body.\n"
           "# One line per pair: `scene integrator hash` (scene relative to config/scenes), or\n"
           "# `scene integrator excluded: reason`. Checked by test/unit/golden_hash_test.cpp. A deliberate physics\n"
           "# change regenerates this file in its own commit, saying why:\n"
           "#   PARTICLE_SIM_UPDATE_GOLDEN=1 $PARTICLE_SIM_BUILD/devel/lib/particle_sim/particle_sim_unit_tests "
           "--gtest_filter='GoldenHash*'\n";
    out << "# Notes (frames only tf provides; bodies that froze, hashed where they stopped):\n";
    for (const std::string& note : notes)
      out << "#   " << note << ".\n";
    for (const auto& [pair, value] : results)
      out << pair << " " << value << "\n";
    out.close();
    ASSERT_TRUE(out) << "cannot write " << kGoldenFile;
    std::printf("[golden] wrote %zu scene x integrator pairs (%zu scenes, %zu integrators) to %s\n", results.size(),
                scenes.size(), integrators.size(), kGoldenFile.c_str());
    return;
  }

  std::map<std::string, std::string> golden;
  std::string error;
  ASSERT_TRUE(readGolden(golden, error)) << error;
  std::ostringstream mismatches;
  int mismatch_count = 0;
  std::set<std::string> produced;
  for (const auto& [pair, value] : results)
  {
    produced.insert(pair);
    const auto expected = golden.find(pair);
    if (expected == golden.end())
      mismatches << "  " << pair << ": not in the golden file (got " << value << ")\n";
    else if (expected->second != value)
      mismatches << "  " << pair << ": expected " << expected->second << ", got " << value << "\n";
    else
      continue;
    ++mismatch_count;
  }
  for (const auto& [pair, value] : golden)
  {
    const std::string integrator = pair.substr(pair.rfind(' ') + 1);
    if (produced.count(pair) || std::find(integrators.begin(), integrators.end(), integrator) == integrators.end())
      continue;
    mismatches << "  " << pair << ": in the golden file (" << value << ") but no such scene or integrator\n";
    ++mismatch_count;
  }
  EXPECT_EQ(mismatch_count, 0) << mismatch_count << " of " << results.size() << " scene x integrator pairs differ from "
                               << kGoldenFile << ":\n"
                               << mismatches.str()
                               << "If the physics changed on purpose, regenerate the file in its own commit, saying "
                                  "why:\n  PARTICLE_SIM_UPDATE_GOLDEN=1 "
                                  "$PARTICLE_SIM_BUILD/devel/lib/particle_sim/particle_sim_unit_tests "
                                  "--gtest_filter='GoldenHash*'";
}
}  // namespace

TEST(GoldenHash, EveryShippedSceneAndIntegratorEndsInItsGoldenState)
{
  std::uint64_t shared_loops = 0;
  checkGoldenStates(1, shared_loops);
  EXPECT_EQ(shared_loops, 0u) << "one thread per world shares no loop";
}

// Two threads per world end every pair in the same golden state, bit for bit: the loops shared
// between threads (WorkerPool) give each particle the same arithmetic in the same order. Several
// scenes have bodies large enough to share their loops; the count shows that they did. It compares
// with the file in every mode: when the file is regenerated, the one-thread test above has just
// written it (gtest runs the tests of a file in order).
TEST(GoldenHash, EveryPairEndsInTheSameStateWithTwoThreadsPerWorld)
{
  std::uint64_t shared_loops = 0;
  checkGoldenStates(2, shared_loops);
  EXPECT_GT(shared_loops, 0u) << "no scene shared a loop between two threads: this test would prove nothing";
  std::printf("[golden] two threads per world: %llu loops shared between them\n",
              static_cast<unsigned long long>(shared_loops));
}

// The conjugate gradient's AVX2 passes (core/integrators/cg_avx2.h), which the solver takes where
// the processor has AVX2, give the same bits as its scalar passes: with the scalar passes forced,
// every pair of the methods that solve with CG ends in its golden state too (a golden file written
// on a machine with AVX2 thus holds on one without, and the other way round). The switch forces the
// direct solver's supernodal tiles (dense_panel.h) and the springs' force pass (four springs at a
// time, addSpringForcesOf()) to their scalar form as well: the explicit methods run here too.
TEST(GoldenHash, TheConjugateGradientsScalarAndAvx2PassesGiveTheSameStates)
{
  const bool avx2 = core::ImplicitEulerSolver::useAvx2();
  core::ImplicitEulerSolver::setUseAvx2(!avx2);
  EXPECT_EQ(core::ImplicitEulerSolver::useAvx2(), !avx2 && core::cg_avx2::available());
  core::ImplicitEulerSolver::setUseAvx2(false);
  EXPECT_FALSE(core::ImplicitEulerSolver::useAvx2());
  std::uint64_t shared_loops = 0;
  checkGoldenStates(1, shared_loops, {"implicit_euler", "bdf2", "auto", "symplectic_euler", "verlet"});
  core::ImplicitEulerSolver::setUseAvx2(avx2);
  std::printf("[golden] the CG's and the springs' %s passes checked against the file (AVX2 %s on this processor)\n",
              avx2 ? "scalar" : "only", core::cg_avx2::available() ? "available" : "not available");
}
