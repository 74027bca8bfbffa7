// The lecture's four emitters: their initial positions and velocities obey the formulas, mapped
// to z up; particles are recycled at their lifetime; the pool never grows; seeds reproduce.

#include "particle_sim/core/emitter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "particle_sim/core/worker_pool.h"
#include "particle_sim/core/world.h"

using particle_sim::core::EmitterBody;
using particle_sim::core::EmitterDef;
using particle_sim::core::EmitterType;
using particle_sim::core::Environment;
using particle_sim::core::ParticlePool;
using particle_sim::core::ParticleSnapshot;
using particle_sim::core::WorkerPool;

namespace
{
constexpr int kSamples = 20000;

EmitterDef makeDef(EmitterType type)
{
  EmitterDef def;
  def.name = "e";
  def.type = type;
  def.origin = {1.0, -2.0, 3.0};
  def.speed = 7.0;
  def.spread = 1.0;
  return def;
}
}  // namespace

TEST(EmitterFormulas, FountainStartsAtOriginWithBoundedHorizontalAndFixedVerticalVelocity)
{
  const EmitterDef def = makeDef(EmitterType::Fountain);
  std::mt19937_64 rng(5);
  double min_vx = 1e9, max_vx = -1e9, mean_vx = 0.0;
  for (int i = 0; i < kSamples; ++i)
  {
    Eigen::Vector3d x, v;
    EmitterBody::sample(def, rng, x, v);
    EXPECT_EQ(x, def.origin);
    EXPECT_EQ(v.z(), def.speed);
    // rand01() - 0.5 lies in [-0.5, 0.5)
    ASSERT_GE(v.x(), -0.5 * def.spread);
    ASSERT_LT(v.x(), 0.5 * def.spread);
    ASSERT_GE(v.y(), -0.5 * def.spread);
    ASSERT_LT(v.y(), 0.5 * def.spread);
    min_vx = std::min(min_vx, v.x());
    max_vx = std::max(max_vx, v.x());
    mean_vx += v.x() / kSamples;
  }
  // Uniform over the whole interval, centred.
  EXPECT_LT(min_vx, -0.49);
  EXPECT_GT(max_vx, 0.49);
  EXPECT_NEAR(mean_vx, 0.0, 0.02);
}

TEST(EmitterFormulas, WaterfallDefaultsPourWithNoVerticalSpeed)
{
  EmitterDef def = makeDef(EmitterType::Waterfall);
  def.speed = 0.0;
  std::mt19937_64 rng(6);
  for (int i = 0; i < 1000; ++i)
  {
    Eigen::Vector3d x, v;
    EmitterBody::sample(def, rng, x, v);
    EXPECT_EQ(x, def.origin);
    EXPECT_EQ(v.z(), 0.0);
    EXPECT_LE(std::abs(v.x()), 0.5);
    EXPECT_LE(std::abs(v.y()), 0.5);
  }
}

TEST(EmitterFormulas, SemiSphereStartsOnUnitUpperHemisphereMovingOutwardAtSpeed)
{
  const EmitterDef def = makeDef(EmitterType::SemiSphere);
  std::mt19937_64 rng(7);
  int negative_x = 0, negative_y = 0;
  for (int i = 0; i < kSamples; ++i)
  {
    Eigen::Vector3d x, v;
    EmitterBody::sample(def, rng, x, v);
    const Eigen::Vector3d offset = x - def.origin;
    ASSERT_NEAR(offset.norm(), 1.0, 1e-12);  // unit radius
    ASSERT_GE(offset.z(), 0.0);              // altitude in [0, 90) degrees: upper half
    ASSERT_NEAR(v.norm(), def.speed, 1e-12);
    ASSERT_NEAR(v.normalized().dot(offset), 1.0, 1e-12);  // along the outward normal
    negative_x += offset.x() < 0;
    negative_y += offset.y() < 0;
  }
  // Azimuth covers the full circle.
  EXPECT_NEAR(negative_x / double(kSamples), 0.5, 0.03);
  EXPECT_NEAR(negative_y / double(kSamples), 0.5, 0.03);
}

