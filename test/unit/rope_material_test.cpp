// Rope materials in physical units (issue 17): validate() refuses each field outside its range of
// limits.h with a message naming the field, the value as received, the range and the unit; the
// presets are valid, distinct and found by name.

#include "particle_sim/core/materials/rope_material.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <utility>

#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/environment.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/spring_network.h"

using namespace particle_sim::core;

namespace
{
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();
const double kPiForTests = 3.14159265358979323846;

RopeMaterial validMaterial()
{
  RopeMaterial material;
  material.linear_density = 0.1;
  material.axial_stiffness = 1e5;
  material.bending_stiffness = 1e-2;
  material.damping_ratio = 0.05;
  return material;
}

void expectMessage(const Status& status, const std::string& expected)
{
  EXPECT_FALSE(status.ok);
  EXPECT_NE(status.message.find(expected), std::string::npos) << "message: " << status.message;
}
}  // namespace

TEST(RopeMaterial, ValidMaterialPasses)
{
  EXPECT_TRUE(validate(validMaterial()).ok) << validate(validMaterial()).message;
}

TEST(RopeMaterial, ZeroBendingAndZeroDampingAreAllowed)
{
  RopeMaterial chain = validMaterial();
  chain.bending_stiffness = 0.0;
  chain.damping_ratio = 0.0;
  EXPECT_TRUE(validate(chain).ok) << validate(chain).message;
}

TEST(RopeMaterial, EachFieldOutOfRangeIsRefusedWithFieldValueRangeAndUnit)
{
  RopeMaterial m = validMaterial();
  m.linear_density = 0.0;
  expectMessage(validate(m), "linear_density = 0 is out of range: must be in [1e-06, 10000] kg/m");
  m = validMaterial();
  m.linear_density = -2.5;
  expectMessage(validate(m), "linear_density = -2.5 is out of range: must be in [1e-06, 10000] kg/m");

  m = validMaterial();
  m.axial_stiffness = 2e12;
  expectMessage(validate(m), "axial_stiffness = 2e+12 is out of range: must be in [0.001, 1e+12] N");

  m = validMaterial();
  m.bending_stiffness = -1e-3;
  expectMessage(validate(m), "bending_stiffness = -0.001 is out of range: must be in [0, 1e+06] N·m²");

  m = validMaterial();
  m.damping_ratio = 11.0;
  expectMessage(validate(m), "damping_ratio = 11 is out of range: must be in [0, 10]");
}

TEST(RopeMaterial, NonFiniteValuesAreRefusedAsReceived)
{
  RopeMaterial m = validMaterial();
  m.linear_density = kNaN;
  expectMessage(validate(m), "linear_density = nan is not a finite number: must be in [1e-06, 10000] kg/m");
  m = validMaterial();
  m.axial_stiffness = kInf;
  expectMessage(validate(m), "axial_stiffness = inf is not a finite number: must be in [0.001, 1e+12] N");
  m = validMaterial();
  m.bending_stiffness = -kInf;
  expectMessage(validate(m), "bending_stiffness = -inf is not a finite number");
  m = validMaterial();
  m.damping_ratio = -kNaN;  // the sign of a NaN means nothing: never "-nan"
  expectMessage(validate(m), "damping_ratio = nan is not a finite number: must be in [0, 10]");
}

TEST(RopeMaterial, PresetsAreValidNamedAndFound)
{
  std::set<std::string> names;
  for (const RopeMaterial& preset : ropePresets())
  {
    EXPECT_TRUE(validate(preset).ok) << preset.name << ": " << validate(preset).message;
    EXPECT_FALSE(preset.name.empty());
    EXPECT_TRUE(names.insert(preset.name).second) << "duplicate preset " << preset.name;
    const std::optional<RopeMaterial> found = findRopePreset(preset.name);
    ASSERT_TRUE(found.has_value()) << preset.name;
    EXPECT_EQ(found->linear_density, preset.linear_density);
    EXPECT_EQ(found->axial_stiffness, preset.axial_stiffness);
    EXPECT_EQ(found->bending_stiffness, preset.bending_stiffness);
    EXPECT_EQ(found->damping_ratio, preset.damping_ratio);
    EXPECT_NE(ropePresetNames().find(preset.name), std::string::npos) << ropePresetNames();
  }
  for (const std::string expected : {"nylon_rope", "polyester_rope", "steel_cable", "climbing_rope"})
    EXPECT_EQ(names.count(expected), 1u) << expected << " missing from " << ropePresetNames();
  EXPECT_FALSE(findRopePreset("Nylon_Rope").has_value());
  EXPECT_FALSE(findRopePreset("").has_value());
}

