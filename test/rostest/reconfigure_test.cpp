// rostest: dynamic_reconfigure changes observed in the simulation, and kept consistent with
// ~set_spring_constants (README "Live parameters").

#include <gtest/gtest.h>
#include <ros/ros.h>

#include <algorithm>

#include "node_listener.h"
#include "particle_sim/SetSpringConstants.h"
#include "particle_sim/SpawnCloth.h"
#include "particle_sim/SpawnRope.h"
#include "particle_sim/core/materials/cloth_material.h"
#include "particle_sim/core/materials/rope_material.h"
#include "sim_probe.h"

using particle_sim_test::call;
using particle_sim_test::Listener;
using particle_sim_test::SimProbe;
using particle_sim_test::waitForWall;

namespace
{
class ReconfigureTest : public ::testing::Test
{
protected:
  static void SetUpTestSuite()
  {
    for (const char* s : {"set_parameters", "set_spring_constants", "spawn_rope"})
      ASSERT_TRUE(ros::service::waitForService(std::string("/particle_sim/") + s, ros::Duration(30.0))) << s;
  }
  void SetUp() override
  {
    ASSERT_TRUE(waitForWall([&] { return probe_.updates() > 0 && !probe_.body("rope").name.empty(); }))
        << "no ~parameter_updates or ~status with the rope";
  }
  // Largest kinetic energy [J] of `body` in the statuses of the next `seconds` of wall time.
  double maxKineticEnergyOver(const std::string& body, double seconds)
  {
    const std::size_t first = probe_.statuses().size();
    ros::WallDuration(seconds).sleep();
    const auto statuses = probe_.statuses();
    double energy = 0.0;
    std::size_t seen = 0;
    for (std::size_t i = first; i < statuses.size(); ++i)
      for (const auto& b : statuses[i].bodies)
        if (b.name == body)
        {
          energy = std::max(energy, b.kinetic_energy);
          ++seen;
        }
    EXPECT_GT(seen, 10u) << "too few statuses of '" << body << "'";
    return energy;
  }

  ros::NodeHandle nh_;
  SimProbe probe_{nh_};
  Listener listener_{nh_};
};
}  // namespace

TEST_F(ReconfigureTest, StartsFromTheSceneAndSpringConstantsChangeTheRope)
{
  // The scene's values, not the .cfg defaults: rope stretch springs of 800 N/m, 0.3 N·s/m.
  const auto start = probe_.config();
  EXPECT_EQ(start.strs.at("body"), "rope");
  EXPECT_EQ(start.strs.at("spring_class"), "stretch");
  EXPECT_DOUBLE_EQ(start.doubles.at("stiffness"), 800.0);
  EXPECT_DOUBLE_EQ(start.doubles.at("damping"), 0.3);
  EXPECT_DOUBLE_EQ(start.doubles.at("gravity_z"), -9.81);
  EXPECT_DOUBLE_EQ(start.doubles.at("rate"), 50.0);
  // 800 N/m holds the 0.2 kg rope within a few per cent.
  ASSERT_TRUE(waitForWall([&] { return probe_.body("rope").max_strain < 0.2; }));

  // 20 N/m: the hanging rope stretches by tens of per cent.
  const auto answered = probe_.reconfigure({{"stiffness", 20.0}});
  EXPECT_DOUBLE_EQ(answered.doubles.at("stiffness"), 20.0);
  EXPECT_EQ(answered.strs.at("body"), "rope");
  EXPECT_TRUE(waitForWall([&] { return probe_.body("rope").max_strain > 0.4; }))
      << "max strain " << probe_.body("rope").max_strain;

  // Back through the service: dynamic_reconfigure (rqt) shows what the service set.
  particle_sim::SetSpringConstants::Request req;
  req.body = "rope";
  req.spring_class = "stretch";
  req.stiffness = 1234.0;
  req.damping = 0.4;
  const auto res = call<particle_sim::SetSpringConstants>("set_spring_constants", req);
  ASSERT_TRUE(res.success) << res.message;
  EXPECT_TRUE(waitForWall([&] {
    const auto c = probe_.config();
    return c.doubles.at("stiffness") == 1234.0 && c.doubles.at("damping") == 0.4;
  })) << "~parameter_updates shows stiffness "
      << probe_.config().doubles.at("stiffness");
  EXPECT_TRUE(waitForWall([&] { return probe_.body("rope").max_strain < 0.2; }));
}

