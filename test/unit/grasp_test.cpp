// ~grasp and ~release without a master (ros/grasps.h): the request's checks, capture and release
// of pins, refusals that change nothing, and a breakaway in the very tick the force first exceeds it.

#include <gtest/gtest.h>

#include <cmath>

#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/ros/grasps.h"

using namespace particle_sim;
using ros_interface::Grasps;
using ros_interface::GraspSpec;
using ros_interface::GraspState;
using ros_interface::HeldParticle;

namespace
{
Grasp::Request sphereRequest(const std::string& name, double radius)
{
  Grasp::Request req;
  req.name = name;
  req.frame = "gripper";
  req.region = Grasp::Request::REGION_SPHERE;
  req.radius = radius;
  return req;
}

// A 1 m, 11-particle rope along x at z = 2; no ground.
core::World makeWorld(double dt = 0.002)
{
  core::WorldDef def;
  def.ground.enabled = false;
  def.dt = dt;
  core::World world{def};
  core::RopeDef rope;
  rope.name = "rope";
  rope.particles = 11;
  rope.start = {0.0, 0.0, 2.0};
  rope.end = {1.0, 0.0, 2.0};
  rope.mass = 0.5;
  rope.stretch_stiffness = 2000.0;
  rope.integrator.type = core::kImplicitEulerIntegrator;
  EXPECT_TRUE(world.addRope(rope).ok);
  return world;
}

Eigen::Isometry3d at(const Eigen::Vector3d& p)
{
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = p;
  return pose;
}

bool noPose(const std::string&, Eigen::Isometry3d&)
{
  return false;
}
}  // namespace

TEST(Grasps, RequestsAreCheckedFieldByField)
{
  GraspSpec spec;
  EXPECT_TRUE(ros_interface::toGraspSpec(sphereRequest("g", 0.05), spec).ok);
  EXPECT_EQ(spec.region.shape, core::CaptureRegion::Shape::Sphere);
  EXPECT_EQ(ros_interface::toGraspSpec(sphereRequest("g", 0.0), spec).message,
            "radius = 0 is out of range: must be in [1e-06, 100] m");
  Grasp::Request req = sphereRequest("g", 0.05);
  req.frame = "";
  EXPECT_EQ(ros_interface::toGraspSpec(req, spec).message, "frame is empty: name the gripper's tf frame");
  req = sphereRequest("g", 0.05);
  req.region = 7;
  EXPECT_EQ(ros_interface::toGraspSpec(req, spec).message,
            "region = 7 is out of range: 0 (sphere), 1 (box) or 2 (nearest)");
  req.region = Grasp::Request::REGION_BOX;
  req.half_extents.x = req.half_extents.y = 0.1;
  EXPECT_NE(ros_interface::toGraspSpec(req, spec).message.find("half_extents.z = 0 is out of range"),
            std::string::npos);
  req.region = Grasp::Request::REGION_NEAREST;
  EXPECT_EQ(ros_interface::toGraspSpec(req, spec).message,
            "count = 0 is out of range: must be in [1, 1e+06] particles");
  req = sphereRequest("g", 0.05);
  req.breakaway_force = -1.0;
  EXPECT_EQ(ros_interface::toGraspSpec(req, spec).message,
            "breakaway_force = -1 is out of range: must be in [0, 1e+09] N");
  req = sphereRequest("g", 0.05);
  req.offset.y = std::nan("");
  EXPECT_NE(ros_interface::toGraspSpec(req, spec).message.find("offset = [0, nan, 0] is not finite"),
            std::string::npos);
  EXPECT_NE(ros_interface::toGraspSpec(sphereRequest("_g", 0.05), spec).message.find("reserved"), std::string::npos);
}

