// The world and its colliders: free particles follow the analytic parabola, never end a step
// inside the ground or a sphere, bounce with the given restitution, and runs are reproducible.

#include "particle_sim/core/world.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "test_helpers.h"

using namespace particle_sim::core;

namespace
{
// One particle shot from `origin` with velocity (speed along +z by the explosion's direction
// chosen by its seed); the emitter has a single burst and no rate.
EmitterDef oneParticle(const Eigen::Vector3d& origin, double speed, std::uint64_t seed)
{
  EmitterDef def;
  def.name = "shot";
  def.type = EmitterType::Explosion;
  def.origin = origin;
  def.rate = 0.0;
  def.burst_count = 1;
  def.max_particles = 1;
  def.speed = speed;
  def.lifetime = 100.0;
  def.seed = seed;
  return def;
}
}  // namespace

TEST(World, FreeParticleFollowsTheAnalyticParabola)
{
  WorldDef def;
  def.ground.enabled = false;
  def.gravity = {0.3, -0.2, -9.81};
  def.dt = 1.0 / 240.0;
  World world(def);
  ASSERT_TRUE(world.addEmitter(oneParticle({1, 2, 3}, 12.0, 11)).ok);
  const ParticlePool& p = world.findBody("shot")->particles();
  const Eigen::Vector3d x0 = p.position.col(0), v0 = p.velocity.col(0);
  for (int k = 1; k <= 600; ++k)
  {
    world.step();
    const double t = world.simTime();
    const Eigen::Vector3d exact = x0 + v0 * t + 0.5 * def.gravity * t * t;
    ASSERT_LT((p.position.col(0) - exact).norm(), 1e-9 * (1.0 + exact.norm())) << "t = " << t;
    ASSERT_LT((p.velocity.col(0) - (v0 + def.gravity * t)).norm(), 1e-9);
  }
}

TEST(World, SimTimeIsExactlyStepsTimesDt)
{
  WorldDef def;
  def.dt = 0.001;
  World world(def);
  for (int k = 0; k < 12345; ++k)
    world.step();
  EXPECT_EQ(world.stepCount(), 12345u);
  EXPECT_EQ(world.simTime(), 12345 * 0.001);
}

TEST(World, NoParticleEndsAStepBelowTheGroundOrInsideASphere)
{
  WorldDef def;
  def.ground.height = -0.5;
  def.ground.contact.restitution = 0.9;
  SphereColliderDef ball;
  ball.name = "ball";
  ball.center = {0, 0, 1.0};
  ball.radius = 0.8;
  def.spheres.push_back(ball);
  def.dt = 0.005;  // large steps make deep penetrations
  World world(def);
  EmitterDef explosion = oneParticle({0, 0, 2.5}, 25.0, 3);
  explosion.burst_count = 2000;
  explosion.max_particles = 2000;
  ASSERT_TRUE(world.addEmitter(explosion).ok);
  const ParticlePool& p = world.findBody("shot")->particles();
  for (int k = 0; k < 1000; ++k)
  {
    world.step();
    for (int i = 0; i < p.size(); ++i)
    {
      ASSERT_GE(p.position(2, i), def.ground.height) << "particle " << i << " step " << k;
      ASSERT_GE((p.position.col(i) - ball.center).norm(), ball.radius - 1e-12) << "particle " << i;
    }
  }
}

TEST(World, BounceReachesRestitutionSquaredTimesTheDropHeight)
{
  // Dropped from rest at h, a ball meets the ground at speed sqrt(2 g h) and leaves at e times
  // that, so it climbs back to e^2 h.
  for (double e : {0.3, 0.6, 0.9})
  {
    WorldDef def;
    def.dt = 1e-4;
    def.ground.contact.restitution = e;
    def.ground.contact.friction = 0.0;
    World world(def);
    const double h = 2.0;
    ASSERT_TRUE(world.addEmitter(oneParticle({0, 0, h}, 0.0, 1)).ok);
    const ParticlePool& p = world.findBody("shot")->particles();
    bool bounced = false;
    double apex = 0.0;
    for (int k = 0; k < 30000; ++k)
    {
      world.step();
      if (p.velocity(2, 0) > 0.0) bounced = true;
      if (bounced && p.velocity(2, 0) <= 0.0)
      {
        apex = p.position(2, 0);
        break;
      }
    }
    EXPECT_NEAR(apex, e * e * h, 0.01 * h) << "restitution " << e;
  }
}

