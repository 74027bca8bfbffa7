// Materials in the node's interfaces (issue 17), without a ROS master: the `material` field of
// ~spawn_rope and ~spawn_cloth (none, a preset, a preset with values replaced, or a material by
// value), the default preset of dynamic_reconfigure's rope_material and cloth_material, and each
// refusal naming the request's field, the value as received and what is allowed (the preset
// names, or the core's range and unit). A rope and a cloth spawned by preset weigh μ·L and ρ_A·area.

#include "particle_sim/ros/material_conversions.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "particle_sim/core/world.h"
#include "particle_sim/ros/request_conversions.h"
#include "test_helpers.h"

using namespace particle_sim;
using namespace particle_sim::ros_interface;
using particle_sim_test::kNaN;

namespace
{
const core::RopeMaterial& firstRopePreset()
{
  return core::ropePresets().front();
}

const core::ClothMaterial& firstClothPreset()
{
  return core::clothPresets().front();
}

void expectSameRope(const core::RopeMaterial& a, const core::RopeMaterial& b)
{
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.linear_density, b.linear_density);
  EXPECT_EQ(a.axial_stiffness, b.axial_stiffness);
  EXPECT_EQ(a.bending_stiffness, b.bending_stiffness);
  EXPECT_EQ(a.damping_ratio, b.damping_ratio);
}

void expectSameCloth(const core::ClothMaterial& a, const core::ClothMaterial& b)
{
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.areal_density, b.areal_density);
  EXPECT_EQ(a.tensile_stiffness, b.tensile_stiffness);
  EXPECT_EQ(a.shear_stiffness, b.shear_stiffness);
  EXPECT_EQ(a.bending_rigidity, b.bending_rigidity);
  EXPECT_EQ(a.damping_ratio, b.damping_ratio);
}

SpawnRope::Request ropeRequest()
{
  SpawnRope::Request req;
  req.name = "line";
  req.particles = 11;
  req.start.z = 2.0;
  req.end.x = 1.5;
  req.end.z = 2.0;
  req.pins = {0};
  return req;
}

SpawnCloth::Request clothRequest()
{
  SpawnCloth::Request req;
  req.name = "towel";
  req.nu = 9;
  req.nv = 7;
  req.origin.z = 2.0;
  req.edge_u.x = 0.8;
  req.edge_v.y = 0.5;
  req.named_pins = {"corner_00"};
  return req;
}

double totalMass(const core::World& world, const std::string& body)
{
  const std::vector<double>& masses = world.findSpringBody(body)->definition().masses;
  return std::accumulate(masses.begin(), masses.end(), 0.0);
}
}  // namespace

// ---------------------------------------------------------------------------------------------
// Rope

TEST(MaterialConversions, RopeWithoutMaterialIsBuiltFromItsConstantsAsBefore)
{
  SpawnRope::Request req = ropeRequest();
  req.mass = 0.4;
  req.stretch_stiffness = 900.0;
  core::RopeDef def;
  ASSERT_TRUE(toRopeDef(req, core::IntegratorDef(), def).ok);
  EXPECT_FALSE(def.material);
  EXPECT_EQ(def.mass, 0.4);                 // [kg]
  EXPECT_EQ(def.stretch_stiffness, 900.0);  // [N/m]
}

TEST(MaterialConversions, RopeByPresetGetsThePresetAndNoConstants)
{
  SpawnRope::Request req = ropeRequest();
  req.material.preset = firstRopePreset().name;
  core::RopeDef def;
  ASSERT_TRUE(toRopeDef(req, core::IntegratorDef(), def).ok);
  ASSERT_TRUE(def.material);
  expectSameRope(*def.material, firstRopePreset());
  // The definition's own mass and constants stay at their defaults: the material replaces them.
  EXPECT_EQ(def.mass, core::RopeDef().mass);
  EXPECT_EQ(def.stretch_stiffness, core::RopeDef().stretch_stiffness);
  EXPECT_TRUE(core::validate(def, 1000).ok) << core::validate(def, 1000).message;
}