// The presets against the handbook figures they come from (rope_material.cpp): a wrong exponent
// or unit in a preset shows here.
TEST(RopeMaterial, PresetsMatchTheirSources)
{
  const RopeMaterial steel = *findRopePreset("steel_cable");
  // 0.26 lb/ft at 3/8 in (9.525 mm), scaled to 10 mm by the cross-section: 0.43 kg/m (metric tables: 0.40).
  const double scaled = 0.26 * 0.45359237 / 0.3048 * std::pow(10.0 / 9.525, 2);
  EXPECT_NEAR(steel.linear_density, scaled, 0.1 * scaled);
  EXPECT_NEAR(steel.axial_stiffness, 15000e3 * 6894.757 * 0.471 * 1e-4, 0.01 * steel.axial_stiffness);  // 15000 ksi
  const RopeMaterial climbing = *findRopePreset("climbing_rope");
  EXPECT_NEAR(climbing.axial_stiffness * 0.08, 80.0 * 9.81, 1e-9);  // 8 % static elongation under 80 kg
  // Bending lengths (EI / (μ g))^(1/3) of fibre ropes and wire rope of about 1 cm: 0.03 to 0.5 m.
  for (const RopeMaterial& preset : ropePresets())
  {
    const double bending_length = std::cbrt(preset.bending_stiffness / (preset.linear_density * 9.81));
    EXPECT_GT(bending_length, 0.03) << preset.name;
    EXPECT_LT(bending_length, 0.5) << preset.name;
  }
}

// ---------------------------------------------------------------------------------------------------
// A rope built from a material: masses, stretch springs and damping for its segment length.

namespace
{
RopeDef materialRope(int particles, const RopeMaterial& material)
{
  RopeDef def;
  def.name = "rope";
  def.particles = particles;
  def.start = {0, 0, 3};
  def.end = {2, 0, 3};
  def.material = material;
  return def;
}

/// The lowest non-rigid axial mode of a free–free rope from its built network (1-D, along the
/// rope): angular frequency [rad/s] and damping ratio [-] of the discrete system M ü + C u̇ + K u = 0.
std::pair<double, double> lowestAxialMode(const SpringNetworkDef& net)
{
  const int n = static_cast<int>(net.masses.size());
  Eigen::MatrixXd stiffness = Eigen::MatrixXd::Zero(n, n), damping = Eigen::MatrixXd::Zero(n, n);
  for (const Spring& s : net.springs)
  {
    for (auto [matrix, value] : {std::pair<Eigen::MatrixXd*, double>{&stiffness, s.stiffness}, {&damping, s.damping}})
    {
      (*matrix)(s.i, s.i) += value;
      (*matrix)(s.j, s.j) += value;
      (*matrix)(s.i, s.j) -= value;
      (*matrix)(s.j, s.i) -= value;
    }
  }
  Eigen::MatrixXd mass = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i)
    mass(i, i) = net.masses[i];
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> modes(stiffness, mass);
  const double omega = std::sqrt(modes.eigenvalues()(1));  // (0) is the rigid translation
  const Eigen::VectorXd shape = modes.eigenvectors().col(1);
  const double zeta = shape.dot(damping * shape) / (2.0 * omega * shape.dot(mass * shape));
  return {omega, zeta};
}
}  // namespace

TEST(RopeMaterialBuild, MassesAreLumpedPerSegmentWithHalfMassesAtTheEnds)
{
  RopeMaterial material = validMaterial();
  const RopeDef def = materialRope(11, material);  // 2 m in 10 segments of 0.2 m
  ASSERT_TRUE(validate(def, 1000).ok) << validate(def, 1000).message;
  const SpringNetworkDef net = buildRope(def);
  ASSERT_EQ(net.masses.size(), 11u);
  double total = 0.0;
  for (int i = 0; i < 11; ++i)
  {
    EXPECT_NEAR(net.masses[i], (i == 0 || i == 10 ? 0.5 : 1.0) * 0.1 * 0.2, 1e-15) << i;
    total += net.masses[i];
  }
  EXPECT_NEAR(total, 0.1 * 2.0, 1e-14);  // μ L
}

