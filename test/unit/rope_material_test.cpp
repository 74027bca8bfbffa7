// Rope materials in physical units (issue 17): validate() refuses each field outside its range of
// limits.h with a message naming the field, the value as received, the range and the unit; the
// presets are valid, distinct and found by name.

#include "particle_sim/core/materials/rope_material.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <string>

using namespace particle_sim::core;

namespace
{
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

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