TEST(Colliders, CoulombFrictionStopsASlidingParticleAtThePredictedDistance)
{
  // Resting on the ground, a particle sliding at speed u decelerates at mu g and stops after
  // u^2 / (2 mu g).
  Environment env;
  env.ground.contact.restitution = 0.0;
  env.ground.contact.friction = 0.5;
  ParticlePool pool;
  pool.resize(1, 1);
  pool.inverse_mass[0] = 1.0;
  const double u = 3.0, dt = 1e-4, g = -env.gravity.z();
  pool.velocity.col(0) = Eigen::Vector3d(u, 0, 0);
  for (int k = 0; k < 200000 && pool.velocity(0, 0) > 0.0; ++k)
  {
    pool.velocity.col(0) += dt * env.gravity;
    pool.position.col(0) += dt * pool.velocity.col(0);
    resolveCollisions(env, pool);
    ASSERT_GE(pool.position(2, 0), 0.0);
  }
  EXPECT_NEAR(pool.velocity(0, 0), 0.0, 1e-12);
  EXPECT_NEAR(pool.position(0, 0), u * u / (2.0 * 0.5 * g), 1e-3);
}

TEST(Colliders, PinnedParticlesAreLeftWhereTheyAre)
{
  Environment env;
  ParticlePool pool;
  pool.resize(1, 1);
  pool.inverse_mass[0] = 0.0;  // pinned
  pool.position.col(0) = Eigen::Vector3d(0, 0, -1);
  resolveCollisions(env, pool);
  EXPECT_EQ(pool.position(2, 0), -1.0);
}

TEST(World, SameSceneAndSeedGiveBitIdenticalStates)
{
  auto run = [](std::uint64_t seed) {
    WorldDef def;
    def.seed = seed;
    World world(def);
    for (EmitterType type :
         {EmitterType::Fountain, EmitterType::Waterfall, EmitterType::SemiSphere, EmitterType::Explosion})
    {
      EmitterDef e;
      e.type = type;
      e.name = toString(type);
      e.burst_count = 50;
      e.seed = deriveSeed(seed, e.name);
      EXPECT_TRUE(world.addEmitter(e).ok);
    }
    for (int k = 0; k < 2000; ++k)
      world.step();
    return particle_sim_test::worldStateHash(world);
  };
  EXPECT_EQ(run(3), run(3));
  EXPECT_NE(run(3), run(4));
}

TEST(World, RefusesDuplicateNamesAndRemovesBodies)
{
  World world(WorldDef{});
  EmitterDef e;
  e.name = "a";
  ASSERT_TRUE(world.addEmitter(e).ok);
  const Status dup = world.addEmitter(e);
  EXPECT_FALSE(dup.ok);
  EXPECT_NE(dup.message.find("'a'"), std::string::npos);
  e.name = "_hidden";
  EXPECT_NE(world.addEmitter(e).message.find("reserved"), std::string::npos);
  e.name = "two words";
  EXPECT_NE(world.addEmitter(e).message.find("character ' '"), std::string::npos);
  EXPECT_FALSE(world.removeBody("b").ok);
  EXPECT_TRUE(world.removeBody("a").ok);
  EXPECT_EQ(world.findBody("a"), nullptr);
}

TEST(World, ParticleCapCountsEveryBodysCapacityAndRefusesWhatWouldPassIt)
{
  // Two 2000-particle pools fit a cap of 4500; a rope of 600 more does not (4600), one of 500 does
  // (exactly 4500); after a removal the room is back.
  WorldDef def;
  def.max_particles_per_world = 4500;
  World world(def);
  EmitterDef pool;
  pool.max_particles = 2000;
  pool.name = "first";
  ASSERT_TRUE(world.addEmitter(pool).ok);
  pool.name = "second";
  ASSERT_TRUE(world.addEmitter(pool).ok);
  RopeDef rope;
  rope.name = "long";
  rope.particles = 600;
  const Status refused = world.addRope(rope);
  EXPECT_FALSE(refused.ok);
  for (const char* part : {"'long'", "needs 600", "holds 4000", "at most 4500", "max_particles_per_world"})
    EXPECT_NE(refused.message.find(part), std::string::npos) << part << " not in: " << refused.message;
  EXPECT_EQ(world.findBody("long"), nullptr);
  rope.particles = 500;
  EXPECT_TRUE(world.addRope(rope).ok);
  EXPECT_TRUE(world.removeBody("first").ok);
  rope.name = "again";
  rope.particles = 2000;
  EXPECT_TRUE(world.addRope(rope).ok);

  // The cap itself is range-checked, naming the field and the value.
  def.max_particles_per_world = 0;
  const Status bad = validate(def);
  EXPECT_FALSE(bad.ok);
  EXPECT_NE(bad.message.find("max_particles_per_world"), std::string::npos) << bad.message;
}
