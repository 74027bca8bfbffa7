// Tearing at any thread count (issue 15, item 4): config/scenes/cloth_tear.yaml, pulled apart by its
// grippers for 4 s, tears the same springs in the same steps, leaves the same surface and ends in
// the same state, to the bit, at one, two and three threads per world (world.threads), and again on
// a rerun. Its cloth has 4662 springs, so their energies (of the blow-up check) are shared between
// the threads; its 825 particles are one chunk of the spring forces (WorkerPool's tests and the
// golden sweep at two threads share those of larger bodies).

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
  run.state = particle_sim_test::positionsAndVelocities(cloth.particles());
  run.shared_loops = world->workers().sharedLoops();
  return run;
}
}  // namespace

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
