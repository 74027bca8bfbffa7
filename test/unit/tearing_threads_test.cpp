// Tearing at any thread count (issue 15, item 4): config/scenes/cloth_tear.yaml, pulled apart by its
// grippers for 4 s, tears the same springs in the same steps, leaves the same surface and ends in
// the same state, to the bit, at one, two and three threads per world (world.threads), and again on
// a rerun. Its cloth has 4662 springs, so their energies (of the blow-up check) are shared between
// the threads; its 825 particles are one chunk of the spring forces (WorkerPool's tests and the
// golden sweep at two threads share those of larger bodies). And it ends in two sheets.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "particle_sim/core/world.h"
#include "particle_sim/scene/scene.h"
#include "shipped_scenes.h"
#include "test_helpers.h"

namespace core = particle_sim::core;
namespace scene = particle_sim::scene;

using particle_sim_test::sameBits;

namespace
{
struct TearRun
{
  std::vector<std::pair<long long, std::pair<int, int>>> torn;  // (step, spring's particles)
  std::vector<Eigen::Vector3i> surface;
  std::vector<std::pair<int, std::string>> grip;  // (particle, frame) of each frame pin
  long long split_particles = 0;
  Eigen::Matrix3Xd state;  // positions, then velocities
  std::uint64_t shared_loops = 0;
};

TearRun pullApart(int threads)
{
  scene::SceneDef def;
  const core::Status loaded = scene::loadSceneFile(particle_sim_test::kShippedScenesDir + "/cloth_tear.yaml", def);
  EXPECT_TRUE(loaded.ok) << loaded.message;
  def.world.threads = threads;
  std::unique_ptr<core::World> world;
  const core::Status built = scene::buildWorld(def, world);
  EXPECT_TRUE(built.ok) << built.message;
  TearRun run;
  if (!built.ok) return run;
  const core::SpringNetworkBody& cloth = *world->findSpringBody("cloth");
  const long long steps = static_cast<long long>(std::ceil(4.0 / world->dt()));
  for (long long k = 0; k < steps; ++k)
  {
    scene::stepScene(def, *world);
    for (const std::pair<int, int>& spring : cloth.lastTear().springs)
      run.torn.emplace_back(k, spring);
  }
  run.surface = cloth.surfaceTriangles();
  run.split_particles = cloth.splitParticles();
  for (const scene::FramePinDef& pin : def.frame_pins)
    run.grip.emplace_back(pin.index, pin.frame);
  run.state = particle_sim_test::positionsAndVelocities(cloth.particles());
  run.shared_loops = world->workers().sharedLoops();
  return run;
}
}  // namespace

// The sheets of a surface: its triangles joined through the edges they share, by union–find.
std::vector<int> sheetOfEachParticle(const std::vector<Eigen::Vector3i>& surface, int particles)
{
  std::vector<int> parent(particles);
  for (int i = 0; i < particles; ++i)
    parent[i] = i;
  auto root = [&](int i) {
    while (parent[i] != i)
      i = parent[i] = parent[parent[i]];
    return i;
  };
  // Two triangles sharing an edge share its two particles: joining each triangle's corners joins
  // the sheets through shared edges and also through shared lone corners, so a vertex that held
  // two sheets together would show as one sheet.
  for (const Eigen::Vector3i& t : surface)
  {
    parent[root(t[1])] = root(t[0]);
    parent[root(t[2])] = root(t[0]);
  }
  std::vector<int> sheet(particles);
  for (int i = 0; i < particles; ++i)
    sheet[i] = root(i);
  return sheet;
}

// cloth_tear is torn in two: after 4 s, no particle or triangle joins a particle the left gripper
// holds to one the right gripper holds, and the tear split vertices on its way.
TEST(TearingThreads, ClothTearEndsInTwoSheetsOnePerGripper)
{
  const TearRun run = pullApart(1);
  ASSERT_FALSE(run.grip.empty());
  EXPECT_GT(run.split_particles, 0) << "the tear split no vertex";
  const std::vector<int> sheet = sheetOfEachParticle(run.surface, static_cast<int>(run.state.cols() / 2));
  int left = 0, right = 0;
  for (const auto& [particle, frame] : run.grip)
    for (const auto& [other, other_frame] : run.grip)
    {
      if (frame != "left" || other_frame != "right") continue;
      ++left, ++right;
      EXPECT_NE(sheet[particle], sheet[other]) << "particles " << particle << " and " << other;
    }
  EXPECT_GT(left * right, 0) << "no pair of particles held by the two grippers";
}

TEST(TearingThreads, TheSameStrainTearsTheSameHoleAtAnyThreadCountAndOnARerun)
{
  const TearRun one = pullApart(1);
  ASSERT_GT(one.torn.size(), 100u) << "the cloth did not tear";
  EXPECT_EQ(one.shared_loops, 0u);
  for (int threads : {1, 2, 3})
  {
    SCOPED_TRACE(std::to_string(threads) + " threads (the first run had 1)");
    const TearRun again = pullApart(threads);
    if (threads > 1)
    {
      EXPECT_GT(again.shared_loops, 0u) << "nothing was shared: the comparison proves nothing";
    }
    EXPECT_EQ(again.torn, one.torn);
    EXPECT_EQ(again.surface, one.surface);
    EXPECT_TRUE(sameBits(again.state, one.state));
  }
}
