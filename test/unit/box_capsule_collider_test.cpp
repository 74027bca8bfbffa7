// Box and capsule colliders (issue 14, item 3): where a contact puts a particle, the sweep that
// keeps fast paths and thin boxes from tunnelling, moving colliders pushing with their velocity,
// and bodies against them: a cloth swept by a thin fast box, a cloth draped over a box, a rope swept
// by a capsule, a jelly pushed by a box.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/builders/jelly.h"
#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/environment.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/world.h"

using namespace particle_sim::core;

namespace
{
Eigen::Quaterniond aboutZ(double angle)
{
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()));
}

ParticlePool oneParticle(const Eigen::Vector3d& x, const Eigen::Vector3d& v = Eigen::Vector3d::Zero())
{
  ParticlePool pool;
  pool.resize(1, 1);
  pool.inverse_mass[0] = 1.0;
  pool.position.col(0) = x;
  pool.velocity.col(0) = v;
  return pool;
}

Environment withoutGround()
{
  Environment env;
  env.ground.enabled = false;
  return env;
}

// A particle's coordinates in a collider's frame.
template <typename Collider>
Eigen::Vector3d local(const Collider& c, const Eigen::Vector3d& x)
{
  return c.orientation.toRotationMatrix().transpose() * (x - c.center);
}
}  // namespace

TEST(BoxCollider, PushesOutThroughTheNearestFaceOfTheTurnedBox)
{
  Environment env = withoutGround();
  BoxColliderDef box;
  box.name = "table";
  box.center = {1.0, 2.0, 3.0};
  box.orientation = aboutZ(M_PI / 6.0);
  box.half_extents = {0.5, 0.2, 0.1};
  env.boxes.push_back(box);
  // At rest 5 cm inside the +x face (the nearest: 5 cm, against 20 cm and 10 cm to the others).
  const Eigen::Vector3d inside = box.center + box.orientation * Eigen::Vector3d(0.45, 0.03, -0.02);
  ParticlePool pool = oneParticle(inside);
  resolveCollisions(env, pool);
  const Eigen::Vector3d q = local(box, pool.position.col(0));
  EXPECT_NEAR(q.x(), 0.5, 1e-12);
  EXPECT_NEAR(q.y(), 0.03, 1e-12);
  EXPECT_NEAR(q.z(), -0.02, 1e-12);
  // A contact thickness t keeps it t outside the face.
  pool = oneParticle(inside);
  resolveCollisions(env, pool, nullptr, nullptr, 0.01);
  EXPECT_NEAR(local(box, pool.position.col(0)).x(), 0.51, 1e-12);
  // Outside: untouched.
  const Eigen::Vector3d outside = box.center + box.orientation * Eigen::Vector3d(0.2, 0.25, 0.0);
  pool = oneParticle(outside);
  resolveCollisions(env, pool);
  EXPECT_EQ(Eigen::Vector3d(pool.position.col(0)), outside);
}

TEST(CapsuleCollider, PushesOutRadiallyFromItsAxisAndFromItsCaps)
{
  Environment env = withoutGround();
  CapsuleColliderDef capsule;
  capsule.name = "finger";
  capsule.center = {0.0, 0.0, 1.0};
  capsule.orientation = aboutZ(M_PI / 2.0);  // axis along world y
  capsule.half_length = 0.3;
  capsule.radius = 0.1;
  env.capsules.push_back(capsule);
  // Beside the axis: out along the perpendicular from the axis point (0.1, 0, 0).
  ParticlePool pool = oneParticle(capsule.center + capsule.orientation * Eigen::Vector3d(0.1, 0.03, 0.04));
  resolveCollisions(env, pool);
  Eigen::Vector3d q = local(capsule, pool.position.col(0));
  EXPECT_NEAR(q.x(), 0.1, 1e-12);
  EXPECT_NEAR(q.y(), 0.06, 1e-12);
  EXPECT_NEAR(q.z(), 0.08, 1e-12);
  // Past the end of the axis: out of the cap, from its centre (0.3, 0, 0).
  pool = oneParticle(capsule.center + capsule.orientation * Eigen::Vector3d(0.35, 0.0, 0.02));
  resolveCollisions(env, pool);
  q = local(capsule, pool.position.col(0));
  EXPECT_NEAR((q - Eigen::Vector3d(0.3, 0.0, 0.0)).norm(), 0.1, 1e-12);
  EXPECT_NEAR(q.z() / (q.x() - 0.3), 0.02 / 0.05, 1e-9);  // along the same direction
  // The world axis really is y: a particle at (0, 0.25, 1.05) is inside, at (0, 0.45, 1.0) not.
  pool = oneParticle({0.0, 0.25, 1.05});
  resolveCollisions(env, pool);
  EXPECT_NEAR(pool.position(2, 0), 1.1, 1e-12);
  pool = oneParticle({0.0, 0.45, 1.0});
  resolveCollisions(env, pool);
  EXPECT_EQ(pool.position(1, 0), 0.45);
}

