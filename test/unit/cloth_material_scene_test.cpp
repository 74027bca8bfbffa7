// Scene keys of a cloth's material (issue 17): a preset by name, a preset with values replaced, all
// values by key; refused beside mass or spring constants and for an unknown preset; written back as
// read.

#include <gtest/gtest.h>

#include <string>

#include "particle_sim/core/materials/cloth_material.h"
#include "particle_sim/scene/scene.h"
#include "scene_test_helpers.h"

using namespace particle_sim;
using particle_sim_test::contains;
using particle_sim_test::parseOk;
using particle_sim_test::refusal;

namespace
{
constexpr const char* kGrid =
    "bodies:\n  - name: c\n    kind: cloth\n    model: baraff_witkin\n    resolution: [5, 4]\n    edge_v: [0, 0.5, "
    "0]\n";
constexpr const char* kMesh =
    "bodies:\n  - name: m\n    kind: cloth\n    vertices: [[0, 0, 1], [1, 0, 1], [0, 1, 1]]\n    triangles: [[0, 1, "
    "2]]\n";

// Parses, writes back and parses again: the same text both times.
void expectRoundTrip(const scene::SceneDef& def)
{
  scene::SceneDef again;
  const core::Status status = scene::parseScene(scene::toYaml(def), "round-trip", again);
  ASSERT_TRUE(status.ok) << status.message << "\n" << scene::toYaml(def);
  EXPECT_EQ(scene::toYaml(again), scene::toYaml(def));
}
}  // namespace

TEST(ClothMaterialScene, APresetByName)
{
  const scene::SceneDef def = parseOk(std::string(kGrid) + "    material: cotton\n");
  const auto& cloth = std::get<core::ClothGridDef>(def.bodies[0]);
  ASSERT_TRUE(cloth.material.has_value());
  const core::ClothMaterial cotton = *core::findClothPreset("cotton");
  EXPECT_EQ(cloth.material->name, "cotton");
  EXPECT_EQ(cloth.material->areal_density, cotton.areal_density);
  EXPECT_EQ(cloth.material->bending_rigidity, cotton.bending_rigidity);
  EXPECT_TRUE(contains(scene::toYaml(def), "material: cotton"));
  expectRoundTrip(def);
}

TEST(ClothMaterialScene, APresetWithAValueReplaced)
{
  const scene::SceneDef def = parseOk(std::string(kGrid) + "    material: {preset: denim, damping_ratio: 0.2}\n");
  const auto& cloth = std::get<core::ClothGridDef>(def.bodies[0]);
  ASSERT_TRUE(cloth.material.has_value());
  EXPECT_EQ(cloth.material->damping_ratio, 0.2);
  EXPECT_EQ(cloth.material->tensile_stiffness, core::findClothPreset("denim")->tensile_stiffness);
  EXPECT_TRUE(contains(scene::toYaml(def), "preset: denim"));
  expectRoundTrip(def);
}

TEST(ClothMaterialScene, AllValuesByKeyOnAMesh)
{
  const scene::SceneDef def = parseOk(
      std::string(kMesh) + "    material: {areal_density: 0.3, tensile_stiffness: 2000, shear_stiffness: 40}\n");
  const auto& cloth = std::get<core::MeshClothDef>(def.bodies[0]);
  ASSERT_TRUE(cloth.material.has_value());
  EXPECT_EQ(cloth.material->name, "");
  EXPECT_EQ(cloth.material->areal_density, 0.3);
  EXPECT_EQ(cloth.material->tensile_stiffness, 2000.0);
  EXPECT_EQ(cloth.material->shear_stiffness, 40.0);
  EXPECT_EQ(cloth.material->bending_rigidity, 0.0);
  EXPECT_FALSE(contains(scene::toYaml(def), "mass:"));
  EXPECT_FALSE(contains(scene::toYaml(def), "stretch:"));
  expectRoundTrip(def);
}

