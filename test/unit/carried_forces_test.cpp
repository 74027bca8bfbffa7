// An explicit step measures the energy of its end state (the blow-up check) with the forces of that
// state, in one pass over the springs, and carries those forces to the next step's first force
// evaluation (SpringNetworkBody::takeCarriedForces()). Whatever the carry saves, the steps must be the
// bits of steps that evaluate every force afresh: a twin body told after each step that its particles
// moved (particlesMovedAfterStep()) never takes a carry and is that reference.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <vector>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/environment.h"
#include "particle_sim/core/integrators/rk4.h"
#include "particle_sim/core/integrators/symplectic_euler.h"
#include "particle_sim/core/integrators/verlet.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/worker_pool.h"
#include "test_helpers.h"

namespace core = particle_sim::core;
using particle_sim_test::positionsAndVelocities;
using particle_sim_test::sameBits;

namespace
{
constexpr int kSteps = 60;
constexpr double kDt = 1.0 / 120.0;  // several substeps for every method (the guard splits the step)

// An n x n spring cloth (stretch, shear, bend) hung by two corners, with `type`.
core::SpringNetworkDef hangingCloth(core::IntegratorType type, int n = 12)
{
  core::ClothGridDef def(core::ClothModel::Springs);
  def.name = "cloth";
  def.origin = {0.0, 0.0, 1.0};
  def.edge_u = {0.3, 0.0, 0.0};
  def.edge_v = {0.0, 0.3, 0.0};
  def.nu = def.nv = n;
  def.named_pins = {"corner_00", "corner_10"};
  def.integrator.type = type;
  return core::buildClothGrid(def);
}

// What changes between steps, the same for the body and its twin.
struct Disturbance
{
  bool move_pin = false;    // the second pin's target moves every step, faster each time
  int wind_change_at = -1;  // the step at which the wind turns (none: −1)
};

struct RunResult
{
  Eigen::Matrix3Xd state;  // positions and velocities at the end
  long long carried = 0;   // steps that took carried forces
  long long events = 0;    // stability events
};

// kSteps of `def` under air and gravity; `fresh`: the body is told after every step that its
// particles moved, so that every force is evaluated afresh.
RunResult run(const core::SpringNetworkDef& def, int threads, const Disturbance& disturbance, bool fresh,
              int steps = kSteps)
{
  core::WorkerPool pool(threads);
  core::SpringNetworkBody body(def);
  body.setWorkers(&pool);
  core::Environment env;
  env.ground.enabled = false;
  env.air.drag = 0.5;
  env.air.wind = {0.5, 0.0, 0.0};
  const int moving = def.pins.back();
  const Eigen::Vector3d start = def.positions[moving];
  for (int step = 0; step < steps; ++step)
  {
    if (step == disturbance.wind_change_at) env.air.wind = {0.0, 1.0, 0.0};
    if (disturbance.move_pin)
    {
      EXPECT_TRUE(body.setPinTarget(moving, start + Eigen::Vector3d(0.0, 0.0, 1e-4 * step * step)));
    }
    body.step(kDt, env);
    if (fresh) body.particlesMovedAfterStep();
  }
  EXPECT_FALSE(body.frozen()) << body.frozenReason();
  return {positionsAndVelocities(body.particles()), body.carriedForceSteps(), body.stabilityEvents()};
}
}  // namespace

TEST(CarriedForces, ExplicitStepsAreTheBitsOfFreshForces)
{
  for (const core::IntegratorType type :
       {core::kSymplecticEulerIntegrator, core::kVerletIntegrator, core::kRk4Integrator})
  {
    const core::SpringNetworkDef def = hangingCloth(type);
    for (int threads : {1, 2})
    {
      const RunResult carried = run(def, threads, {}, false);
      const RunResult fresh = run(def, threads, {}, true);
      EXPECT_TRUE(sameBits(carried.state, fresh.state)) << core::toString(type) << ", " << threads << " threads";
      EXPECT_EQ(carried.events, fresh.events);
      // Every step but the first took the forces its predecessor carried; the twin never did.
      EXPECT_EQ(carried.carried, kSteps - 1) << core::toString(type);
      EXPECT_EQ(fresh.carried, 0);
    }
  }
}

TEST(CarriedForces, AChangedWindOrMovingPinIsEvaluatedAfresh)
{
  // A wind that turns changes the air's force on the state the forces were carried for; a pin that
  // speeds up changes its particle's velocity, so its springs' damping, at every step. Either way
  // the carry must not be taken: the bits are those of fresh forces. A carry that goes unused pauses
  // carrying for a while (after the wind's turn, the steps carry again).
  const core::SpringNetworkDef def = hangingCloth(core::kSymplecticEulerIntegrator);
  for (int threads : {1, 2})
  {
    Disturbance wind;
    wind.wind_change_at = kSteps / 2;
    const RunResult wind_carried = run(def, threads, wind, false);
    EXPECT_TRUE(sameBits(wind_carried.state, run(def, threads, wind, true).state)) << threads << " threads";
    EXPECT_LT(wind_carried.carried, kSteps - 1);
    EXPECT_GT(wind_carried.carried, kSteps / 3);

    Disturbance pin;
    pin.move_pin = true;
    const RunResult pin_carried = run(def, threads, pin, false);
    EXPECT_TRUE(sameBits(pin_carried.state, run(def, threads, pin, true).state)) << threads << " threads";
    EXPECT_EQ(pin_carried.carried, 0);
  }
}

TEST(CarriedForces, TwoThreadsOnTheChunkedSpringLoopGiveTheSameBits)
{
  // 48 x 48: more particles than a chunk of the shared spring loop (2048), so that two threads take
  // its chunked path (springs across the chunks visited from both sides, each spring's energy kept by
  // the run that holds its end i).
  constexpr int kChunkedSteps = 12;
  for (const core::IntegratorType type : {core::kSymplecticEulerIntegrator, core::kVerletIntegrator})
  {
    const core::SpringNetworkDef def = hangingCloth(type, 48);
    const RunResult carried = run(def, 2, {}, false, kChunkedSteps);
    EXPECT_TRUE(sameBits(carried.state, run(def, 2, {}, true, kChunkedSteps).state)) << core::toString(type);
    EXPECT_TRUE(sameBits(carried.state, run(def, 1, {}, true, kChunkedSteps).state)) << core::toString(type);
    EXPECT_EQ(carried.carried, kChunkedSteps - 1) << core::toString(type);
  }
}