TEST(BoxCollider, AFastParticleIsStoppedByAThinBoxItsStepWouldJumpOver)
{
  // 2 m/s at dt = 1/60 is 33 mm a step; the box is 1 cm thick. Without its path the particle ends
  // beyond the box untouched (the control); with it, it is caught on the face it met.
  Environment env = withoutGround();
  BoxColliderDef wall;
  wall.name = "wall";
  wall.half_extents = {0.5, 0.005, 0.5};
  wall.contact.restitution = 0.0;
  env.boxes.push_back(wall);
  const double dt = 1.0 / 60.0;
  const Eigen::Vector3d start(0.1, -0.02, 0.0), velocity(0.0, 2.0, 0.0);
  ParticlePool pool = oneParticle(start + dt * velocity, velocity);
  resolveCollisions(env, pool);
  EXPECT_GT(pool.position(1, 0), 0.005) << "the control: the step jumps over the box";
  pool = oneParticle(start + dt * velocity, velocity);
  const Eigen::Matrix3Xd path_start = start;
  resolveCollisions(env, pool, nullptr, &path_start, 0.0, dt);
  EXPECT_NEAR(pool.position(1, 0), -0.005, 1e-9);
  EXPECT_NEAR(pool.position(0, 0), 0.1, 1e-12);
  EXPECT_LE(pool.velocity(1, 0), 1e-12) << "no longer moving into the box";
}

TEST(CapsuleCollider, AFastParticleIsStoppedByAThinCapsuleItsStepWouldJumpOver)
{
  Environment env = withoutGround();
  CapsuleColliderDef rod;
  rod.name = "rod";
  rod.half_length = 0.5;  // along x
  rod.radius = 0.004;
  rod.contact.restitution = 0.0;
  env.capsules.push_back(rod);
  const double dt = 1.0 / 60.0;
  const Eigen::Vector3d start(0.2, 0.0, 0.02), velocity(0.0, 0.0, -2.5);
  ParticlePool pool = oneParticle(start + dt * velocity, velocity);
  resolveCollisions(env, pool);
  EXPECT_LT(pool.position(2, 0), -0.004) << "the control: the step jumps over the rod";
  pool = oneParticle(start + dt * velocity, velocity);
  const Eigen::Matrix3Xd path_start = start;
  resolveCollisions(env, pool, nullptr, &path_start, 0.0, dt);
  EXPECT_NEAR(pool.position(2, 0), 0.004, 1e-9);
  EXPECT_GE(pool.velocity(2, 0), -1e-12);
}

TEST(BoxCollider, AMovingBoxPushesAParticleAtRestWithItsOwnVelocity)
{
  // A thin box at 2 m/s reaches a particle at rest in one step and would pass it. Relative to the
  // box the particle comes at it at 2 m/s: it ends on the box's front face, moving at least as
  // fast as the box (2 m/s plus the bounce: 2 (1 + e) with restitution e).
  Environment env = withoutGround();
  const double dt = 1.0 / 60.0;
  BoxColliderDef paddle;
  paddle.name = "paddle";
  paddle.half_extents = {0.3, 0.005, 0.3};
  paddle.contact.restitution = 0.5;
  paddle.contact.friction = 0.0;
  env.boxes.push_back(paddle);
  World world([&] {
    WorldDef def;
    def.ground.enabled = false;
    def.boxes = env.boxes;
    return def;
  }());
  ASSERT_TRUE(world.setColliderPose("paddle", {0.0, 2.0 * dt, 0.0}, Eigen::Quaterniond::Identity(), dt).ok);
  const BoxColliderDef& moved = world.environment().boxes.front();
  EXPECT_NEAR(moved.motion.velocity.y(), 2.0, 1e-12);
  EXPECT_NEAR(moved.motion.angular_velocity.norm(), 0.0, 1e-12);

  ParticlePool pool = oneParticle({0.0, 0.01, 0.0});
  const Eigen::Matrix3Xd path_start = pool.position.leftCols(1);
  resolveCollisions(world.environment(), pool, nullptr, &path_start, 0.0, dt);
  EXPECT_GE(pool.position(1, 0), moved.center.y() + 0.005 - 1e-12);
  EXPECT_NEAR(pool.velocity(1, 0), 2.0 * 1.5, 1e-9);
  EXPECT_NEAR(pool.velocity(0, 0), 0.0, 1e-12);

  // A turn is read as an angular velocity: a quarter turn about z over 0.5 s is π rad/s.
  ASSERT_TRUE(world.setColliderPose("paddle", moved.center, aboutZ(M_PI / 2.0), 0.5).ok);
  EXPECT_NEAR(world.environment().boxes.front().motion.angular_velocity.z(), M_PI, 1e-9);
  // Refusals name the field.
  const Status bad = world.setColliderPose("paddle", moved.center, Eigen::Quaterniond(2.0, 0.0, 0.0, 0.0), dt);
  EXPECT_FALSE(bad.ok);
  EXPECT_NE(bad.message.find("not a unit quaternion"), std::string::npos) << bad.message;
  const Status unknown = world.setColliderPose("nothing", moved.center, Eigen::Quaterniond::Identity(), dt);
  EXPECT_FALSE(unknown.ok);
  EXPECT_NE(unknown.message.find("no box or capsule collider"), std::string::npos) << unknown.message;
}