TEST(MaterialConversions, RopePresetValuesGivenReplaceThePresetsAndTheNameGoes)
{
  SpawnRope::Request req = ropeRequest();
  req.material.preset = firstRopePreset().name;
  req.material.linear_density = 0.125;  // [kg/m]
  std::optional<core::RopeMaterial> material;
  ASSERT_TRUE(toRopeMaterial(req.material, material).ok);
  ASSERT_TRUE(material);
  EXPECT_EQ(material->name, "");  // no longer the preset
  EXPECT_EQ(material->linear_density, 0.125);
  EXPECT_EQ(material->axial_stiffness, firstRopePreset().axial_stiffness);
  EXPECT_EQ(material->bending_stiffness, firstRopePreset().bending_stiffness);
  EXPECT_EQ(material->damping_ratio, firstRopePreset().damping_ratio);
}

TEST(MaterialConversions, RopeByValueNeedsDensityAndAxialStiffness)
{
  SpawnRope::Request req = ropeRequest();
  req.material.linear_density = 0.05;  // [kg/m]
  req.material.axial_stiffness = 2e4;  // [N]
  req.material.bending_stiffness = 1e-4;
  req.material.damping_ratio = 0.02;
  std::optional<core::RopeMaterial> material;
  ASSERT_TRUE(toRopeMaterial(req.material, material).ok);
  ASSERT_TRUE(material);
  expectSameRope(*material, core::RopeMaterial{"", 0.05, 2e4, 1e-4, 0.02});

  // Without EA: refused, naming the field missing, what is needed and the presets.
  req.material.axial_stiffness = 0.0;
  const core::Status s = toRopeMaterial(req.material, material);
  EXPECT_FALSE(s.ok);
  EXPECT_FALSE(material);
  EXPECT_EQ(s.message,
            "material.axial_stiffness = 0 is not set: a rope material given by value (material.preset empty) needs "
            "linear_density > 0 kg/m, axial_stiffness > 0 N; or name a preset: " +
                core::ropePresetNames());
}

TEST(MaterialConversions, RopeRefusesAnUnknownPresetListingThePresets)
{
  SpawnRope::Request req = ropeRequest();
  req.material.preset = "unobtainium";
  core::RopeDef def;
  const core::Status s = toRopeDef(req, core::IntegratorDef(), def);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message,
            "material.preset = 'unobtainium' is not a rope material preset; allowed: " + core::ropePresetNames());
}

TEST(MaterialConversions, RopeValuesOutOfRangeAreRefusedByTheCoresCheckAsReceived)
{
  SpawnRope::Request req = ropeRequest();
  req.material.preset = firstRopePreset().name;
  req.material.linear_density = -0.5;
  std::optional<core::RopeMaterial> material;
  core::Status s = toRopeMaterial(req.material, material);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "material.linear_density = -0.5 is out of range: must be in [1e-06, 10000] kg/m");

  req.material.linear_density = 0.0;
  req.material.axial_stiffness = kNaN;
  s = toRopeMaterial(req.material, material);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "material.axial_stiffness = nan is not a finite number: must be in [0.001, 1e+12] N");
}

TEST(MaterialConversions, RopeMaterialWithMassOrSpringConstantsIsRefusedNamingBoth)
{
  SpawnRope::Request req = ropeRequest();
  req.material.preset = firstRopePreset().name;
  req.stretch_stiffness = 300.0;
  core::RopeDef def;
  core::Status s = toRopeDef(req, core::IntegratorDef(), def);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "material.preset = '" + firstRopePreset().name +
                           "' and stretch_stiffness = 300 N/m are both set: a rope material gives the rope's mass and "
                           "spring constants; leave stretch_stiffness at 0 or spawn without a material");

  // By value, the first value given names the material; the mass is in kg.
  req = ropeRequest();
  req.material.linear_density = 0.05;
  req.material.axial_stiffness = 2e4;
  req.mass = 2.0;
  s = toRopeDef(req, core::IntegratorDef(), def);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message.rfind("material.linear_density = 0.05 kg/m and mass = 2 kg are both set", 0), 0u) << s.message;

  req.mass = 0.0;
  req.bend_damping = 0.01;
  s = toRopeDef(req, core::IntegratorDef(), def);
  EXPECT_FALSE(s.ok);
  EXPECT_TRUE(particle_sim_test::mentions(s, "and bend_damping = 0.01 N·s/m are both set")) << s.message;
}

