// WorkerPool shares loops between threads without changing a bit of their results: it covers
// every item exactly once at any thread and chunk count; a thread done with its own home range
// takes the chunks left in another's; the spring forces it shares (each spring's force, then each
// particle's sum in spring order) equal the one-thread loop's bit for bit on a network in random
// order, also after a tear; and every method steps a cloth to the same bits at two threads as at
// one.

#include "particle_sim/core/worker_pool.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <random>
#include <thread>
#include <vector>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/forces/springs.h"
#include "particle_sim/core/integrators/registry.h"
#include "particle_sim/core/integrators/symplectic_euler.h"
#include "particle_sim/core/spring_network.h"
#include "test_helpers.h"

namespace core = particle_sim::core;
using particle_sim_test::positionsAndVelocities;
using particle_sim_test::sameBits;

TEST(WorkerPool, EveryItemIsVisitedExactlyOnceInChunksOfTheGivenSize)
{
  for (int threads : {1, 2, 3, 8})
  {
    core::WorkerPool pool(threads);
    for (int items : {0, 1, 7, 64, 1000, 4097})
    {
      for (int chunk : {1, 5, 64, 5000})
      {
        std::vector<std::atomic<int>> visits(items);
        std::atomic<int> calls{0};
        std::atomic<bool> bad_range{false};
        pool.forEachChunk(items, chunk, [&](int begin, int end) {
          ++calls;
          // Each call is one chunk: it starts on a multiple of the chunk and is a chunk long (the
          // last one shorter), or it is the whole range on one thread.
          const bool whole = begin == 0 && end == items;
          if (!whole && (begin % chunk != 0 || (end - begin != chunk && end != items))) bad_range = true;
          for (int i = begin; i < end; ++i)
            ++visits[i];
        });
        for (int i = 0; i < items; ++i)
          ASSERT_EQ(visits[i].load(), 1) << threads << " threads, " << items << " items, chunk " << chunk;
        EXPECT_FALSE(bad_range) << threads << " threads, " << items << " items, chunk " << chunk;
        const int chunks = (items + chunk - 1) / chunk;
        if (threads == 1 || chunks <= 1)
          EXPECT_EQ(calls.load(), items > 0 ? 1 : 0);
        else
          EXPECT_EQ(calls.load(), chunks);
      }
    }
    EXPECT_EQ(pool.sharedLoops() > 0, threads > 1);
  }
}

TEST(WorkerPool, OtherThreadsDoShareTheWork)
{
  // With two threads and many slow chunks, the second thread takes some: the loop is really shared.
  core::WorkerPool pool(2);
  const int items = 64;
  std::vector<std::thread::id> owner(items);
  pool.forEachChunk(items, 1, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
    {
      owner[i] = std::this_thread::get_id();
      volatile double sink = 0.0;
      for (int k = 0; k < 200000; ++k)
        sink = sink + 1.0;
    }
  });
  int by_caller = 0;
  for (const std::thread::id& id : owner)
    by_caller += id == std::this_thread::get_id() ? 1 : 0;
  EXPECT_LT(by_caller, items) << "the caller ran every chunk";
  EXPECT_GT(by_caller, 0) << "the caller ran no chunk";
}

TEST(WorkerPool, AThreadDoneWithItsHomeRangeTakesWhatIsLeftOfAnother)
{
  // Two threads, 64 chunks: the caller's home range is chunks 0-31, the worker's 32-63. The caller's
  // first chunk holds it up until the other thread has run one of chunks 1-31 (or 10 s pass): the
  // worker, done with its own range, must take them.
  core::WorkerPool pool(2);
  const int items = 64;
  const std::thread::id caller = std::this_thread::get_id();
  std::atomic<bool> caller_range_taken{false};
  std::vector<std::atomic<int>> visits(items);
  pool.forEachChunk(items, 1, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
    {
      ++visits[i];
      if (i > 0 && i < items / 2 && std::this_thread::get_id() != caller) caller_range_taken = true;
      if (i != 0 || std::this_thread::get_id() != caller) continue;
      const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
      while (!caller_range_taken && std::chrono::steady_clock::now() < give_up)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  });
  EXPECT_TRUE(caller_range_taken) << "no chunk of the held-up caller's range went to the free thread";
  for (int i = 0; i < items; ++i)
    EXPECT_EQ(visits[i].load(), 1) << "chunk " << i;
}