TEST(BoxCollider, WorldRefusesBadBoxesAndCapsulesAndSharedNames)
{
  WorldDef def;
  BoxColliderDef box;
  box.name = "b";
  box.half_extents = {0.1, 0.0, 0.1};
  def.boxes = {box};
  Status s = validate(def);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("box 'b'.half_extents[1]"), std::string::npos) << s.message;
  def.boxes.front().half_extents.y() = 0.1;
  EXPECT_TRUE(validate(def).ok);
  CapsuleColliderDef capsule;
  capsule.name = "b";
  def.capsules = {capsule};
  s = validate(def);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("'b' is used twice"), std::string::npos) << s.message;
  def.capsules.front().name = "c";
  def.capsules.front().radius = -1.0;
  s = validate(def);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("capsule 'c'.radius"), std::string::npos) << s.message;
}

TEST(BoxCollider, AThinBoxAtTwoMetresASecondSweepsAClothWithoutPassingThroughIt)
{
  // A 0.3 m square cloth floats (no gravity) in the plane y = 0. A 1 cm thick paddle, 0.6 m
  // square, starts 5 cm behind it and moves through its plane at 2 m/s: 33 mm a step at dt = 1/60,
  // more than its thickness, with implicit Euler's one substep a step. The cloth cannot go round
  // the larger paddle, so after every step every particle must be in front of its face.
  WorldDef def;
  def.dt = 1.0 / 60.0;
  def.gravity.setZero();
  def.ground.enabled = false;
  BoxColliderDef paddle;
  paddle.name = "paddle";
  paddle.center = {0.0, -0.05, 1.5};
  paddle.half_extents = {0.3, 0.005, 0.3};
  paddle.contact.restitution = 0.0;  // carried, not bounced ahead
  def.boxes = {paddle};
  World world(def);
  ClothGridDef cloth(ClothModel::Springs);
  cloth.name = "cloth";
  cloth.origin = {-0.15, 0.0, 1.65};
  cloth.edge_u = {0.3, 0.0, 0.0};
  cloth.edge_v = {0.0, 0.0, -0.3};
  cloth.nu = cloth.nv = 16;
  cloth.mass = 0.1;
  cloth.stretch = {500.0, 0.5};
  cloth.shear = {100.0, 0.1};
  cloth.bend = {1.0, 0.01};
  cloth.integrator.type = kImplicitEulerIntegrator;
  ASSERT_TRUE(world.addClothGrid(cloth).ok);
  const SpringNetworkBody& body = *world.findSpringBody("cloth");
  for (int step = 0; step < 30; ++step)  // 0.5 s: the paddle ends 0.95 m in front of the plane
  {
    const Eigen::Vector3d center = paddle.center + Eigen::Vector3d(0.0, 2.0 * def.dt * (step + 1), 0.0);
    ASSERT_TRUE(world.setColliderPose("paddle", center, Eigen::Quaterniond::Identity(), def.dt).ok);
    world.step();
    for (int i = 0; i < body.particles().size(); ++i)
    {
      const Eigen::Vector3d q = body.particles().position.col(i) - center;
      ASSERT_LT(std::abs(q.x()), 0.3);
      ASSERT_LT(std::abs(q.z()), 0.3);
      ASSERT_GE(q.y(), 0.005 - 1e-9) << "particle " << i << " is inside or behind the paddle after step " << step;
    }
  }
  // And it was carried: its mean speed is the paddle's.
  const double mean_speed = body.particles().velocity.row(1).leftCols(body.particles().size()).mean();
  EXPECT_NEAR(mean_speed, 2.0, 0.2);
}