TEST_F(ReconfigureTest, GravityAndGlobalDampingAreAppliedLive)
{
  // Gravity up (and a little sideways, so that a rope hanging straight down is not balanced):
  // the rope, pinned at z = 2 m, ends up above its pin.
  auto answered = probe_.reconfigure({{"gravity_x", 1.0}, {"gravity_z", 9.81}});
  EXPECT_DOUBLE_EQ(answered.doubles.at("gravity_z"), 9.81);
  EXPECT_TRUE(waitForWall([&] { return probe_.status().gravity.z == 9.81; }));
  EXPECT_TRUE(waitForWall([&] {
    const auto line = listener_.latest("rope", 1);
    return line.points.size() == 10 && line.points.back().z > 2.6;
  })) << "the rope did not rise";

  // Gravity down again: the rope swings down through its lowest point with most of its 2 J.
  probe_.reconfigure({{"gravity_x", 0.0}, {"gravity_z", -9.81}});
  const double undamped = maxKineticEnergyOver("rope", 2.0);
  EXPECT_GT(undamped, 0.1);

  // Global damping 50 /s: no particle falls faster than g / 50 ≈ 0.2 m/s any more.
  answered = probe_.reconfigure({{"global_damping", 50.0}, {"gravity_z", 9.81}});
  EXPECT_DOUBLE_EQ(answered.doubles.at("global_damping"), 50.0);
  EXPECT_TRUE(waitForWall([&] { return probe_.status().global_damping == 50.0; }));
  ros::WallDuration(1.0).sleep();
  probe_.reconfigure({{"gravity_z", -9.81}});
  const double damped = maxKineticEnergyOver("rope", 2.0);
  EXPECT_LT(damped, 0.02) << "undamped " << undamped;

  // A value out of the .cfg's range is clamped by dynamic_reconfigure, not refused.
  answered = probe_.reconfigure({{"global_damping", 1e6}});
  EXPECT_DOUBLE_EQ(answered.doubles.at("global_damping"), 100.0);
  answered = probe_.reconfigure({{"global_damping", 0.0}});
  EXPECT_DOUBLE_EQ(answered.doubles.at("global_damping"), 0.0);
  EXPECT_TRUE(waitForWall([&] { return probe_.status().global_damping == 0.0; }));
}

TEST_F(ReconfigureTest, DefaultIntegratorAndBodySelection)
{
  // New default integrator: a rope spawned without one gets it.
  auto answered = probe_.reconfigure({}, {{"integrator", "rk4"}});
  EXPECT_EQ(answered.strs.at("integrator"), "rk4");
  particle_sim::SpawnRope::Request req;
  req.name = "second";
  req.particles = 5;
  req.start.z = 1.0;
  req.end.x = 1.0;
  req.end.z = 1.0;
  req.mass = 0.1;
  req.stretch_stiffness = 321.0;
  req.stretch_damping = 0.25;
  req.pins = {0};
  const auto spawned = call<particle_sim::SpawnRope>("spawn_rope", req);
  ASSERT_TRUE(spawned.success) << spawned.message;
  ASSERT_TRUE(waitForWall([&] { return !probe_.body("second").name.empty(); }));
  EXPECT_EQ(probe_.body("second").integrator, "rk4");
  EXPECT_EQ(probe_.body("rope").integrator, "implicit_euler");  // built before: unchanged

  // Choosing another body shows its constants.
  answered = probe_.reconfigure({}, {{"body", "second"}});
  EXPECT_EQ(answered.strs.at("body"), "second");
  EXPECT_DOUBLE_EQ(answered.doubles.at("stiffness"), 321.0);
  EXPECT_DOUBLE_EQ(answered.doubles.at("damping"), 0.25);

  // A body that does not exist is refused: the selection stays.
  answered = probe_.reconfigure({}, {{"body", "no_such_body"}});
  EXPECT_EQ(answered.strs.at("body"), "second");
  // An unknown integrator is refused too.
  answered = probe_.reconfigure({}, {{"integrator", "leapfrog"}});
  EXPECT_EQ(answered.strs.at("integrator"), "rk4");
}

TEST_F(ReconfigureTest, BaraffWitkinClothShowsAndTakesItsConditionConstants)
{
  particle_sim::SpawnCloth::Request req;
  req.name = "bw";
  req.model = "baraff_witkin";
  req.origin.z = 1.0;
  req.edge_u.x = 0.5;
  req.edge_v.y = 0.5;
  req.nu = req.nv = 4;
  req.stretch_stiffness = 1500.0;
  req.stretch_damping = 1.5;
  req.shear_stiffness = 120.0;
  req.shear_damping = 0.12;
  req.bend_stiffness = 0.004;
  req.bend_damping = 4e-5;
  const auto spawned = call<particle_sim::SpawnCloth>("spawn_cloth", req);
  ASSERT_TRUE(spawned.success) << spawned.message;

  // Selecting the cloth and its shear class shows the conditions' constants ...
  auto answered = probe_.reconfigure({}, {{"body", "bw"}, {"spring_class", "shear"}});
  EXPECT_EQ(answered.strs.at("body"), "bw");
  EXPECT_DOUBLE_EQ(answered.doubles.at("stiffness"), 120.0);
  EXPECT_DOUBLE_EQ(answered.doubles.at("damping"), 0.12);
  // ... and setting them there is seen when the class is shown again.
  probe_.reconfigure({{"stiffness", 80.0}});
  probe_.reconfigure({}, {{"spring_class", "stretch"}});
  answered = probe_.reconfigure({}, {{"spring_class", "shear"}});
  EXPECT_DOUBLE_EQ(answered.doubles.at("stiffness"), 80.0);
}