namespace
{
// A random network: `springs` springs between random pairs of `particles` particles, in random
// order, random constants; random positions and velocities.
struct RandomNetwork
{
  std::vector<core::Spring> springs;
  Eigen::Matrix3Xd x, v;
};

RandomNetwork randomNetwork(int particles, int springs, unsigned seed)
{
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> pick(0, particles - 1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  RandomNetwork network;
  for (int k = 0; k < springs; ++k)
  {
    core::Spring s;
    s.i = pick(random);
    do
      s.j = pick(random);
    while (s.j == s.i);
    s.rest_length = 0.05 + 0.2 * unit(random);
    s.stiffness = 10.0 + 1000.0 * unit(random);
    s.damping = 0.1 * unit(random);
    network.springs.push_back(s);
  }
  network.x = Eigen::Matrix3Xd::Random(3, particles);
  network.v = Eigen::Matrix3Xd::Random(3, particles);
  return network;
}

// Force contexts over `particles` unit masses, none pinned: one thread's, and two threads' shared.
struct TwoContexts
{
  explicit TwoContexts(int particles) : mass(Eigen::VectorXd::Ones(particles)), pinned(particles, 0) {}
  core::ForceContext alone() const { return {mass, pinned, Eigen::Vector3d::Zero(), {}, 0.0, nullptr}; }
  core::ForceContext shared() { return {mass, pinned, Eigen::Vector3d::Zero(), {}, 0.0, &pool}; }

  Eigen::VectorXd mass;
  std::vector<char> pinned;
  core::WorkerPool pool{2};
};

// Springs between near indices of `particles` particles (a strip 37 particles wide): few cross the
// chunks of 2048 particles, and in this order a chunk's springs come in long runs with both ends
// inside it.
std::vector<core::Spring> stripSprings(int particles)
{
  std::vector<core::Spring> springs;
  for (int i = 0; i < particles; ++i)
    for (int step : {1, 2, 37, 38})
      if (i + step < particles)
        springs.push_back(core::Spring{i, i + step, 0.1, 100.0 + i % 7, 0.01 * (i % 3), core::SpringClass::Stretch});
  return springs;
}

// The springs in a random order (`seed`), each with its ends swapped or not: a chunk's springs then
// come in runs of one, either end inside it.
void shuffleSprings(std::vector<core::Spring>& springs, unsigned seed)
{
  std::mt19937 random(seed);
  std::shuffle(springs.begin(), springs.end(), random);
  for (core::Spring& spring : springs)
    if (random() % 2) std::swap(spring.i, spring.j);  // either end may be the lower index
}

// `forces` added onto `before` (forces already there, gravity say, come first in both sums) at
// (x, v) by one thread and by two give the same bits, and the two did share a loop.
void expectSharedEqualsAlone(const core::SpringForces& forces, TwoContexts& contexts, const Eigen::Matrix3Xd& x,
                             const Eigen::Matrix3Xd& v, const Eigen::Matrix3Xd& before)
{
  const std::uint64_t shared_before = contexts.pool.sharedLoops();
  Eigen::Matrix3Xd expected = before, got = before;
  forces.addForces(contexts.alone(), x, v, expected);
  forces.addForces(contexts.shared(), x, v, got);
  EXPECT_GT(contexts.pool.sharedLoops(), shared_before);
  EXPECT_TRUE(sameBits(expected, got));
}
}  // namespace

TEST(WorkerPool, SharedSpringForcesEqualTheOneThreadLoopBitForBit)
{
  const int particles = 3000;
  const RandomNetwork network = randomNetwork(particles, 20000, 7);
  TwoContexts contexts(particles);
  const core::ForceContext alone = contexts.alone();
  core::SpringForces springs(network.springs);
  const Eigen::Matrix3Xd before = Eigen::Matrix3Xd::Random(3, particles);
  expectSharedEqualsAlone(springs, contexts, network.x, network.v, before);
  Eigen::Matrix3Xd expected = before;
  springs.addForces(alone, network.x, network.v, expected);
  // Equal bits are a test of the order: the same springs summed in reverse order differ.
  std::vector<core::Spring> reversed(network.springs.rbegin(), network.springs.rend());
  Eigen::Matrix3Xd other_order = before;
  core::SpringForces(reversed).addForces(alone, network.x, network.v, other_order);
  EXPECT_FALSE(sameBits(expected, other_order));
  EXPECT_TRUE(expected.isApprox(other_order, 1e-12));

  // After a tear the particles' lists of ends follow the springs that are left.
  core::TearRecord torn;
  springs.tear(network.x, 6.0, torn);
  ASSERT_GT(torn.springs.size(), 100u);
  ASSERT_GT(springs.springs().size(), 2048u);
  expectSharedEqualsAlone(springs, contexts, network.x, network.v, before);
  // And after mending, all of them again.
  springs.mend();
  Eigen::Matrix3Xd mended = before;
  springs.addForces(contexts.shared(), network.x, network.v, mended);
  Eigen::Matrix3Xd first = before;
  core::SpringForces(network.springs).addForces(alone, network.x, network.v, first);
  EXPECT_TRUE(sameBits(first, mended));
}

TEST(WorkerPool, SharedSpringForcesByChunksOfParticlesEqualTheOneThreadLoopBitForBit)
{
  // Springs between near indices (a strip 37 particles wide): few cross the chunks of 2048
  // particles, so each chunk's thread computes the springs touching it and adds to its own
  // particles; the boundary springs are computed by both chunks. In the built order a chunk's
  // springs come in long runs with both ends inside it; shuffled, in runs of one, either end inside.
  const int particles = 10000;
  std::vector<core::Spring> springs = stripSprings(particles);
  const Eigen::Matrix3Xd x = Eigen::Matrix3Xd::Random(3, particles);
  const Eigen::Matrix3Xd v = Eigen::Matrix3Xd::Random(3, particles);
  const Eigen::Matrix3Xd before = Eigen::Matrix3Xd::Random(3, particles);
  TwoContexts contexts(particles);
  core::SpringForces in_order(springs);
  expectSharedEqualsAlone(in_order, contexts, x, v, before);
  // After a tear (of the springs stretched most by the random positions) the runs follow the
  // springs that are left.
  core::TearRecord torn;
  in_order.tear(x, 16.0, torn);
  ASSERT_GT(torn.springs.size(), 100u);
  ASSERT_LT(torn.springs.size(), springs.size() / 2);
  expectSharedEqualsAlone(in_order, contexts, x, v, before);

  shuffleSprings(springs, 3);
  expectSharedEqualsAlone(core::SpringForces(springs), contexts, x, v, before);
}

TEST(WorkerPool, SharedSpringJacobiansEqualTheOneThreadLoopBitForBit)
{
  // The springs' implicit blocks (SpringForces::addJacobians()) by chunks of particles: each
  // particle's diagonal block and right-hand side get the one-thread loop's terms in its order and
  // each spring's pair is kept once, so one solve from the same start ends in the same bits. In the
  // built order (long runs with both ends inside a chunk) and shuffled (runs of one, either end).
  const int particles = 10000;
  std::vector<core::Spring> springs = stripSprings(particles);
  const Eigen::Matrix3Xd x = Eigen::Matrix3Xd::Random(3, particles) * 0.2;
  const Eigen::Matrix3Xd v = Eigen::Matrix3Xd::Random(3, particles);
  const Eigen::Matrix3Xd force = Eigen::Matrix3Xd::Random(3, particles);
  TwoContexts contexts(particles);
  core::IntegratorDef settings;
  settings.linear_solver = core::LinearSolverType::ConjugateGradient;
  auto velocityAfterOneSolve = [&](const std::vector<core::Spring>& list, const core::ForceContext& context) {
    core::SpringForces forces(list);
    std::vector<std::pair<int, int>> pairs;
    forces.coupledPairs(pairs);
    core::ImplicitEulerSolver solver;
    solver.setPattern(particles, pairs);
    forces.bindPattern(solver);
    solver.begin(1.0 / 60.0, contexts.mass, force, &v);
    forces.addJacobians(context, x, solver);
    EXPECT_EQ(solver.keptPairs(), static_cast<int>(list.size()));
    std::vector<core::RestingContact> contacts;
    Eigen::Matrix3Xd x1 = x, v1 = v;
    solver.solve(contexts.pinned, contacts, settings, x1, v1);
    return v1;
  };
  for (const bool shuffled : {false, true})
  {
    if (shuffled) shuffleSprings(springs, 5);
    const Eigen::Matrix3Xd alone = velocityAfterOneSolve(springs, contexts.alone());
    const std::uint64_t shared_before = contexts.pool.sharedLoops();
    const Eigen::Matrix3Xd shared = velocityAfterOneSolve(springs, contexts.shared());
    EXPECT_GT(contexts.pool.sharedLoops(), shared_before);
    EXPECT_TRUE(sameBits(alone, shared)) << (shuffled ? "shuffled" : "in the built order");
  }
}

namespace
{
// Whether two doubles are the same bits.
bool sameDouble(double a, double b)
{
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// A body built from `def`, with `pool`'s threads, after three steps of 1/240 s in `env`.
std::unique_ptr<core::SpringNetworkBody> clothSteppedWith(core::WorkerPool& pool, const core::ClothGridDef& def,
                                                          const core::Environment& env)
{
  auto body = std::make_unique<core::SpringNetworkBody>(core::buildClothGrid(def));
  body->setWorkers(&pool);
  for (int k = 0; k < 3; ++k)
    body->step(1.0 / 240.0, env);
  return body;
}
}  // namespace

// sumByChunks adds its terms in fixed chunks and then chunk after chunk: the same bits at 1, 2, 3
// and 8 threads, and within rounding of the exact sum (long double, terms of mixed sign and size).
TEST(WorkerPool, SumByChunksGivesTheSameBitsAtAnyThreadCountAndTheSumWithinRounding)
{
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int items : {0, 1, 2047, 2048, 2049, 100000})
  {
    std::vector<double> terms(items);
    long double exact = 0.0L, magnitude = 0.0L;
    for (double& term : terms)
    {
      term = unit(random) * std::pow(10.0, 3.0 * unit(random));
      exact += term;
      magnitude += std::abs(term);
    }
    std::vector<double> partial, sums;
    for (int threads : {1, 2, 3, 8})
    {
      core::WorkerPool pool(threads);
      sums.push_back(core::sumByChunks(&pool, items, 2048, partial, [&](int i) { return terms[i]; }));
    }
    sums.push_back(core::sumByChunks(nullptr, items, 2048, partial, [&](int i) { return terms[i]; }));
    for (double sum : sums)
      EXPECT_TRUE(sameDouble(sum, sums[0])) << items << " items: " << sum << " against " << sums[0];
    EXPECT_LE(std::abs(static_cast<long double>(sums[0]) - exact), 1e-15L * items * magnitude + 1e-300L)
        << items << " items";
  }
}

// A cloth's mechanical energy, which the blow-up check of the explicit methods reads each step
// (kinetic, gravity and spring energies, each summed by chunks and shared), is the same bits at one
// and two threads, and within rounding of the energies summed independently here in long double.
TEST(WorkerPool, AClothsEnergyIsTheSameBitsAtTwoThreadsAndTheSumOfItsParts)
{
  core::ClothGridDef def(core::ClothModel::Springs);
  def.name = "cloth";
  def.nu = def.nv = 96;  // 9216 particles, about 55,000 springs: several chunks of each sum
  def.origin = {0.0, 0.0, 2.0};
  def.edge_u = {1.0, 0.0, 0.0};
  def.edge_v = {0.0, 1.0, 0.0};
  def.named_pins = {"corner_00", "corner_10"};
  def.integrator.type = core::kSymplecticEulerIntegrator;
  def.integrator.max_substeps = 100000;
  core::Environment env;
  env.ground.enabled = false;
  double energies[2];
  for (int threads : {1, 2})
  {
    core::WorkerPool pool(threads);
    const auto body = clothSteppedWith(pool, def, env);
    ASSERT_FALSE(body->frozen()) << body->frozenReason();
    energies[threads - 1] = body->kineticEnergy() + body->potentialEnergy(env.gravity);

    // Independently: ½ m v² and −m g·x of the free particles, ½ k (|x_i − x_j| − L)² per spring.
    const core::ParticlePool& p = body->particles();
    long double expected = 0.0L, magnitude = 0.0L;
    for (int i = 0; i < p.size(); ++i)
    {
      if (p.inverse_mass[i] == 0.0) continue;
      const double m = 1.0 / p.inverse_mass[i];
      const long double kinetic = 0.5L * m * p.velocity.col(i).squaredNorm();
      const long double gravity = -m * env.gravity.dot(p.position.col(i));
      expected += kinetic + gravity;
      magnitude += std::abs(kinetic) + std::abs(gravity);
    }
    for (const core::Spring& s : body->springs())
    {
      const double stretch = (p.position.col(s.i) - p.position.col(s.j)).norm() - s.rest_length;
      const long double spring = 0.5L * s.stiffness * stretch * stretch;
      expected += spring;
      magnitude += spring;
    }
    EXPECT_GT(magnitude, 0.0L);
    EXPECT_LE(std::abs(static_cast<long double>(energies[threads - 1]) - expected), 1e-12L * magnitude)
        << threads << " threads: " << energies[threads - 1] << " J against " << static_cast<double>(expected) << " J";
  }
  EXPECT_TRUE(sameDouble(energies[0], energies[1])) << energies[0] << " J against " << energies[1] << " J";
}

// An 80 × 80 spring cloth of the default constants (6400 particles, about 38,000 springs), a 1 m
// square at 2 m, hanging from two adjacent corners.
namespace
{
core::ClothGridDef hangingCloth80()
{
  core::ClothGridDef def(core::ClothModel::Springs);
  def.name = "cloth";
  def.nu = def.nv = 80;
  def.origin = {0.0, 0.0, 2.0};
  def.edge_u = {1.0, 0.0, 0.0};
  def.edge_v = {0.0, 1.0, 0.0};
  def.named_pins = {"corner_00", "corner_10"};
  return def;
}
}  // namespace

// Every method of the core (and `auto`) steps an 80 × 80 spring cloth (6400 particles, about 38,000
// springs: its spring forces, its vector updates and, for the implicit methods, its conjugate
// gradient with its sums are shared, in two chunks or more each) to the same bits at two threads as
// at one.
TEST(WorkerPool, EveryMethodStepsAClothToTheSameBitsAtTwoThreads)
{
  std::vector<core::IntegratorType> types{core::kAutoIntegrator};
  for (const core::IntegratorInfo& info : core::integratorRegistry())
    types.push_back(info.type);
  core::Environment env;
  env.ground.enabled = false;
  for (core::IntegratorType type : types)
  {
    core::ClothGridDef def = hangingCloth80();
    def.integrator.type = type;
    def.integrator.linear_solver = core::LinearSolverType::ConjugateGradient;
    def.integrator.max_substeps = 100000;  // the explicit methods take the substeps they need
    Eigen::Matrix3Xd end[2];
    std::uint64_t shared = 0;
    for (int threads : {1, 2})
    {
      core::WorkerPool pool(threads);
      core::SpringNetworkBody body(core::buildClothGrid(def));
      body.setWorkers(&pool);
      for (int k = 0; k < 5; ++k)
        body.step(1.0 / 240.0, env);
      ASSERT_FALSE(body.frozen()) << core::toString(type) << ": " << body.frozenReason();
      end[threads - 1] = positionsAndVelocities(body.particles());
      shared = pool.sharedLoops();
    }
    EXPECT_GT(shared, 5u) << core::toString(type);
    EXPECT_TRUE(sameBits(end[0], end[1])) << core::toString(type);
    EXPECT_GT((end[0].leftCols(6400).row(2).array() - 2.0).abs().maxCoeff(), 1e-3)
        << core::toString(type) << ": the cloth did not move";
  }
}

// The multigrid solver shares its passes over a level's nodes, its setup's (the Galerkin product
// among them) as well as the cycle's: an 80 × 80 spring cloth (6400 particles: four chunks of the
// finest level, about 700 aggregates below it, six chunks) steps to the same bits in three steps at
// two threads as at one. Its CG's own vector passes are serial, so
// the loops the two threads shared count the multigrid's: each iteration has the finest product
// and, on each of the two levels above the coarse ones, the smoothing twice, two residuals, the
// restriction and the prolongation (twelve or so), where the step's own shared loops (forces,
// updates) are a few a step.
TEST(WorkerPool, TheMultigridSolverStepsAClothToTheSameBitsAtTwoThreads)
{
  core::Environment env;
  env.ground.enabled = false;
  core::ClothGridDef def = hangingCloth80();
  def.integrator.type = core::kImplicitEulerIntegrator;
  def.integrator.linear_solver = core::LinearSolverType::Multigrid;
  Eigen::Matrix3Xd end[2];
  long long iterations = 0;
  std::uint64_t shared = 0;
  for (int threads : {1, 2})
  {
    core::WorkerPool pool(threads);
    core::SpringNetworkBody body(core::buildClothGrid(def));
    body.setWorkers(&pool);
    iterations = 0;
    for (int k = 0; k < 3; ++k)
    {
      body.step(1.0 / 60.0, env);
      iterations += body.lastSolve().iterations;
    }
    ASSERT_FALSE(body.frozen()) << body.frozenReason();
    end[threads - 1] = positionsAndVelocities(body.particles());
    shared = pool.sharedLoops();
  }
  EXPECT_GT(iterations, 5);
  EXPECT_TRUE(sameBits(end[0], end[1]));
  EXPECT_GT((end[0].leftCols(6400).row(2).array() - 2.0).abs().maxCoeff(), 1e-3) << "the cloth did not move";
  EXPECT_GE(shared, 10u * static_cast<std::uint64_t>(iterations)) << iterations << " iterations";
}

TEST(WorkerPool, CollisionsWithEveryKindOfColliderGiveTheSameBitsAtTwoThreads)
{
  // A 96 × 96 cloth (9216 particles: three chunks of the collision loop) lying across a sphere, a
  // box and a moving capsule that rise above it, with the ground above it too: every particle is
  // in some collider at the first step. One thread and two end in the same bits, and every free
  // particle ends above the ground (the collisions did run).
  core::Environment env;
  env.ground.height = 0.26;
  core::SphereColliderDef sphere;
  sphere.center = {0.5, 0.5, 0.0};
  sphere.radius = 0.3;
  env.spheres.push_back(sphere);
  core::BoxColliderDef box;
  box.center = {0.2, 0.2, 0.1};
  box.half_extents = {0.1, 0.1, 0.2};
  env.boxes.push_back(box);
  core::CapsuleColliderDef capsule;
  capsule.center = {0.5, 0.85, 0.2};
  capsule.half_length = 0.3;
  capsule.motion.velocity = {0.0, 0.0, 0.5};
  env.capsules.push_back(capsule);

  core::ClothGridDef def(core::ClothModel::Springs);
  def.name = "cloth";
  def.nu = def.nv = 96;
  def.origin = {0.0, 0.0, 0.25};
  def.edge_u = {1.0, 0.0, 0.0};
  def.edge_v = {0.0, 1.0, 0.0};
  def.integrator.type = core::kSymplecticEulerIntegrator;
  def.integrator.max_substeps = 100000;
  Eigen::Matrix3Xd end[2];
  for (int threads : {1, 2})
  {
    core::WorkerPool pool(threads);
    const auto body = clothSteppedWith(pool, def, env);
    ASSERT_FALSE(body->frozen()) << body->frozenReason();
    end[threads - 1] = positionsAndVelocities(body->particles());
    EXPECT_GE(body->particles().position.row(2).minCoeff(), env.ground.height - 1e-9) << threads << " threads";
    if (threads == 2)
    {
      EXPECT_GT(pool.sharedLoops(), 0u);
    }
  }
  EXPECT_TRUE(sameBits(end[0], end[1]));
}