TEST(BoxCollider, ClothDrapedOverABoxRestsOnItsTopAndHangsDownItsSides)
{
  // A 1 m square cloth dropped flat from 10 cm above a 0.4 m table top (box top at z = 0.5) on the
  // ground. After 4 s: nothing inside the box; the part over the top lies on it; the rest hangs
  // below the top, outside the box.
  WorldDef def;
  def.dt = 1.0 / 240.0;
  BoxColliderDef table;
  table.name = "table";
  table.center = {0.0, 0.0, 0.25};
  table.half_extents = {0.2, 0.2, 0.25};
  table.contact.friction = 0.5;
  def.boxes = {table};
  World world(def);
  ClothGridDef cloth(ClothModel::Springs);
  cloth.name = "tablecloth";
  cloth.origin = {-0.5, -0.5, 0.6};
  cloth.edge_u = {1.0, 0.0, 0.0};
  cloth.edge_v = {0.0, 1.0, 0.0};
  cloth.nu = cloth.nv = 21;
  cloth.mass = 0.2;
  cloth.stretch = {800.0, 0.5};
  cloth.shear = {200.0, 0.2};
  cloth.bend = {0.5, 0.01};
  cloth.integrator.type = kImplicitEulerIntegrator;
  ASSERT_TRUE(world.addClothGrid(cloth).ok);
  for (int step = 0; step < 960; ++step)
    world.step();
  const SpringNetworkBody& body = *world.findSpringBody("tablecloth");
  const Eigen::Vector3d top_extents = table.half_extents;
  double centre_height = 0.0, fastest = 0.0;
  for (int i = 0; i < body.particles().size(); ++i)
  {
    const Eigen::Vector3d x = body.particles().position.col(i);
    const Eigen::Vector3d q = x - table.center;
    ASSERT_FALSE((q.cwiseAbs().array() < top_extents.array() - 1e-9).all()) << "particle " << i << " inside";
    ASSERT_TRUE(x.allFinite());
    fastest = std::max(fastest, body.particles().velocity.col(i).norm());
    if (i == 10 * 21 + 10) centre_height = x.z();
  }
  EXPECT_NEAR(centre_height, 0.5, 2e-3) << "the middle lies on the top";
  // The corners (0.5 m from the middle, the top 0.2 m wide) hang below the top.
  for (int corner : {0, 20, 20 * 21, 21 * 21 - 1})
    EXPECT_LT(body.particles().position(2, corner), 0.45) << "corner " << corner;
  RecordProperty("fastest_particle_after_4_s", std::to_string(fastest));
}

TEST(CapsuleCollider, ACapsuleSweepsARopeLyingOnTheGroundSideways)
{
  // A 1 m rope on the ground along x; a capsule lying along x (radius 3 cm) sweeps across it at
  // 0.5 m/s along y. After the sweep every particle is ahead of the capsule (y beyond its
  // surface), none left behind or inside.
  WorldDef def;
  def.dt = 1.0 / 120.0;
  CapsuleColliderDef sweeper;
  sweeper.name = "sweeper";
  sweeper.center = {0.5, -0.1, 0.02};  // dips into the ground: it reaches what lies there
  sweeper.half_length = 0.7;
  sweeper.radius = 0.03;
  sweeper.contact.friction = 0.2;
  def.capsules = {sweeper};
  World world(def);
  RopeDef rope;
  rope.name = "rope";
  rope.particles = 21;
  rope.start = {0.0, 0.0, 0.0};
  rope.end = {1.0, 0.0, 0.0};
  rope.mass = 0.1;
  rope.pins.clear();
  rope.integrator.type = kImplicitEulerIntegrator;
  ASSERT_TRUE(world.addRope(rope).ok);
  const SpringNetworkBody& body = *world.findSpringBody("rope");
  Eigen::Vector3d center = sweeper.center;
  for (int step = 0; step < 120; ++step)  // 1 s: 0.5 m
  {
    center.y() += 0.5 * def.dt;
    ASSERT_TRUE(world.setColliderPose("sweeper", center, Eigen::Quaterniond::Identity(), def.dt).ok);
    world.step();
    for (int i = 0; i < body.particles().size(); ++i)
    {
      const Eigen::Vector3d x = body.particles().position.col(i);
      const double along = std::clamp(x.x() - center.x(), -sweeper.half_length, sweeper.half_length);
      const double distance = (x - center - Eigen::Vector3d(along, 0.0, 0.0)).norm();
      ASSERT_GE(distance, sweeper.radius - 1e-9) << "particle " << i << " inside after step " << step;
      ASSERT_GT(x.y(), center.y()) << "particle " << i << " left behind after step " << step;
    }
  }
  EXPECT_GT(body.particles().position.row(1).leftCols(21).minCoeff(), 0.35) << "the whole rope was carried along";
}