TEST(EmitterFormulas, ExplosionStartsOnCentimetreSphereInEveryDirectionAtSpeed)
{
  const EmitterDef def = makeDef(EmitterType::Explosion);
  std::mt19937_64 rng(8);
  int below = 0;
  for (int i = 0; i < kSamples; ++i)
  {
    Eigen::Vector3d x, v;
    EmitterBody::sample(def, rng, x, v);
    const Eigen::Vector3d offset = x - def.origin;
    ASSERT_NEAR(offset.norm(), 0.01, 1e-14);
    ASSERT_NEAR(v.norm(), def.speed, 1e-12);  // speed * unit direction, not speed * position
    ASSERT_NEAR(v.normalized().dot(offset.normalized()), 1.0, 1e-9);
    below += offset.z() < 0;
  }
  // Altitude in [-90, 90): both hemispheres, evenly.
  EXPECT_NEAR(below / double(kSamples), 0.5, 0.03);
}

TEST(EmitterBody, SameSeedGivesIdenticalParticlesAndAnotherSeedDoesNot)
{
  EmitterDef def = makeDef(EmitterType::SemiSphere);
  def.rate = 1000.0;
  const Environment env;
  EmitterBody a(def), b(def);
  def.seed = 99;
  EmitterBody c(def);
  for (int k = 0; k < 500; ++k)
  {
    a.step(0.001, env);
    b.step(0.001, env);
    c.step(0.001, env);
  }
  ASSERT_EQ(a.particles().size(), b.particles().size());
  const int n = a.particles().size();
  EXPECT_GT(n, 0);
  EXPECT_TRUE(a.particles().position.leftCols(n) == b.particles().position.leftCols(n));
  EXPECT_TRUE(a.particles().velocity.leftCols(n) == b.particles().velocity.leftCols(n));
  EXPECT_FALSE(a.particles().position.leftCols(n) == c.particles().position.leftCols(n));
}

TEST(EmitterBody, RateEmitsTheExpectedCountAndParticlesAreRecycledAtTheirLifetime)
{
  EmitterDef def = makeDef(EmitterType::Fountain);
  def.rate = 200.0;    // particles/s
  def.lifetime = 0.5;  // s
  def.max_particles = 1000;
  Environment env;
  env.ground.enabled = false;
  EmitterBody emitter(def);
  const double dt = 0.001;
  for (int k = 0; k < 2000; ++k)
  {
    emitter.step(dt, env);
    for (int i = 0; i < emitter.particles().size(); ++i)
      ASSERT_LT(emitter.particles().age[i], def.lifetime);
  }
  // After 2 s: 400 emitted, and the live ones are those of the last 0.5 s.
  EXPECT_NEAR(static_cast<double>(emitter.emittedCount()), 400.0, 1.0);
  EXPECT_NEAR(emitter.particles().size(), def.rate * def.lifetime, 1.0);
  EXPECT_EQ(emitter.droppedCount(), 0);
}

TEST(EmitterBody, FullPoolDropsEmissionsAndNeverGrows)
{
  EmitterDef def = makeDef(EmitterType::Fountain);
  def.rate = 1000.0;
  def.lifetime = 10.0;
  def.max_particles = 50;
  EmitterBody emitter(def);
  const Environment env;
  for (int k = 0; k < 200; ++k)
    emitter.step(0.001, env);
  EXPECT_EQ(emitter.particles().size(), 50);
  EXPECT_EQ(emitter.particles().capacity(), 50);
  EXPECT_EQ(emitter.emittedCount() + emitter.droppedCount(), 200);
}