TEST(MaterialConversions, RopeDefaultPresetAppliesOnlyToRequestsWithoutMaterialOrConstants)
{
  const std::string preset = firstRopePreset().name;
  core::RopeDef def;

  // Nothing set: the default preset.
  ASSERT_TRUE(toRopeDef(ropeRequest(), core::IntegratorDef(), def, preset).ok);
  ASSERT_TRUE(def.material);
  expectSameRope(*def.material, firstRopePreset());

  // Its own constants win: no material.
  SpawnRope::Request req = ropeRequest();
  req.stretch_stiffness = 700.0;
  def = core::RopeDef();
  ASSERT_TRUE(toRopeDef(req, core::IntegratorDef(), def, preset).ok);
  EXPECT_FALSE(def.material);
  EXPECT_EQ(def.stretch_stiffness, 700.0);

  // Its own material wins.
  req = ropeRequest();
  req.material.linear_density = 0.05;
  req.material.axial_stiffness = 2e4;
  ASSERT_TRUE(toRopeDef(req, core::IntegratorDef(), def, preset).ok);
  ASSERT_TRUE(def.material);
  EXPECT_EQ(def.material->linear_density, 0.05);
  EXPECT_EQ(def.material->name, "");

  // A default that is no preset (reconfigure and the parameters check it first) is refused.
  const core::Status s = toRopeDef(ropeRequest(), core::IntegratorDef(), def, "nope");
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "rope_material = 'nope' is not a rope material preset; allowed: " + core::ropePresetNames());
}

TEST(MaterialConversions, RopeByPresetWeighsLinearDensityTimesLength)
{
  // μ·L with L the rest length: |end − start| = 1.5 m, then an explicit 2 m.
  core::World world{core::WorldDef()};
  SpawnRope::Request req = ropeRequest();
  req.material.preset = firstRopePreset().name;
  core::RopeDef def;
  ASSERT_TRUE(toRopeDef(req, core::IntegratorDef(), def).ok);
  ASSERT_TRUE(world.addRope(def).ok);
  EXPECT_NEAR(totalMass(world, "line"), firstRopePreset().linear_density * 1.5,
              1e-12 * firstRopePreset().linear_density);

  req.name = "slack";
  req.rest_length = 2.0;
  ASSERT_TRUE(toRopeDef(req, core::IntegratorDef(), def).ok);
  ASSERT_TRUE(world.addRope(def).ok);
  EXPECT_NEAR(totalMass(world, "slack"), firstRopePreset().linear_density * 2.0,
              1e-12 * firstRopePreset().linear_density);
}

// ---------------------------------------------------------------------------------------------
// Cloth

TEST(MaterialConversions, ClothWithoutMaterialIsBuiltFromItsConstantsAsBefore)
{
  SpawnCloth::Request req = clothRequest();
  req.mass = 0.3;
  req.stretch_stiffness = 800.0;
  core::ClothGridDef def;
  ASSERT_TRUE(toClothGridDef(req, core::IntegratorDef(), def).ok);
  EXPECT_FALSE(def.material);
  EXPECT_EQ(def.mass, 0.3);  // [kg]
  EXPECT_TRUE(def.stretch.stiffness.isSet());
  EXPECT_EQ(def.stretch.stiffness, 800.0);  // [N/m]
}