TEST(RopeMaterialBuild, StretchSpringsAreEAOverTheSegmentAndNoBendSprings)
{
  for (int particles : {3, 11, 101})
  {
    const RopeDef def = materialRope(particles, validMaterial());
    const SpringNetworkDef net = buildRope(def);
    const double segment = 2.0 / (particles - 1);
    ASSERT_EQ(net.springs.size(), static_cast<std::size_t>(particles - 1));
    for (const Spring& s : net.springs)
    {
      EXPECT_EQ(s.spring_class, SpringClass::Stretch);
      EXPECT_EQ(s.j, s.i + 1);
      EXPECT_NEAR(s.rest_length, segment, 1e-15);
      EXPECT_NEAR(s.stiffness, 1e5 / segment, 1e-9 * s.stiffness);
    }
  }
}

// The continuum's lowest axial mode of a free–free rope has ω = (π / L) √(EA / μ) and, by the
// definition of the damping ratio (rope.h), damping ratio ζ. The lumped chain's is
// ω_N = (2 / l) √(EA / μ) sin(π l / (2 L)) (its modes are cosines): both converge as (π l / L)² / 24.
TEST(RopeMaterialBuild, LowestAxialModeConvergesToTheMaterialsFrequencyAndDampingRatio)
{
  RopeMaterial material = validMaterial();
  material.damping_ratio = 0.05;
  const double length = 2.0;
  const double omega = kPiForTests / length * std::sqrt(material.axial_stiffness / material.linear_density);
  double previous_error = 0.0;
  for (int segments : {10, 20, 40})
  {
    const auto [omega_n, zeta_n] = lowestAxialMode(buildRope(materialRope(segments + 1, material)));
    const double predicted = std::pow(kPiForTests / segments, 2) / 24.0;  // leading term of the error
    const double error = std::abs(omega_n / omega - 1.0);
    EXPECT_NEAR(error, predicted, 0.02 * predicted) << segments << " segments";
    EXPECT_NEAR(std::abs(zeta_n / material.damping_ratio - 1.0), predicted, 0.02 * predicted) << segments;
    if (previous_error > 0.0)
    {
      EXPECT_NEAR(previous_error / error, 4.0, 0.1) << segments;  // second order
    }
    previous_error = error;
  }
}

// Hanging from its pin, the segment s (from the pin) carries the lumped weight below it,
// μ g l (N − s − ½), so the rope is longer by μ g L² / (2 EA) at any N (the sum is exact).
TEST(RopeMaterialBuild, HangingRopeStretchesTheSameAtAnyResolution)
{
  RopeMaterial material;
  material.linear_density = 0.1;
  material.axial_stiffness = 50.0;
  material.damping_ratio = 1.0;
  const double length = 2.0, g = 9.81;
  const double stretch = material.linear_density * g * length * length / (2.0 * material.axial_stiffness);
  for (int particles : {5, 21})
  {
    RopeDef def = materialRope(particles, material);
    def.end = {0, 0, 1};  // hanging straight down, 2 m
    def.pins = {0};
    def.integrator.type = kImplicitEulerIntegrator;
    def.integrator.cg_tolerance = 1e-12;
    ASSERT_TRUE(validate(def, 1000).ok) << validate(def, 1000).message;
    SpringNetworkBody body(buildRope(def));
    Environment env;
    env.ground.enabled = false;
    env.gravity = {0, 0, -g};
    for (int n = 0; n < 20 * 60; ++n)
      body.step(1.0 / 60.0, env);
    ASSERT_FALSE(body.frozen()) << body.frozenReason();
    const double tip = body.particles().position(2, particles - 1);
    EXPECT_NEAR(3.0 - tip, length + stretch, 1e-7) << particles << " particles";
  }
}

TEST(RopeMaterialBuild, ValidateRefusesABadMaterialAndSpringsBeyondTheirRangeByName)
{
  RopeMaterial material = validMaterial();
  material.linear_density = kNaN;
  expectMessage(validate(materialRope(11, material), 1000),
                "material.linear_density = nan is not a finite number: must be in [1e-06, 10000] kg/m");

  // Steel cable (EA = 4.85e6 N) on 0.1 mm segments: k = 4.85e10 N/m, beyond kStiffness.
  RopeDef fine = materialRope(20001, *findRopePreset("steel_cable"));
  expectMessage(validate(fine, 100000), "material.axial_stiffness = 4.85");
  expectMessage(validate(fine, 100000), "is out of range: must be in [0, 1e+09] N/m for segments of 0.0001 m");
  EXPECT_TRUE(validate(materialRope(201, *findRopePreset("steel_cable")), 1000).ok);
}