TEST(EmitterBody, BurstEmitsOnceAndResetRepeatsItExactly)
{
  EmitterDef def = makeDef(EmitterType::Explosion);
  def.rate = 0.0;
  def.burst_count = 300;
  def.max_particles = 300;
  EmitterBody emitter(def);
  EXPECT_EQ(emitter.particles().size(), 300);
  const Eigen::Matrix3Xd first = emitter.particles().position.leftCols(300);
  const Environment env;
  for (int k = 0; k < 100; ++k)
    emitter.step(0.001, env);
  EXPECT_EQ(emitter.emittedCount(), 300);
  emitter.reset();
  EXPECT_TRUE(emitter.particles().position.leftCols(300) == first);
}

TEST(EmitterBody, ASnapshotIsEveryKthParticleAsTheStepLeftThemAndChangesNothing)
{
  // Two emitters of the same seed, one asked for a snapshot at some steps: the snapshot equals, bit
  // for bit, every k-th particle copied after the step (also where recycling moved particles into
  // copied slots and emission added some), the two emitters stay identical, and a step not asked
  // leaves the last snapshot alone; copySnapshot() after the step gives the same. One thread and two
  // (the motion's chunks shared).
  for (const int threads : {1, 2})
  {
    SCOPED_TRACE("threads " + std::to_string(threads));
    WorkerPool workers(threads);
    EmitterDef def = makeDef(EmitterType::Fountain);
    def.rate = 200000.0;  // 200 a step, about 20000 live, 200 recycled a step
    def.lifetime = 0.1;
    def.max_particles = 30000;
    const Environment env;
    EmitterBody asked(def), plain(def);
    asked.setWorkers(&workers);
    plain.setWorkers(&workers);
    ParticleSnapshot snapshot;
    const int strides[] = {1, 3, 7, 4096};
    for (int k = 0; k < 240; ++k)
    {
      const bool ask = k % 2 == 0;
      const int stride = strides[(k / 2) % 4];
      const ParticleSnapshot before = snapshot;
      if (ask) asked.snapshotNextStep(stride, &snapshot);
      asked.step(0.001, env);
      plain.step(0.001, env);
      const ParticlePool& p = asked.particles();
      ASSERT_EQ(p.size(), plain.particles().size());
      ASSERT_TRUE(p.position.leftCols(p.size()) == plain.particles().position.leftCols(p.size()));
      ASSERT_TRUE(p.velocity.leftCols(p.size()) == plain.particles().velocity.leftCols(p.size()));
      if (!ask)
      {
        ASSERT_EQ(snapshot.stride, before.stride);
        ASSERT_EQ(snapshot.position, before.position);
        continue;
      }
      ASSERT_EQ(snapshot.stride, stride);
      const std::size_t copied = static_cast<std::size_t>((p.size() + stride - 1) / stride);
      ASSERT_EQ(snapshot.age.size(), copied);
      ASSERT_EQ(snapshot.position.size(), 3 * copied);
      for (std::size_t c = 0; c < copied; ++c)
      {
        const int i = static_cast<int>(c) * stride;
        ASSERT_EQ(snapshot.age[c], p.age[i]) << "step " << k << " particle " << i;
        for (int d = 0; d < 3; ++d)
          ASSERT_EQ(snapshot.position[3 * c + d], p.position(d, i)) << "step " << k << " particle " << i;
      }
      ParticleSnapshot after;  // a copy made now: the same
      asked.copySnapshot(stride, after);
      ASSERT_EQ(after.stride, stride);
      ASSERT_EQ(after.position, snapshot.position);
      ASSERT_EQ(after.age, snapshot.age);
    }
    EXPECT_GT(asked.particles().size(), 15000);
    EXPECT_GT(asked.emittedCount(), asked.particles().size() + 10000);  // recycling happened

    // A request taken back is not taken.
    snapshot.stride = 0;
    asked.snapshotNextStep(5, &snapshot);
    asked.snapshotNextStep(0, nullptr);
    asked.step(0.001, env);
    EXPECT_EQ(snapshot.stride, 0);
  }
}