TEST(Grasps, CaptureReleaseAndRefusalsThatChangeNothing)
{
  core::World world = makeWorld();
  Grasps grasps;
  GraspSpec spec;
  ASSERT_TRUE(ros_interface::toGraspSpec(sphereRequest("left", 0.15), spec).ok);
  // Around the rope's start: particles 0 and 1 (0.1 m apart), pinned where they are.
  ASSERT_TRUE(grasps.grasp(world, spec, at({0.0, 0.0, 2.0})).ok);
  const core::SpringNetworkBody& rope = *world.findSpringBody("rope");
  EXPECT_EQ(rope.pinnedCount(), 2);
  EXPECT_TRUE(rope.isPinned(0) && rope.isPinned(1));
  const GraspState& held = *grasps.find("left");
  ASSERT_EQ(held.holds.size(), 1u);
  EXPECT_EQ(held.holds[0].body, "rope");
  EXPECT_NEAR(held.holds[0].particles[1].offset.x(), 0.1, 1e-12);

  // The same name again while active, nothing in the region, an unknown body: refused, nothing changes.
  EXPECT_NE(grasps.grasp(world, spec, at({1.0, 0.0, 2.0})).message.find("is held by an active grasp"),
            std::string::npos);
  GraspSpec empty = spec;
  empty.name = "air";
  EXPECT_NE(grasps.grasp(world, empty, at({5.0, 5.0, 5.0})).message.find("the grasp captured nothing"),
            std::string::npos);
  GraspSpec again = spec;
  again.name = "again";
  EXPECT_NE(grasps.grasp(world, again, at({0.0, 0.0, 2.0})).message.find("2 pinned particles there are held already"),
            std::string::npos);
  GraspSpec unknown = spec;
  unknown.name = "other";
  unknown.body = "nope";
  EXPECT_NE(grasps.grasp(world, unknown, at({0.0, 0.0, 2.0})).message.find("body = 'nope'"), std::string::npos);
  EXPECT_EQ(grasps.all().size(), 1u);
  EXPECT_EQ(rope.pinnedCount(), 2);

  // Release: both unpinned and listed; the name is gone.
  std::vector<HeldParticle> let_go;
  const core::Status released = grasps.release(world, "left", let_go);
  ASSERT_TRUE(released.ok) << released.message;
  EXPECT_EQ(released.message, "released grasp 'left': let go of 2 particles");
  EXPECT_EQ(let_go, (std::vector<HeldParticle>{{"rope", 0}, {"rope", 1}}));
  EXPECT_EQ(rope.pinnedCount(), 0);
  EXPECT_EQ(grasps.release(world, "left", let_go).message, "name = 'left': no grasp has that name (grasps: none)");
}

TEST(Grasps, BreakawayHappensInTheTickTheForceFirstExceedsItsThreshold)
{
  // A rope held at one end swings down from horizontal; the force on the grasp grows towards the
  // bottom of the swing. A first run without breakaway records the force each tick (10 steps);
  // an identical run with the threshold at 1.5 m g must let go in exactly the first tick whose
  // force exceeds it, and keep holding before.
  const double threshold = 1.5 * 0.5 * 9.81;
  constexpr int kStepsPerTick = 10, kTicks = 200;
  auto run = [&](double breakaway, std::vector<double>& forces, double& released_at) {
    core::World world = makeWorld();
    Grasps grasps;
    GraspSpec spec;
    Grasp::Request req = sphereRequest("hand", 0.01);
    req.breakaway_force = breakaway;
    EXPECT_TRUE(ros_interface::toGraspSpec(req, spec).ok);
    EXPECT_TRUE(grasps.grasp(world, spec, at({0.0, 0.0, 2.0})).ok);
    released_at = -1.0;
    for (int tick = 0; tick < kTicks && released_at < 0.0; ++tick)
    {
      for (int k = 0; k < kStepsPerTick; ++k)
        world.step();
      std::vector<HeldParticle> let_go;
      const auto broke = grasps.update(world, noPose, world.simTime(), let_go);
      forces.push_back(grasps.find("hand")->force.norm());
      if (!broke.empty())
      {
        EXPECT_EQ(broke, std::vector<std::string>{"hand"});
        EXPECT_EQ(let_go, (std::vector<HeldParticle>{{"rope", 0}}));
        EXPECT_EQ(world.findSpringBody("rope")->pinnedCount(), 0);
        const GraspState& state = *grasps.find("hand");
        EXPECT_TRUE(state.released);
        EXPECT_NE(state.release_reason.find("exceeded the breakaway force"), std::string::npos);
        released_at = state.released_at;
      }
    }
  };
  std::vector<double> free_forces, forces;
  double never = 0.0, released_at = 0.0;
  run(0.0, free_forces, never);
  EXPECT_LT(never, 0.0) << "no breakaway without a threshold";
  const auto first = std::find_if(free_forces.begin(), free_forces.end(), [&](double f) { return f > threshold; });
  ASSERT_NE(first, free_forces.end()) << "the swing never pulls 1.5 m g";
  ASSERT_GT(first - free_forces.begin(), 5) << "the crossing should come mid-swing, not at once";
  run(threshold, forces, released_at);
  const auto tick = first - free_forces.begin();
  EXPECT_DOUBLE_EQ(released_at, 0.002 * kStepsPerTick * static_cast<double>(tick + 1));
  ASSERT_EQ(forces.size(), static_cast<std::size_t>(tick + 1));
  for (std::size_t k = 0; k < forces.size(); ++k)
    EXPECT_EQ(forces[k], free_forces[k]) << "the same run until the release";
}