TEST(MaterialConversions, ClothByPresetGetsThePresetAndLeavesTheConstantsUnset)
{
  // Model empty: Baraff–Witkin, the model that carries the material's bending rigidity.
  for (const char* model : {"", "baraff_witkin"})
  {
    SCOPED_TRACE(model);
    SpawnCloth::Request req = clothRequest();
    req.model = model;
    req.material.preset = firstClothPreset().name;
    core::ClothGridDef def;
    ASSERT_TRUE(toClothGridDef(req, core::IntegratorDef(), def).ok);
    EXPECT_EQ(def.model, core::ClothModel::BaraffWitkin);
    ASSERT_TRUE(def.material);
    expectSameCloth(*def.material, firstClothPreset());
    EXPECT_FALSE(def.stretch.stiffness.isSet());
    EXPECT_FALSE(def.bend.damping.isSet());
    EXPECT_EQ(def.mass, core::ClothGridDef().mass);
    EXPECT_TRUE(core::validate(def, 1000).ok) << core::validate(def, 1000).message;
  }

  // The spring model asked for: kept, and the core refuses a bending rigidity it cannot carry.
  ASSERT_GT(firstClothPreset().bending_rigidity, 0.0);
  SpawnCloth::Request req = clothRequest();
  req.model = "springs";
  req.material.preset = firstClothPreset().name;
  core::ClothGridDef def;
  ASSERT_TRUE(toClothGridDef(req, core::IntegratorDef(), def).ok);
  EXPECT_EQ(def.model, core::ClothModel::Springs);
  const core::Status s = inRequestTerms(SpawnRequest::Cloth, core::validate(def, 1000));
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message.rfind("material.bending_rigidity = ", 0), 0u) << s.message;
  EXPECT_TRUE(particle_sim_test::mentions(s, "baraff_witkin")) << s.message;
}

TEST(MaterialConversions, ClothPresetValuesGivenReplaceThePresetsAndTheNameGoes)
{
  ClothMaterial msg;
  msg.preset = firstClothPreset().name;
  msg.bending_rigidity = 2e-5;  // [N·m]
  std::optional<core::ClothMaterial> material;
  ASSERT_TRUE(toClothMaterial(msg, material).ok);
  ASSERT_TRUE(material);
  core::ClothMaterial expected = firstClothPreset();
  expected.name.clear();
  expected.bending_rigidity = 2e-5;
  expectSameCloth(*material, expected);
}

TEST(MaterialConversions, ClothByValueNeedsDensityTensileAndShearStiffness)
{
  ClothMaterial msg;
  msg.areal_density = 0.2;         // [kg/m²]
  msg.tensile_stiffness = 5000.0;  // [N/m]
  msg.shear_stiffness = 50.0;      // [N/m]
  std::optional<core::ClothMaterial> material;
  ASSERT_TRUE(toClothMaterial(msg, material).ok);
  ASSERT_TRUE(material);
  expectSameCloth(*material, core::ClothMaterial{"", 0.2, 5000.0, 50.0, 0.0, 0.0});

  msg.shear_stiffness = 0.0;
  const core::Status s = toClothMaterial(msg, material);
  EXPECT_FALSE(s.ok);
  EXPECT_FALSE(material);
  EXPECT_EQ(s.message,
            "material.shear_stiffness = 0 is not set: a cloth material given by value (material.preset empty) needs "
            "areal_density > 0 kg/m^2, tensile_stiffness > 0 N/m, shear_stiffness > 0 N/m; or name a preset: " +
                core::clothPresetNames());
}

TEST(MaterialConversions, ClothRefusesAnUnknownPresetAndOutOfRangeValues)
{
  SpawnCloth::Request req = clothRequest();
  req.material.preset = "cheesecloth?";
  core::ClothGridDef def;
  core::Status s = toClothGridDef(req, core::IntegratorDef(), def);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message,
            "material.preset = 'cheesecloth?' is not a cloth material preset; allowed: " + core::clothPresetNames());

  req.material.preset = firstClothPreset().name;
  req.material.areal_density = -1.0;
  s = toClothGridDef(req, core::IntegratorDef(), def);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "material.areal_density = -1 is out of range: must be in [0.001, 10] kg/m^2");
}

