// Cloth materials in physical units (issue 17): validation messages and presets.
#include "particle_sim/core/materials/cloth_material.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>

#include "particle_sim/core/limits.h"

namespace core = particle_sim::core;

namespace
{
core::ClothMaterial someCloth()
{
  return {"", 0.2, 5000.0, 50.0, 1e-5, 0.1};
}
}  // namespace

TEST(ClothMaterial, AValidMaterialPasses)
{
  EXPECT_TRUE(core::validate(someCloth()).ok) << core::validate(someCloth()).message;
  core::ClothMaterial flexible = someCloth();
  flexible.bending_rigidity = 0.0;  // a cloth without bending resistance is allowed
  flexible.damping_ratio = 0.0;
  EXPECT_TRUE(core::validate(flexible).ok);
}

TEST(ClothMaterial, EachFieldOutOfRangeIsRefusedNamingFieldValueRangeAndUnit)
{
  struct Case
  {
    double core::ClothMaterial::*field;
    double value;
    const char* message;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const Case cases[] = {
      {&core::ClothMaterial::areal_density, -0.5,
       "material.areal_density = -0.5 is out of range: must be in [0.001, 10] kg/m^2"},
      {&core::ClothMaterial::areal_density, 0.0,
       "material.areal_density = 0 is out of range: must be in [0.001, 10] kg/m^2"},
      {&core::ClothMaterial::areal_density, -nan,
       "material.areal_density = nan is not a finite number: must be in [0.001, 10] kg/m^2"},
      {&core::ClothMaterial::tensile_stiffness, 0.0,
       "material.tensile_stiffness = 0 is out of range: must be in [1, 1e+07] N/m"},
      {&core::ClothMaterial::tensile_stiffness, inf,
       "material.tensile_stiffness = inf is not a finite number: must be in [1, 1e+07] N/m"},
      {&core::ClothMaterial::shear_stiffness, 2e6,
       "material.shear_stiffness = 2e+06 is out of range: must be in [0.01, 1e+06] N/m"},
      {&core::ClothMaterial::bending_rigidity, -1e-6,
       "material.bending_rigidity = -1e-06 is out of range: must be in [0, 1] N·m"},
      {&core::ClothMaterial::bending_rigidity, -inf,
       "material.bending_rigidity = -inf is not a finite number: must be in [0, 1] N·m"},
      {&core::ClothMaterial::damping_ratio, 11.0, "material.damping_ratio = 11 is out of range: must be in [0, 10]"},
      {&core::ClothMaterial::damping_ratio, nan,
       "material.damping_ratio = nan is not a finite number: must be in [0, 10]"},
  };
  for (const Case& c : cases)
  {
    core::ClothMaterial material = someCloth();
    material.*c.field = c.value;
    const core::Status status = core::validate(material);
    EXPECT_FALSE(status.ok) << c.message;
    EXPECT_EQ(status.message, c.message);
  }
}

TEST(ClothMaterial, RangesAreTheSharedOnes)
{
  // The damping ratio range is shared with the rope material (limits.h).
  EXPECT_EQ(core::limits::kDampingRatio.min, 0.0);
  EXPECT_EQ(core::limits::kDampingRatio.max, 10.0);
  EXPECT_STREQ(core::limits::kDampingRatio.unit, "-");
}

TEST(ClothMaterial, PresetsAreValidNamedAndFound)
{
  const std::set<std::string> wanted = {"cotton", "denim", "silk", "polyester", "wool", "aramid"};
  std::set<std::string> names;
  for (const core::ClothMaterial& preset : core::clothPresets())
  {
    EXPECT_TRUE(core::validate(preset).ok) << preset.name << ": " << core::validate(preset).message;
    EXPECT_TRUE(names.insert(preset.name).second) << "preset named twice: " << preset.name;
    const auto found = core::findClothPreset(preset.name);
    ASSERT_TRUE(found.has_value());
    EXPECT_EQ(found->areal_density, preset.areal_density);
    EXPECT_NE(core::clothPresetNames().find(preset.name), std::string::npos);
  }
  EXPECT_EQ(names, wanted);
  EXPECT_FALSE(core::findClothPreset("tweed").has_value());
  EXPECT_FALSE(core::findClothPreset("").has_value());
  EXPECT_EQ(core::clothPresetNames(), "cotton, denim, silk, polyester, wool, aramid");
}

TEST(ClothMaterial, PresetsFollowTheKnownOrderingOfFabrics)
{
  // Independent of the exact figures: denim is heavier and stiffer in bending and shear than cotton
  // shirting, which is heavier and stiffer than silk; the aramid is by far the stiffest in tension.
  const auto cotton = *core::findClothPreset("cotton"), denim = *core::findClothPreset("denim"),
             silk = *core::findClothPreset("silk"), aramid = *core::findClothPreset("aramid");
  EXPECT_GT(denim.areal_density, cotton.areal_density);
  EXPECT_GT(cotton.areal_density, silk.areal_density);
  EXPECT_GT(denim.bending_rigidity, cotton.bending_rigidity);
  EXPECT_GT(cotton.bending_rigidity, silk.bending_rigidity);
  EXPECT_GT(denim.shear_stiffness, cotton.shear_stiffness);
  EXPECT_GT(aramid.tensile_stiffness, 10.0 * denim.tensile_stiffness);
  // Fabrics' bending length (B/(w g))^(1/3), the cantilever test's quantity, lies between about 0.5
  // and 5 cm for apparel fabrics (Peirce 1930; ASTM D1388 reports it in that range).
  for (const core::ClothMaterial& preset : core::clothPresets())
  {
    const double bending_length = std::cbrt(preset.bending_rigidity / (preset.areal_density * 9.81));
    EXPECT_GT(bending_length, 0.005) << preset.name;
    EXPECT_LT(bending_length, 0.05) << preset.name;
  }
}
