// Ropes and spring-network definitions: buildRope lays out the particles, masses, springs and pins
// it documents, validate refuses every bad field by name, a damped hanging rope settles to the
// analytic static equilibrium, and spring constants can only be changed to valid values of classes
// the body has.

#include "particle_sim/core/builders/rope.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/verlet.h"
#include "particle_sim/core/spring_network.h"

using namespace particle_sim::core;

namespace
{
const double kNaN = std::numeric_limits<double>::quiet_NaN();

bool mentions(const Status& status, const std::string& field)
{
  return status.message.find(field) != std::string::npos;
}

// The rope's spring constants may be named as the C++ field (stretch_stiffness) or as the scene
// file's path (stretch.stiffness).
bool mentionsEither(const Status& status, const std::string& field)
{
  if (mentions(status, field)) return true;
  for (const std::string prefix : {"stretch_", "bend_"})
  {
    if (field.compare(0, prefix.size(), prefix) == 0)
      return mentions(status, prefix.substr(0, prefix.size() - 1) + "." + field.substr(prefix.size()));
  }
  return false;
}

// A valid free-form network: three particles in a line and two springs.
SpringNetworkDef threeParticles()
{
  SpringNetworkDef def;
  def.name = "net";
  def.positions = {{0, 0, 1}, {1, 0, 1}, {2, 0, 1}};
  def.masses = {1.0, 1.0, 1.0};
  Spring a;
  a.i = 0;
  a.j = 1;
  Spring b;
  b.i = 1;
  b.j = 2;
  def.springs = {a, b};
  return def;
}

std::vector<Spring> springsOfClass(const std::vector<Spring>& springs, SpringClass spring_class)
{
  std::vector<Spring> out;
  for (const Spring& s : springs)
    if (s.spring_class == spring_class) out.push_back(s);
  return out;
}

double maxSpeed(const SpringNetworkBody& body)
{
  const ParticlePool& p = body.particles();
  return p.velocity.leftCols(p.size()).colwise().norm().maxCoeff();
}
}  // namespace

TEST(Rope, BuildLaysOutEvenlySpacedParticlesWithEqualMasses)
{
  RopeDef def;
  def.name = "cable";
  def.particles = 11;
  def.start = {1, -2, 3};
  def.end = {4, 2, 3};  // 5 m long
  def.mass = 2.2;
  def.integrator.type = kVerletIntegrator;
  ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
  const SpringNetworkDef net = buildRope(def);
  EXPECT_EQ(net.name, "cable");
  EXPECT_EQ(net.shape, NetworkShape::Rope);
  EXPECT_EQ(net.integrator.type, kVerletIntegrator);
  ASSERT_EQ(net.positions.size(), 11u);
  ASSERT_EQ(net.masses.size(), 11u);
  EXPECT_TRUE(net.velocities.empty() || net.velocities.size() == 11u);
  for (const Eigen::Vector3d& v : net.velocities)
    EXPECT_EQ(v.norm(), 0.0);
  double total = 0.0;
  for (int i = 0; i < 11; ++i)
  {
    const Eigen::Vector3d expected = def.start + (i / 10.0) * (def.end - def.start);
    EXPECT_LE((net.positions[i] - expected).norm(), 1e-12) << "particle " << i;
    EXPECT_NEAR(net.masses[i], 0.2, 1e-15) << "particle " << i;
    total += net.masses[i];
  }
  EXPECT_NEAR(total, 2.2, 1e-12);
  EXPECT_EQ(net.positions.front(), def.start);
  EXPECT_LE((net.positions.back() - def.end).norm(), 1e-12);
  EXPECT_TRUE(net.pins.empty());
  EXPECT_TRUE(validate(net, 100).ok) << validate(net, 100).message;
}

TEST(Rope, BuildMakesStretchSpringsBetweenNeighbours)
{
  RopeDef def;
  def.name = "rope";
  def.particles = 6;
  def.start = {0, 0, 2};
  def.end = {0, 3, 6};  // 5 m long
  def.stretch_stiffness = 321.0;
  def.stretch_damping = 0.7;
  ASSERT_TRUE(validate(def, 100).ok);
  for (double rest_length : {0.0, 7.5, 2.5})
  {
    def.rest_length = rest_length;
    const SpringNetworkDef net = buildRope(def);
    // No bend springs without bend stiffness.
    ASSERT_EQ(net.springs.size(), 5u) << "rest_length " << rest_length;
    const double segment = (rest_length > 0.0 ? rest_length : 5.0) / 5.0;
    std::vector<bool> joined(5, false);
    for (const Spring& s : net.springs)
    {
      EXPECT_EQ(s.spring_class, SpringClass::Stretch);
      const int lo = std::min(s.i, s.j), hi = std::max(s.i, s.j);
      ASSERT_EQ(hi - lo, 1) << "spring " << s.i << "-" << s.j;
      ASSERT_GE(lo, 0);
      ASSERT_LT(hi, 6);
      joined[lo] = true;
      EXPECT_NEAR(s.rest_length, segment, 1e-12) << "rest_length " << rest_length;
      EXPECT_EQ(s.stiffness, 321.0);
      EXPECT_EQ(s.damping, 0.7);
    }
    EXPECT_EQ(std::count(joined.begin(), joined.end(), true), 5);
  }
}