TEST(BoxCollider, ABoxPushesAJellyAlongTheGround)
{
  // A 0.2 m jelly cube at rest on the ground; a box (0.3 m wide) starts 5 cm from its side and
  // moves 0.4 m along x at 0.4 m/s. The jelly's centre of mass moves about as far as the box's
  // front passes its start (0.4 - 0.05 m), and no particle is inside the box.
  WorldDef def;
  def.dt = 1.0 / 240.0;
  BoxColliderDef pusher;
  pusher.name = "pusher";
  pusher.center = {-0.2, 0.1, 0.1};
  pusher.half_extents = {0.1, 0.15, 0.1};
  def.boxes = {pusher};
  World world(def);
  JellyDef jelly;
  jelly.name = "jelly";
  jelly.origin = {-0.05 + 0.0, 0.0, 0.0};
  jelly.size = {0.2, 0.2, 0.2};
  jelly.nx = jelly.ny = jelly.nz = 4;
  jelly.mass = 0.5;
  jelly.integrator.type = kImplicitEulerIntegrator;
  ASSERT_TRUE(world.addJelly(jelly).ok);
  const SpringNetworkBody& body = *world.findSpringBody("jelly");
  auto centreOfMass = [&] {
    return Eigen::Vector3d(body.particles().position.leftCols(body.particles().size()).rowwise().mean());
  };
  for (int step = 0; step < 120; ++step)  // settle on the ground
    world.step();
  const Eigen::Vector3d before = centreOfMass();
  Eigen::Vector3d center = pusher.center;
  for (int step = 0; step < 240; ++step)  // 1 s at 0.4 m/s
  {
    center.x() += 0.4 * def.dt;
    ASSERT_TRUE(world.setColliderPose("pusher", center, Eigen::Quaterniond::Identity(), def.dt).ok);
    world.step();
    for (int i = 0; i < body.particles().size(); ++i)
    {
      const Eigen::Vector3d q = body.particles().position.col(i) - center;
      ASSERT_FALSE((q.cwiseAbs().array() < pusher.half_extents.array() - 1e-9).all())
          << "particle " << i << " inside after step " << step;
    }
  }
  const double moved = centreOfMass().x() - before.x();
  EXPECT_GT(moved, 0.3);
  EXPECT_LT(moved, 0.45);
}

TEST(BoxCollider, WorldAddsAndRemovesCollidersByNameAtRunTime)
{
  WorldDef def;
  SphereColliderDef ball;
  ball.name = "ball";
  ball.center = {5.0, 0.0, 0.0};
  def.spheres = {ball};
  World world(def);
  BoxColliderDef box;
  box.name = "table";
  box.half_extents = {0.5, 0.5, 0.05};
  ASSERT_TRUE(world.addCollider(box).ok);
  CapsuleColliderDef capsule;
  capsule.name = "ball";  // taken by the sphere
  Status s = world.addCollider(capsule);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("'ball' is taken"), std::string::npos) << s.message;
  capsule.name = "_finger";  // the rules of body names
  EXPECT_FALSE(world.addCollider(capsule).ok);
  capsule.name = "finger";
  capsule.radius = 0.0;
  s = world.addCollider(capsule);
  EXPECT_NE(s.message.find("capsule 'finger'.radius"), std::string::npos) << s.message;
  capsule.radius = 0.02;
  ASSERT_TRUE(world.addCollider(capsule).ok);
  EXPECT_EQ(world.environment().boxes.size(), 1u);
  EXPECT_EQ(world.environment().capsules.size(), 1u);

  // A particle dropped onto the table rests on it; once the table is removed it falls through.
  ParticlePool pool = oneParticle({0.0, 0.0, 0.04});
  resolveCollisions(world.environment(), pool);
  EXPECT_NEAR(pool.position(2, 0), 0.05, 1e-12);
  ASSERT_TRUE(world.removeCollider("table").ok);
  ASSERT_TRUE(world.removeCollider("ball").ok);
  EXPECT_TRUE(world.environment().boxes.empty());
  EXPECT_TRUE(world.environment().spheres.empty());
  pool = oneParticle({0.0, 0.0, 0.04});
  Environment env = world.environment();
  env.ground.enabled = false;
  resolveCollisions(env, pool);
  EXPECT_EQ(pool.position(2, 0), 0.04);
  s = world.removeCollider("table");
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("no sphere, box or capsule collider has that name"), std::string::npos) << s.message;
}
