// Spring constants of a live body as ~set_spring_constants and dynamic_reconfigure set and show
// them, without a ROS master: what is read back is what was set, and each refusal names the
// field, the value as received and what is allowed, leaving the body unchanged.

#include <gtest/gtest.h>

#include "particle_sim/core/forces/baraff_witkin_model.h"
#include "particle_sim/ros/spring_constants.h"

using namespace particle_sim;
using namespace particle_sim::ros_interface;

namespace
{
// A rope "line" (stretch 500 N/m, 0.5 N·s/m; no bend springs) and a Baraff–Witkin cloth "sheet".
core::World makeWorld()
{
  core::World world{core::WorldDef{}};
  core::RopeDef rope;
  rope.name = "line";
  rope.stretch_stiffness = 500.0;
  rope.stretch_damping = 0.5;
  EXPECT_TRUE(world.addRope(rope).ok);
  core::ClothGridDef cloth(core::ClothModel::BaraffWitkin);
  cloth.name = "sheet";
  cloth.nu = cloth.nv = 4;
  EXPECT_TRUE(world.addClothGrid(cloth).ok);
  return world;
}
}  // namespace

TEST(SpringConstantsConversions, ReadsTheConstantsOfAClassOrOfTheFirstSpring)
{
  const core::World world = makeWorld();
  double stiffness = -1.0, damping = -1.0;
  ASSERT_TRUE(readSpringConstants(world, "line", "stretch", stiffness, damping));
  EXPECT_EQ(stiffness, 500.0);  // [N/m]
  EXPECT_EQ(damping, 0.5);      // [N·s/m]
  ASSERT_TRUE(readSpringConstants(world, "line", "all", stiffness, damping));
  EXPECT_EQ(stiffness, 500.0);
  EXPECT_FALSE(readSpringConstants(world, "line", "bend", stiffness, damping));  // it has none
  EXPECT_FALSE(readSpringConstants(world, "line", "twist", stiffness, damping));
  EXPECT_FALSE(readSpringConstants(world, "nobody", "stretch", stiffness, damping));

  // A Baraff–Witkin cloth shows its conditions' constants.
  const core::SpringNetworkBody& sheet = *world.findSpringBody("sheet");
  ASSERT_TRUE(readSpringConstants(world, "sheet", "shear", stiffness, damping));
  EXPECT_EQ(stiffness, sheet.baraffWitkin()->constants(core::SpringClass::Shear).stiffness);
  EXPECT_EQ(damping, sheet.baraffWitkin()->constants(core::SpringClass::Shear).damping);
}

TEST(SpringConstantsConversions, AppliedConstantsAreReadBackAndTheAnswerSaysWhat)
{
  core::World world = makeWorld();
  const core::Status status = applySpringConstants(world, "line", "stretch", 800.0, 0.7);
  ASSERT_TRUE(status.ok) << status.message;
  EXPECT_EQ(status.message.rfind("set stretch springs of 'line' to 800 N/m, 0.7 N·s/m; omega_max <= ", 0), 0u)
      << status.message;
  double stiffness = 0.0, damping = 0.0;
  ASSERT_TRUE(readSpringConstants(world, "line", "stretch", stiffness, damping));
  EXPECT_EQ(stiffness, 800.0);
  EXPECT_EQ(damping, 0.7);

  ASSERT_TRUE(applySpringConstants(world, "sheet", "all", 100.0, 0.25).ok);
  for (const char* spring_class : {"stretch", "shear", "bend"})
  {
    ASSERT_TRUE(readSpringConstants(world, "sheet", spring_class, stiffness, damping)) << spring_class;
    EXPECT_EQ(stiffness, 100.0) << spring_class;
    EXPECT_EQ(damping, 0.25) << spring_class;
  }
}

TEST(SpringConstantsConversions, RefusalsNameFieldValueAndRangeAndChangeNothing)
{
  core::World world = makeWorld();
  EXPECT_EQ(applySpringConstants(world, "nobody", "stretch", 1.0, 0.0).message,
            "body = 'nobody': no rope or spring network has that name");
  EXPECT_EQ(applySpringConstants(world, "line", "twist", 1.0, 0.0).message,
            "spring_class = 'twist' is not a spring class; allowed: stretch, shear, bend, all");
  EXPECT_EQ(applySpringConstants(world, "line", "stretch", -1.0, 0.0).message,
            "stiffness = -1 is out of range: must be in [0, 1e+09] N/m");
  EXPECT_EQ(applySpringConstants(world, "line", "stretch", 1.0, 2e6).message,
            "damping = 2e+06 is out of range: must be in [0, 1e+06] N·s/m");
  EXPECT_EQ(applySpringConstants(world, "line", "bend", 1.0, 0.0).message,
            "spring_class = 'bend': body 'line' has no such springs");
  double stiffness = 0.0, damping = 0.0;
  ASSERT_TRUE(readSpringConstants(world, "line", "stretch", stiffness, damping));
  EXPECT_EQ(stiffness, 500.0);
  EXPECT_EQ(damping, 0.5);
}