TEST(Grasps, StatusAndWrenchInTheGripperFrame)
{
  GraspState grasp;
  grasp.spec.name = "hand";
  grasp.spec.frame = "tool0";
  grasp.spec.breakaway_force = 12.0;
  grasp.frame_pose.linear() = Eigen::AngleAxisd(M_PI / 2.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  grasp.force = {1.0, 0.0, 3.0};   // sim frame
  grasp.torque = {0.0, 2.0, 0.0};  // sim frame, about the gripper's origin
  grasp.holds.push_back({"rope", {{0, Eigen::Vector3d::Zero()}, {1, Eigen::Vector3d::UnitX()}}});
  const GraspStatus status = ros_interface::toGraspStatus(grasp);
  EXPECT_EQ(status.name, "hand");
  EXPECT_EQ(status.bodies, std::vector<std::string>{"rope"});
  EXPECT_EQ(status.particle_count, 2u);
  EXPECT_EQ(status.force.z, 3.0);
  EXPECT_EQ(status.breakaway_force, 12.0);
  // The gripper is turned 90° about z: sim x is its −y, sim y its x.
  const geometry_msgs::WrenchStamped wrench = ros_interface::buildGraspWrench(grasp, ros::Time(2.5));
  EXPECT_EQ(wrench.header.frame_id, "tool0");
  EXPECT_NEAR(wrench.wrench.force.x, 0.0, 1e-15);
  EXPECT_NEAR(wrench.wrench.force.y, -1.0, 1e-15);
  EXPECT_NEAR(wrench.wrench.force.z, 3.0, 1e-15);
  EXPECT_NEAR(wrench.wrench.torque.x, 2.0, 1e-15);
  EXPECT_NEAR(wrench.wrench.torque.y, 0.0, 1e-15);
}

TEST(Grasps, NearestCountsOverEveryGraspedBody)
{
  // Two ropes; the gripper is 0.02 m from the second's start and 0.05 m from the first's: "the 1
  // nearest" of every body is the second's particle 0 alone, and the 3 nearest are 2 + 1.
  core::World world = makeWorld();
  core::RopeDef other;
  other.name = "other";
  other.particles = 5;
  other.start = {0.0, 0.07, 2.0};
  other.end = {0.4, 0.07, 2.0};
  ASSERT_TRUE(world.addRope(other).ok);
  Grasps grasps;
  Grasp::Request req = sphereRequest("pinch", 0.05);
  req.region = Grasp::Request::REGION_NEAREST;
  req.count = 1;
  GraspSpec spec;
  ASSERT_TRUE(ros_interface::toGraspSpec(req, spec).ok);
  ASSERT_TRUE(grasps.grasp(world, spec, at({0.0, 0.05, 2.0})).ok);
  const GraspState& one = *grasps.find("pinch");
  ASSERT_EQ(one.holds.size(), 1u);
  EXPECT_EQ(one.holds[0].body, "other");
  EXPECT_EQ(one.holds[0].particles.size(), 1u);
  EXPECT_EQ(one.holds[0].particles[0].index, 0);
  std::vector<HeldParticle> let_go;
  ASSERT_TRUE(grasps.release(world, "pinch", let_go).ok);

  spec.region.count = 3;  // distances: other 0 (0.02), rope 0 (0.05), other 1 (0.102), rope 1 (0.112)
  ASSERT_TRUE(grasps.grasp(world, spec, at({0.0, 0.05, 2.0})).ok);
  const GraspState& three = *grasps.find("pinch");
  ASSERT_EQ(three.particleCount(), 3);
  ASSERT_EQ(three.holds.size(), 2u);
  EXPECT_EQ(three.holds[0].body, "rope");
  EXPECT_EQ(three.holds[0].particles.size(), 1u);
  EXPECT_EQ(three.holds[1].body, "other");
  EXPECT_EQ(three.holds[1].particles.size(), 2u);
}