TEST(EmitterValidation, RefusesEachBadFieldNamingIt)
{
  struct Case
  {
    const char* field;
    void (*spoil)(EmitterDef&);
  };
  const Case cases[] = {
      {"name", [](EmitterDef& d) { d.name.clear(); }},
      {"origin", [](EmitterDef& d) { d.origin.x() = std::nan(""); }},
      {"rate", [](EmitterDef& d) { d.rate = -1.0; }},
      {"burst_count", [](EmitterDef& d) { d.burst_count = -5; }},
      {"lifetime", [](EmitterDef& d) { d.lifetime = 0.0; }},
      {"particle_mass", [](EmitterDef& d) { d.particle_mass = -0.1; }},
      {"max_particles", [](EmitterDef& d) { d.max_particles = 0; }},
      {"speed", [](EmitterDef& d) { d.speed = INFINITY; }},
  };
  for (const Case& c : cases)
  {
    EmitterDef def = makeDef(EmitterType::Fountain);
    ASSERT_TRUE(validate(def).ok);
    c.spoil(def);
    const auto status = validate(def);
    EXPECT_FALSE(status.ok) << c.field;
    EXPECT_NE(status.message.find(c.field), std::string::npos) << status.message;
  }
  EmitterDef def = makeDef(EmitterType::Fountain);
  def.max_particles = 5000;
  const auto status = validate(def, 1000);
  EXPECT_FALSE(status.ok);
  EXPECT_NE(status.message.find("max_particles = 5000"), std::string::npos) << status.message;
  EXPECT_NE(status.message.find("1000"), std::string::npos) << status.message;
}

// A rate beyond one whole pool per step could only drop particles: refused with the bound it
// comes from. 1e300 particles/s used to overflow an int and emit nothing, silently.
TEST(EmitterRate, RatesBeyondOnePoolPerStepAreRefusedNamingTheBound)
{
  particle_sim::core::WorldDef world_def;
  world_def.dt = 0.001;
  particle_sim::core::World world(world_def);
  EmitterDef def = makeDef(EmitterType::Fountain);
  def.max_particles = 2000;
  def.rate = 1e300;
  const particle_sim::core::Status refused = world.addEmitter(def);
  EXPECT_FALSE(refused.ok);
  EXPECT_NE(refused.message.find("rate = 1e+300 is out of range: must be in [0, 2e+06] particles/s"), std::string::npos)
      << refused.message;
  EXPECT_NE(refused.message.find("max_particles = 2000"), std::string::npos) << refused.message;
  EXPECT_DOUBLE_EQ(particle_sim::core::maxEmitterRate(2000, 0.001), 2e6);

  // The bound itself is allowed, and fills the pool in one step.
  def.rate = particle_sim::core::maxEmitterRate(2000, 0.001);
  ASSERT_TRUE(world.addEmitter(def).ok);
  world.step();
  EXPECT_EQ(world.findBody("e")->particles().size(), 2000);
}

// Emission arithmetic never overflows, even for a body built without validation: a huge rate
// fills the pool, and what did not fit is counted as dropped.
TEST(EmitterRate, HugeRatesFillThePoolAndCountTheRestAsDropped)
{
  EmitterDef def = makeDef(EmitterType::Fountain);
  def.max_particles = 100;
  def.lifetime = 10.0;
  for (double rate : {1e300, 1e12, std::numeric_limits<double>::max()})
  {
    def.rate = rate;
    EmitterBody emitter(def);
    Environment env;
    env.ground.enabled = false;
    emitter.step(0.01, env);
    EXPECT_EQ(emitter.particles().size(), 100) << "rate " << rate;
    EXPECT_EQ(emitter.emittedCount(), 100) << "rate " << rate;
    EXPECT_GT(emitter.droppedCount(), 0) << "rate " << rate;
    const long long dropped_once = emitter.droppedCount();
    emitter.step(0.01, env);
    EXPECT_GE(emitter.droppedCount(), dropped_once) << "rate " << rate << ": the count never wraps";
  }
  def.rate = 1e12;
  EmitterBody emitter(def);
  Environment env;
  emitter.step(0.01, env);
  EXPECT_EQ(emitter.droppedCount(), 10000000000LL - 100);  // 1e12 · 0.01 owed, 100 fitted
}