TEST(MaterialConversions, ClothMaterialWithMassOrSpringConstantsIsRefusedNamingBoth)
{
  SpawnCloth::Request req = clothRequest();
  req.material.preset = firstClothPreset().name;
  req.mass = 0.5;
  core::ClothGridDef def;
  core::Status s = toClothGridDef(req, core::IntegratorDef(), def);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "material.preset = '" + firstClothPreset().name +
                           "' and mass = 0.5 kg are both set: a cloth material gives the cloth's mass and spring "
                           "constants; leave mass at 0 or spawn without a material");

  // Baraff–Witkin's bend constant is in N·m.
  req.mass = 0.0;
  req.model = "baraff_witkin";
  req.bend_stiffness = 0.001;
  s = toClothGridDef(req, core::IntegratorDef(), def);
  EXPECT_FALSE(s.ok);
  EXPECT_TRUE(particle_sim_test::mentions(s, "and bend_stiffness = 0.001 N·m are both set")) << s.message;

  req.bend_stiffness = 0.0;
  req.shear_damping = kNaN;
  s = toClothGridDef(req, core::IntegratorDef(), def);
  EXPECT_FALSE(s.ok);
  EXPECT_TRUE(particle_sim_test::mentions(s, "and shear_damping = nan N·s/m are both set")) << s.message;
}

TEST(MaterialConversions, ClothDefaultPresetAppliesOnlyToRequestsWithoutMaterialOrConstants)
{
  const std::string preset = firstClothPreset().name;
  core::ClothGridDef def;
  ASSERT_TRUE(toClothGridDef(clothRequest(), core::IntegratorDef(), def, preset).ok);
  ASSERT_TRUE(def.material);
  expectSameCloth(*def.material, firstClothPreset());

  SpawnCloth::Request req = clothRequest();
  req.mass = 0.2;
  def = core::ClothGridDef();
  ASSERT_TRUE(toClothGridDef(req, core::IntegratorDef(), def, preset).ok);
  EXPECT_FALSE(def.material);
  EXPECT_EQ(def.mass, 0.2);

  const core::Status s = toClothGridDef(clothRequest(), core::IntegratorDef(), def, "velvet?");
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message,
            "cloth_material = 'velvet?' is not a cloth material preset; allowed: " + core::clothPresetNames());
}

TEST(MaterialConversions, ClothOfAMaterialWeighsArealDensityTimesArea)
{
  // ρ_A · |edge_u × edge_v| = ρ_A · 0.8 m · 0.5 m: a preset (Baraff–Witkin), and a spring cloth of
  // a material by value without bending rigidity.
  core::World world{core::WorldDef()};
  SpawnCloth::Request req = clothRequest();
  req.material.preset = firstClothPreset().name;
  core::ClothGridDef def;
  ASSERT_TRUE(toClothGridDef(req, core::IntegratorDef(), def).ok);
  ASSERT_TRUE(world.addClothGrid(def).ok);
  EXPECT_NEAR(totalMass(world, "towel"), firstClothPreset().areal_density * 0.4,
              1e-12 * firstClothPreset().areal_density);

  req = clothRequest();
  req.name = "springs";
  req.model = "springs";
  req.material.areal_density = 0.25;      // [kg/m²]
  req.material.tensile_stiffness = 3000;  // [N/m]
  req.material.shear_stiffness = 30;      // [N/m]
  def = core::ClothGridDef();
  ASSERT_TRUE(toClothGridDef(req, core::IntegratorDef(), def).ok);
  ASSERT_TRUE(world.addClothGrid(def).ok);
  EXPECT_NEAR(totalMass(world, "springs"), 0.25 * 0.4, 1e-12);
}

TEST(MaterialConversions, MaterialTextNamesThePresetOrSaysByValue)
{
  EXPECT_EQ(materialText("cotton"), "material 'cotton'");
  EXPECT_EQ(materialText(""), "material by value");
}