TEST(Rope, BuildAddsBendSpringsTwoApartOnlyWithBendStiffness)
{
  RopeDef def;
  def.name = "rope";
  def.particles = 8;
  def.start = {0, 0, 2};
  def.end = {3.5, 0, 2};  // segments of 0.5 m
  def.bend_stiffness = 40.0;
  def.bend_damping = 0.3;
  ASSERT_TRUE(validate(def, 100).ok);
  const SpringNetworkDef net = buildRope(def);
  EXPECT_EQ(springsOfClass(net.springs, SpringClass::Stretch).size(), 7u);
  const std::vector<Spring> bend = springsOfClass(net.springs, SpringClass::Bend);
  ASSERT_EQ(bend.size(), 6u);
  EXPECT_EQ(net.springs.size(), 13u);
  std::vector<bool> joined(6, false);
  for (const Spring& s : bend)
  {
    const int lo = std::min(s.i, s.j), hi = std::max(s.i, s.j);
    ASSERT_EQ(hi - lo, 2);
    ASSERT_GE(lo, 0);
    ASSERT_LT(hi, 8);
    joined[lo] = true;
    EXPECT_NEAR(s.rest_length, 1.0, 1e-12);
    EXPECT_EQ(s.stiffness, 40.0);
    EXPECT_EQ(s.damping, 0.3);
  }
  EXPECT_EQ(std::count(joined.begin(), joined.end(), true), 6);
  EXPECT_TRUE(springsOfClass(net.springs, SpringClass::Shear).empty());
}

TEST(Rope, NegativePinIndicesCountFromTheEnd)
{
  RopeDef def;
  def.name = "rope";
  def.particles = 9;
  def.pins = {-1, 0, -3};
  ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
  const SpringNetworkDef net = buildRope(def);
  std::vector<int> pins = net.pins;
  std::sort(pins.begin(), pins.end());
  EXPECT_EQ(pins, (std::vector<int>{0, 6, 8}));

  SpringNetworkBody body(net);
  EXPECT_EQ(body.kind(), BodyKind::SpringNetwork);
  EXPECT_EQ(body.shape(), NetworkShape::Rope);
  EXPECT_EQ(body.particles().size(), 9);
  EXPECT_EQ(body.pinnedCount(), 3);
  for (int i = 0; i < 9; ++i)
  {
    const bool pinned = i == 0 || i == 6 || i == 8;
    EXPECT_EQ(body.isPinned(i), pinned) << "particle " << i;
    EXPECT_NEAR(body.particles().inverse_mass[i], pinned ? 0.0 : 9.0 / def.mass, 1e-12) << "particle " << i;
    if (pinned)
    {
      EXPECT_EQ(body.pinTarget(i), net.positions[i]);
    }
  }
  EXPECT_EQ(body.nearestParticle(net.positions[4] + Eigen::Vector3d(0.01, 0.02, -0.01)), 4);
}

TEST(Rope, ValidateRefusesEachBadFieldByName)
{
  RopeDef valid;
  valid.name = "rope";
  EXPECT_TRUE(validate(valid, 100).ok) << validate(valid, 100).message;
  struct Case
  {
    const char* field;
    void (*spoil)(RopeDef&);
  };
  const Case cases[] = {
      {"particles", [](RopeDef& d) { d.particles = 1; }},
      {"particles", [](RopeDef& d) { d.particles = 101; }},  // above max_particles
      {"mass", [](RopeDef& d) { d.mass = 0.0; }},
      {"mass", [](RopeDef& d) { d.mass = -1.0; }},
      {"stretch_stiffness", [](RopeDef& d) { d.stretch_stiffness = -1.0; }},
      {"stretch_damping", [](RopeDef& d) { d.stretch_damping = -0.1; }},
      {"bend_stiffness", [](RopeDef& d) { d.bend_stiffness = -2.0; }},
      {"bend_damping", [](RopeDef& d) { d.bend_damping = kNaN; }},
      {"rest_length", [](RopeDef& d) { d.rest_length = -1.0; }},
      {"start", [](RopeDef& d) { d.start.y() = kNaN; }},
      {"end", [](RopeDef& d) { d.end.x() = std::numeric_limits<double>::infinity(); }},
      {"pins",
       [](RopeDef& d) {
         d.pins = {0, 20};
       }},
      {"pins", [](RopeDef& d) { d.pins = {-21}; }},
      {"cg_tolerance", [](RopeDef& d) { d.integrator.cg_tolerance = 0.0; }},
  };
  for (const Case& c : cases)
  {
    RopeDef def;
    def.name = "rope";
    c.spoil(def);
    const Status s = validate(def, 100);
    EXPECT_FALSE(s.ok) << c.field;
    EXPECT_TRUE(mentionsEither(s, c.field)) << "expected '" << c.field << "' in: " << s.message;
  }
}