TEST(ClothMaterialScene, RefusedBesideMassOrSpringConstantsNamingBothKeys)
{
  for (const char* key : {"mass: 1", "stretch: {stiffness: 10}", "shear: {damping: 1}", "bend: {stiffness: 0}"})
  {
    const std::string m = refusal(std::string(kGrid) + "    material: cotton\n    " + key + "\n");
    const std::string name = std::string(key).substr(0, std::string(key).find(':'));
    EXPECT_TRUE(contains(m, "bodies[0].material and bodies[0]." + name +
                                " are both set: a material gives the cloth its masses and constants"));
  }
  EXPECT_TRUE(contains(refusal(std::string(kMesh) + "    mass: 2\n    material: silk\n"),
                       "bodies[0].material and bodies[0].mass are both set"));
}

TEST(ClothMaterialScene, RefusesUnknownPresetsMissingValuesBadValuesAndUnknownKeys)
{
  EXPECT_TRUE(contains(refusal(std::string(kGrid) + "    material: tweed\n"),
                       "bodies[0].material = 'tweed' is not a cloth material preset; allowed: cotton, denim, silk, "
                       "polyester, wool, aramid"));
  EXPECT_TRUE(contains(refusal(std::string(kGrid) + "    material: {preset: Cotton}\n"),
                       "bodies[0].material = 'Cotton' is not a cloth material preset"));
  EXPECT_TRUE(contains(refusal(std::string(kGrid) + "    material: {areal_density: 0.1, tensile_stiffness: 100}\n"),
                       "needs the key 'shear_stiffness'"));
  EXPECT_TRUE(contains(refusal(std::string(kGrid) + "    material: {preset: silk, areal_density: -2}\n"),
                       "material.areal_density = -2 is out of range: must be in [0.001, 10] kg/m^2"));
  EXPECT_TRUE(contains(refusal(std::string(kGrid) + "    material: {preset: silk, density: 2}\n"),
                       "bodies[0].material.density is not a known key"));
  // The spring model cannot carry a bending rigidity (core validation, the same message everywhere).
  EXPECT_TRUE(contains(refusal("bodies:\n  - name: c\n    kind: cloth\n    model: springs\n    material: cotton\n"),
                       "material.bending_rigidity = 7.8e-06 N·m needs model baraff_witkin"));
  parseOk(
      "bodies:\n  - name: c\n    kind: cloth\n    model: springs\n"
      "    material: {preset: cotton, bending_rigidity: 0}\n");
}

TEST(ClothMaterialScene, AGridClothWithAMaterialAndNoModelIsBaraffWitkinWithoutOneSprings)
{
  const scene::SceneDef with = parseOk("bodies:\n  - name: c\n    kind: cloth\n    material: cotton\n");
  const scene::SceneDef without = parseOk("bodies:\n  - name: c\n    kind: cloth\n");
  ASSERT_EQ(with.bodies.size(), 1u);
  ASSERT_EQ(without.bodies.size(), 1u);
  EXPECT_EQ(std::get<core::ClothGridDef>(with.bodies[0]).model, core::ClothModel::BaraffWitkin);
  EXPECT_EQ(std::get<core::ClothGridDef>(without.bodies[0]).model, core::ClothModel::Springs);
  expectRoundTrip(with);
}

TEST(ClothMaterialScene, BodiesWithoutAMaterialWriteTheirConstantsAsBefore)
{
  const scene::SceneDef def = parseOk(std::string(kGrid) + "    mass: 0.5\n    stretch: {stiffness: 900}\n");
  const auto& cloth = std::get<core::ClothGridDef>(def.bodies[0]);
  EXPECT_FALSE(cloth.material.has_value());
  const std::string yaml = scene::toYaml(def);
  EXPECT_TRUE(contains(yaml, "mass: 0.5"));
  EXPECT_TRUE(contains(yaml, "stiffness: 900"));
  EXPECT_FALSE(contains(yaml, "material"));
  expectRoundTrip(def);
}