// Materials in physical units (issue 17): a rope and a cloth spawned by preset weigh μ·L and
// ρ_A·area in ~status; ~cloth_material (reconfigure.test) and rope_material set live are the
// presets of requests without material or constants; unknown presets are refused.
TEST_F(ReconfigureTest, MaterialPresetsGiveTheMassAndTheDefaultMaterials)
{
  // The presets' values (the core's table): nylon_rope μ [kg/m], cotton ρ_A [kg/m²].
  ASSERT_TRUE(particle_sim::core::findRopePreset("nylon_rope"));
  ASSERT_TRUE(particle_sim::core::findClothPreset("cotton"));
  const double nylon_rope_density = particle_sim::core::findRopePreset("nylon_rope")->linear_density;
  const double cotton_density = particle_sim::core::findClothPreset("cotton")->areal_density;

  // A rope by preset, 1.5 m long: μ·L.
  particle_sim::SpawnRope::Request rope;
  rope.name = "nylon";
  rope.particles = 16;
  rope.start.z = 1.5;
  rope.end.x = 1.5;
  rope.end.z = 1.5;
  rope.pins = {0};
  rope.material.preset = "nylon_rope";
  auto spawned = call<particle_sim::SpawnRope>("spawn_rope", rope);
  ASSERT_TRUE(spawned.success) << spawned.message;
  EXPECT_NE(spawned.message.find("material 'nylon_rope'"), std::string::npos) << spawned.message;
  ASSERT_TRUE(waitForWall([&] { return !probe_.body("nylon").name.empty(); }));
  EXPECT_NEAR(probe_.body("nylon").mass, nylon_rope_density * 1.5, 1e-12 * nylon_rope_density);
  EXPECT_EQ(probe_.body("nylon").material, "nylon_rope");

  // With a spring constant too: refused, naming both.
  rope.name = "both";
  rope.stretch_stiffness = 300.0;
  spawned = call<particle_sim::SpawnRope>("spawn_rope", rope);
  EXPECT_FALSE(spawned.success);
  EXPECT_EQ(spawned.message.rfind("material.preset = 'nylon_rope' and stretch_stiffness = 300 N/m are both set", 0), 0u)
      << spawned.message;

  // The cloth preset of ~cloth_material (reconfigure.test), shown by dynamic_reconfigure, is what a
  // cloth without material or constants gets: 0.6 m × 0.4 m of cotton.
  EXPECT_EQ(probe_.config().strs.at("cloth_material"), "cotton");
  particle_sim::SpawnCloth::Request cloth;
  cloth.name = "sheet";
  cloth.origin.z = 1.0;
  cloth.edge_u.x = 0.6;
  cloth.edge_v.y = 0.4;
  cloth.nu = 7;
  cloth.nv = 5;
  cloth.named_pins = {"edge_u0"};
  const auto cloth_spawned = call<particle_sim::SpawnCloth>("spawn_cloth", cloth);
  ASSERT_TRUE(cloth_spawned.success) << cloth_spawned.message;
  EXPECT_NE(cloth_spawned.message.find("material 'cotton'"), std::string::npos) << cloth_spawned.message;
  ASSERT_TRUE(waitForWall([&] { return !probe_.body("sheet").name.empty(); }));
  EXPECT_NEAR(probe_.body("sheet").mass, cotton_density * 0.24, 1e-12 * cotton_density);
  EXPECT_EQ(probe_.body("sheet").material, "cotton");
  EXPECT_EQ(probe_.body("rope").material, "");  // the scene's, of spring constants

  // rope_material set live: a rope without material or constants is of that preset (its mass
  // μ·L, not the 1 kg default); an unknown name is refused and the field goes back.
  auto answered = probe_.reconfigure({}, {{"rope_material", "steel?"}});
  EXPECT_EQ(answered.strs.at("rope_material"), "");
  answered = probe_.reconfigure({}, {{"rope_material", "nylon_rope"}});
  EXPECT_EQ(answered.strs.at("rope_material"), "nylon_rope");
  particle_sim::SpawnRope::Request plain;
  plain.name = "plain";
  plain.particles = 10;
  plain.start.z = 1.0;
  plain.end.x = 2.0;
  plain.end.z = 1.0;
  plain.pins = {0};
  spawned = call<particle_sim::SpawnRope>("spawn_rope", plain);
  ASSERT_TRUE(spawned.success) << spawned.message;
  ASSERT_TRUE(waitForWall([&] { return !probe_.body("plain").name.empty(); }));
  EXPECT_NEAR(probe_.body("plain").mass, nylon_rope_density * 2.0, 1e-12 * nylon_rope_density);
  answered = probe_.reconfigure({}, {{"rope_material", ""}});
  EXPECT_EQ(answered.strs.at("rope_material"), "");
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "reconfigure_test");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