TEST(Rope, ValidateRefusesEachBadNetworkFieldByName)
{
  EXPECT_TRUE(validate(threeParticles(), 100).ok) << validate(threeParticles(), 100).message;
  struct Case
  {
    std::vector<const char*> words;
    void (*spoil)(SpringNetworkDef&);
  };
  const Case cases[] = {
      {{"masses"}, [](SpringNetworkDef& d) { d.masses.pop_back(); }},
      {{"masses"}, [](SpringNetworkDef& d) { d.masses[2] = 0.0; }},
      {{"velocities"}, [](SpringNetworkDef& d) { d.velocities = {Eigen::Vector3d::Zero()}; }},
      {{"positions"}, [](SpringNetworkDef& d) { d.positions[1].z() = kNaN; }},
      {{"springs[1]"}, [](SpringNetworkDef& d) { d.springs[1].j = 3; }},
      {{"springs[0]"}, [](SpringNetworkDef& d) { d.springs[0].i = -1; }},
      {{"springs[1]", "stiffness"}, [](SpringNetworkDef& d) { d.springs[1].stiffness = -5.0; }},
      {{"springs[0]", "damping"}, [](SpringNetworkDef& d) { d.springs[0].damping = -1.0; }},
      {{"springs[1]", "rest_length"}, [](SpringNetworkDef& d) { d.springs[1].rest_length = -0.5; }},
      {{"pins"}, [](SpringNetworkDef& d) { d.pins = {3}; }},
      {{"pins"}, [](SpringNetworkDef& d) { d.pins = {-1}; }},
      {{"cg_tolerance"}, [](SpringNetworkDef& d) { d.integrator.cg_tolerance = -1e-8; }},
  };
  for (const Case& c : cases)
  {
    SpringNetworkDef def = threeParticles();
    c.spoil(def);
    const Status s = validate(def, 100);
    EXPECT_FALSE(s.ok) << c.words.front();
    for (const char* word : c.words)
      EXPECT_TRUE(mentions(s, word)) << "expected '" << word << "' in: " << s.message;
  }
  // More particles than allowed.
  EXPECT_FALSE(validate(threeParticles(), 2).ok);
}

TEST(Rope, HangingRopeSettlesBelowItsPin)
{
  // Released horizontally, a damped rope pinned at one end swings down and comes to rest
  // hanging straight below the pin.
  RopeDef def;
  def.name = "rope";
  def.particles = 16;
  def.start = {0, 0, 3};
  def.end = {1.5, 0, 3};
  def.stretch_stiffness = 2000.0;
  def.stretch_damping = 2.0;
  def.bend_stiffness = 20.0;
  def.bend_damping = 1.0;
  def.pins = {0};
  def.integrator.type = kImplicitEulerIntegrator;
  ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
  SpringNetworkBody body(buildRope(def));
  Environment env;
  env.ground.enabled = false;
  const ParticlePool& p = body.particles();
  // The swing (a rigid-like motion that spring damping barely sees) decays by about 4x every
  // 10 s under implicit Euler's numerical damping; after 150 s it is below 1 mm/s.
  for (int n = 0; n < 150 * 60; ++n)
    body.step(1.0 / 60.0, env);
  ASSERT_FALSE(body.frozen()) << body.frozenReason();
  EXPECT_LT(maxSpeed(body), 5e-3);
  EXPECT_EQ(p.position.col(0), def.start);
  const Eigen::Vector3d lower_end = p.position.col(p.size() - 1);
  // Below the pin by about the rope's length (a little more, as it stretches).
  EXPECT_LT(lower_end.z(), def.start.z() - 1.4);
  EXPECT_GT(lower_end.z(), def.start.z() - 1.7);
  EXPECT_LT((lower_end - def.start).head<2>().norm(), 0.02);
}

