// ~pin_wrench/<body>: topic names that ROS accepts for every body name the core allows, and the
// wrench of a cloth's pins at rest against statics (force and torque balance gravity).

#include "particle_sim/ros/pin_wrench.h"

#include <gtest/gtest.h>
#include <ros/names.h>

#include <Eigen/Geometry>

#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/names.h"
#include "particle_sim/core/world.h"

using namespace particle_sim;

TEST(PinWrench, TopicIsAValidRosNameForEveryBodyName)
{
  const std::pair<const char*, const char*> cases[] = {
      {"rope", "pin_wrench/rope"},           {"cloth-1", "pin_wrench/cloth_1"},
      {"robot/arm", "pin_wrench/robot/arm"}, {"3d", "pin_wrench/b3d"},
      {"a//-b/", "pin_wrench/a/b_b"},        {"left/2nd-finger", "pin_wrench/left/b2nd_finger"},
  };
  for (const auto& [body, topic] : cases)
  {
    ASSERT_TRUE(core::validateBodyName(body).ok) << body;
    EXPECT_EQ(ros_interface::pinWrenchTopic(body), topic);
    std::string error;
    EXPECT_TRUE(ros::names::validate(ros_interface::pinWrenchTopic(body), error)) << body << ": " << error;
  }
}

TEST(PinWrench, ClothAtRestHangsOnItsPinsWithItsWeightAndTheMomentOfGravity)
{
  // A 0.6 x 0.4 m cloth pinned at two corners, settled by global damping. At rest the pins balance
  // gravity: force Σ r = −Σ m g = (0, 0, M g), and about the origin Σ x × r = −Σ x × m g, computed
  // here from the particles' masses and positions alone.
  core::WorldDef def;
  def.ground.enabled = false;
  def.global_damping = 10.0;
  def.dt = 0.02;
  core::World world{def};
  core::ClothGridDef cloth;
  cloth.name = "flag";
  cloth.origin = {0.3, -0.2, 2.0};
  cloth.edge_u = {0.6, 0.0, 0.0};
  cloth.edge_v = {0.0, 0.4, 0.0};
  cloth.nu = 13;
  cloth.nv = 9;
  cloth.mass = 0.3;
  cloth.named_pins = {"corner_00", "corner_10"};
  cloth.integrator.type = core::kImplicitEulerIntegrator;
  ASSERT_TRUE(world.addClothGrid(cloth).ok);
  for (int step = 0; step < 1500; ++step)
    world.step();
  const core::SpringNetworkBody& body = *world.findSpringBody("flag");
  const core::ParticlePool& p = body.particles();
  ASSERT_LT(p.velocity.leftCols(p.size()).colwise().norm().maxCoeff(), 1e-6) << "not at rest";

  Eigen::Vector3d weight_torque = Eigen::Vector3d::Zero();
  double mass = 0.0;
  for (int i = 0; i < p.size(); ++i)
  {
    const double m = body.definition().masses[static_cast<std::size_t>(i)];
    mass += m;
    weight_torque += p.position.col(i).cross(m * def.gravity);
  }
  const geometry_msgs::WrenchStamped wrench = ros_interface::buildPinWrench(body, ros::Time(4.0), "sim");
  EXPECT_EQ(wrench.header.frame_id, "sim");
  EXPECT_EQ(wrench.header.stamp, ros::Time(4.0));
  const double weight = mass * 9.81;
  EXPECT_NEAR(wrench.wrench.force.x, 0.0, 1e-4 * weight);
  EXPECT_NEAR(wrench.wrench.force.y, 0.0, 1e-4 * weight);
  EXPECT_NEAR(wrench.wrench.force.z, weight, 1e-4 * weight);
  // Moment arm about 2 m: allow 1e-4 of the weight times it.
  EXPECT_NEAR(wrench.wrench.torque.x, -weight_torque.x(), 2e-4 * weight);
  EXPECT_NEAR(wrench.wrench.torque.y, -weight_torque.y(), 2e-4 * weight);
  EXPECT_NEAR(wrench.wrench.torque.z, -weight_torque.z(), 2e-4 * weight);
  EXPECT_GT(std::abs(wrench.wrench.torque.x), 0.1 * weight) << "the case has a moment to check";
}
