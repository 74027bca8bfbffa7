// Rope materials in scene files (issue 17): `material: <preset>`, `material: {preset: ..., <values>}`
// and all four values by key are read into RopeDef::material and written back as given; a rope that
// also gives mass, stretch or bend, an unknown preset, a missing value, an unknown key and a value
// out of range are refused with a message naming the keys and values.

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <variant>

#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/materials/rope_material.h"
#include "particle_sim/scene/scene.h"
#include "scene_test_helpers.h"

using namespace particle_sim;
using particle_sim_test::contains;
using particle_sim_test::parseOk;
using particle_sim_test::refusal;

namespace
{
const std::string kRope = "bodies:\n  - name: r\n    kind: rope\n    particles: 11\n";

core::RopeMaterial materialOf(const scene::SceneDef& def)
{
  const auto& rope = std::get<core::RopeDef>(def.bodies.at(0));
  EXPECT_TRUE(rope.material.has_value());
  return rope.material.value_or(core::RopeMaterial());
}

void expectSameMaterial(const core::RopeMaterial& a, const core::RopeMaterial& b)
{
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.linear_density, b.linear_density);
  EXPECT_EQ(a.axial_stiffness, b.axial_stiffness);
  EXPECT_EQ(a.bending_stiffness, b.bending_stiffness);
  EXPECT_EQ(a.damping_ratio, b.damping_ratio);
}

// Written back and read again: the same material, written in the form it was given.
void expectRoundTrip(const scene::SceneDef& def, const std::string& written_form)
{
  const std::string yaml = scene::toYaml(def);
  EXPECT_TRUE(contains(yaml, written_form)) << yaml;
  EXPECT_FALSE(contains(yaml, "mass:")) << yaml;
  expectSameMaterial(materialOf(parseOk(yaml)), materialOf(def));
}
}  // namespace

TEST(RopeMaterialScene, PresetByNameBuildsTheMaterialRope)
{
  const scene::SceneDef def = parseOk(kRope + "    material: steel_cable\n");
  const core::RopeMaterial steel = *core::findRopePreset("steel_cable");
  expectSameMaterial(materialOf(def), steel);
  expectRoundTrip(def, "material: steel_cable");
  std::unique_ptr<core::World> world;
  ASSERT_TRUE(scene::buildWorld(def, world).ok);
  // Total mass μ L over the default 2 m rope.
  const core::SpringNetworkDef net = buildRope(std::get<core::RopeDef>(def.bodies[0]));
  double total = 0.0;
  for (double m : net.masses)
    total += m;
  EXPECT_NEAR(total, steel.linear_density * 2.0, 1e-12);
}

TEST(RopeMaterialScene, PresetWithValuesOverridesOnlyThose)
{
  const scene::SceneDef def = parseOk(kRope + "    material: {preset: nylon_rope, damping_ratio: 0.25}\n");
  core::RopeMaterial expected = *core::findRopePreset("nylon_rope");
  expected.damping_ratio = 0.25;
  expectSameMaterial(materialOf(def), expected);
  expectRoundTrip(def, "material: {preset: nylon_rope, damping_ratio: 0.25}");
}

TEST(RopeMaterialScene, AllValuesByKey)
{
  const scene::SceneDef def = parseOk(kRope +
                                      "    material:\n      linear_density: 0.25\n      axial_stiffness: 3000\n"
                                      "      bending_stiffness: 0.01\n      damping_ratio: 0.5\n");
  const core::RopeMaterial material = materialOf(def);
  EXPECT_EQ(material.name, "");
  EXPECT_EQ(material.linear_density, 0.25);
  EXPECT_EQ(material.axial_stiffness, 3000.0);
  EXPECT_EQ(material.bending_stiffness, 0.01);
  EXPECT_EQ(material.damping_ratio, 0.5);
  expectRoundTrip(def,
                  "material: {linear_density: 0.25, axial_stiffness: 3000, bending_stiffness: 0.01, "
                  "damping_ratio: 0.5}");
}

TEST(RopeMaterialScene, MaterialWithMassOrSpringConstantsIsRefusedNamingBothKeys)
{
  for (const std::string key : {"mass: 1", "stretch: {stiffness: 100}", "bend: {damping: 0.1}"})
  {
    const std::string message = refusal(kRope + "    material: nylon_rope\n    " + key + "\n");
    const std::string name = key.substr(0, key.find(':'));
    EXPECT_TRUE(contains(message, "bodies[0].material and bodies[0]." + name + " are both given"));
    EXPECT_TRUE(contains(message, "inconsistent"));
  }
}

TEST(RopeMaterialScene, BadMaterialsAreRefusedByName)
{
  EXPECT_TRUE(
      contains(refusal(kRope + "    material: kevlar\n"),
               "bodies[0].material = 'kevlar' is not a rope material preset; presets: " + core::ropePresetNames()));
  EXPECT_TRUE(contains(refusal(kRope + "    material: {preset: hemp}\n"),
                       "bodies[0].material.preset = 'hemp' is not a rope material preset; presets: nylon_rope"));
  EXPECT_TRUE(contains(refusal(kRope + "    material: {linear_density: 0.1, axial_stiffness: 100}\n"),
                       "bodies[0].material needs the key 'bending_stiffness'"));
  EXPECT_TRUE(contains(refusal(kRope + "    material: {preset: nylon_rope, density: 3}\n"),
                       "bodies[0].material.density is not a known key"));
  EXPECT_TRUE(contains(refusal(kRope + "    material: {preset: nylon_rope, linear_density: -1}\n"),
                       "bodies[0].material.linear_density = -1 is out of range: must be in [1e-06, 10000] kg/m"));
  EXPECT_TRUE(contains(refusal(kRope + "    material: {preset: nylon_rope, damping_ratio: .nan}\n"),
                       "bodies[0].material.damping_ratio = nan is not a finite number: must be in [0, 10]"));
}