TEST(Rope, HangingRopeReachesTheAnalyticStaticStretch)
{
  // Hanging straight down from its pin, spring s (counting from the pin) carries the weight of
  // the N - 1 - s particles below it, so it is longer than its rest length by (N - 1 - s) m g / k.
  RopeDef def;
  def.name = "rope";
  def.particles = 12;
  def.start = {0.5, -0.5, 3};
  def.end = {0.5, -0.5, 1};
  def.mass = 1.2;
  def.stretch_stiffness = 300.0;
  def.stretch_damping = 3.0;
  def.pins = {0};
  def.integrator.type = kImplicitEulerIntegrator;
  def.integrator.cg_tolerance = 1e-12;
  ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
  SpringNetworkBody body(buildRope(def));
  Environment env;
  env.ground.enabled = false;
  for (int n = 0; n < 30 * 60; ++n)
    body.step(1.0 / 60.0, env);
  const ParticlePool& p = body.particles();
  const int n = def.particles;
  const double m = def.mass / n, g = -env.gravity.z(), segment = 2.0 / (n - 1);
  double z = def.start.z();
  EXPECT_LT(maxSpeed(body), 1e-6);
  for (int i = 1; i < n; ++i)
  {
    z -= segment + (n - i) * m * g / def.stretch_stiffness;
    EXPECT_NEAR(p.position(2, i), z, 1e-6) << "particle " << i;
    EXPECT_NEAR(p.position(0, i), 0.5, 1e-9);
    EXPECT_NEAR(p.position(1, i), -0.5, 1e-9);
  }
}

TEST(Rope, SpringConstantsChangeOnlyForClassesTheBodyHas)
{
  RopeDef def;
  def.name = "rope";
  def.particles = 6;
  def.bend_stiffness = 10.0;
  ASSERT_TRUE(validate(def, 100).ok);
  SpringNetworkBody body(buildRope(def));
  EXPECT_TRUE(body.hasSpringClass(SpringClass::Stretch));
  EXPECT_TRUE(body.hasSpringClass(SpringClass::Bend));
  EXPECT_FALSE(body.hasSpringClass(SpringClass::Shear));
  const std::vector<Spring> original = body.springs();

  // A rope has no shear springs.
  Status s = body.setSpringConstants(SpringClass::Shear, 100.0, 1.0);
  EXPECT_FALSE(s.ok);
  EXPECT_TRUE(mentions(s, "shear")) << s.message;

  // Negative or NaN constants are refused, naming the value.
  s = body.setSpringConstants(SpringClass::Stretch, -5.0, 0.0);
  EXPECT_FALSE(s.ok);
  EXPECT_TRUE(mentions(s, "-5")) << s.message;
  s = body.setSpringConstants(std::nullopt, kNaN, 0.0);
  EXPECT_FALSE(s.ok);
  EXPECT_TRUE(mentions(s, "nan")) << s.message;
  s = body.setSpringConstants(SpringClass::Bend, 10.0, -0.25);
  EXPECT_FALSE(s.ok);
  EXPECT_TRUE(mentions(s, "-0.25")) << s.message;

  // Refusals change nothing.
  ASSERT_EQ(body.springs().size(), original.size());
  for (std::size_t k = 0; k < original.size(); ++k)
  {
    EXPECT_EQ(body.springs()[k].stiffness, original[k].stiffness);
    EXPECT_EQ(body.springs()[k].damping, original[k].damping);
  }

  // A valid change touches only its class.
  ASSERT_TRUE(body.setSpringConstants(SpringClass::Bend, 77.0, 0.5).ok);
  for (const Spring& spring : body.springs())
  {
    EXPECT_EQ(spring.stiffness, spring.spring_class == SpringClass::Bend ? 77.0 : def.stretch_stiffness);
    EXPECT_EQ(spring.damping, spring.spring_class == SpringClass::Bend ? 0.5 : def.stretch_damping);
  }
  ASSERT_TRUE(body.setSpringConstants(std::nullopt, 12.0, 0.0).ok);
  for (const Spring& spring : body.springs())
    EXPECT_EQ(spring.stiffness, 12.0);

  // Without bend springs, bend is refused too.
  RopeDef plain;
  plain.name = "plain";
  plain.particles = 4;
  SpringNetworkBody plain_body(buildRope(plain));
  EXPECT_FALSE(plain_body.hasSpringClass(SpringClass::Bend));
  EXPECT_FALSE(plain_body.setSpringConstants(SpringClass::Bend, 1.0, 0.0).ok);
}
