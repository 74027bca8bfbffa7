// Self- and body–body collision (core/constraints/self_collision.h): impulses against analytic
// answers (a point meets a fixed triangle, two capsules meet), momentum, determinism, and cloths
// that fold, pile up and are struck, checked after every step by the brute-force intersection test
// of intersection_check.h.

#include <gtest/gtest.h>

#include "folded_cloth.h"
#include "intersection_check.h"
#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/builders/mesh_cloth.h"
#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/integrators/bdf2.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/registry.h"
#include "particle_sim/core/integrators/symplectic_euler.h"
#include "particle_sim/core/world.h"
#include "test_helpers.h"

namespace core = particle_sim::core;

namespace
{
constexpr double kThickness = 0.005;  // [m]

// A rope of two particles (one capsule) from `a` to `b` moving at `velocity`, colliding.
core::SpringNetworkDef stick(const std::string& name, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& velocity)
{
  core::RopeDef rope;
  rope.name = name;
  rope.particles = 2;
  rope.start = a;
  rope.end = b;
  rope.mass = 0.02;
  core::SpringNetworkDef def = core::buildRope(rope);
  def.velocities.assign(2, velocity);
  def.self_collision = core::SelfCollisionDef{true, kThickness};
  return def;
}

core::World weightlessWorld(double dt, core::IntegratorType type)
{
  core::WorldDef def;
  def.dt = dt;
  def.gravity.setZero();
  def.ground.enabled = false;
  def.integrator.type = type;
  return core::World(def);
}

// A fixed triangle (every corner pinned) in the plane z = 0.
core::SpringNetworkDef fixedTriangle(bool colliding)
{
  core::MeshClothDef triangle;
  triangle.name = "triangle";
  triangle.vertices = {{-1.0, -1.0, 0.0}, {1.0, -1.0, 0.0}, {0.0, 1.0, 0.0}};
  triangle.triangles = {{0, 1, 2}};
  triangle.pins = {0, 1, 2};
  core::SpringNetworkDef def = core::buildMeshCloth(triangle);
  def.self_collision = core::SelfCollisionDef{colliding, kThickness};
  return def;
}

TEST(SelfCollision, APointFlyingThroughAFixedTriangleStopsAtItAndKeepsItsTangentialVelocity)
{
  // The stick falls at 40 m/s along −z with 3 m/s along x: it would cross z = 0 within the step (it
  // starts 0.1 m above, and moves 0.4 m). The impulse stops its normal approach (inelastic: the end
  // velocity's normal part is 0) and leaves the tangential part alone (no friction).
  for (core::IntegratorType type : {core::kSymplecticEulerIntegrator, core::kImplicitEulerIntegrator})
  {
    core::World world = weightlessWorld(0.01, type);
    ASSERT_TRUE(world.addSpringNetwork(fixedTriangle(true)).ok);
    ASSERT_TRUE(world.addSpringNetwork(stick("stick", {-0.1, 0.0, 0.1}, {0.1, 0.0, 0.1}, {3.0, 0.0, -40.0})).ok);
    world.step();
    const core::SpringNetworkBody& s = *world.findSpringBody("stick");
    for (int i = 0; i < 2; ++i)
    {
      EXPECT_GT(s.particles().position(2, i), 0.0) << core::toString(type);
      EXPECT_NEAR(s.particles().velocity(2, i), 0.0, 1e-9) << core::toString(type);
      EXPECT_NEAR(s.particles().velocity(0, i), 3.0, 1e-9) << core::toString(type);
    }
    EXPECT_EQ(world.lastCollisions().bodies[1].collisions, 2) << "one point–triangle pair per end";
    EXPECT_EQ(world.lastCollisions().impact_zones, 0);
  }
}

TEST(SelfCollision, TwoCrossingCapsulesStopApproachingWithMomentumKept)
{
  // Two sticks crossed at right angles, 0.1 m apart along z, closing at 30 m/s: an edge–edge
  // collision. The impulses are equal and opposite: momentum is kept to rounding, and the
  // sticks end on their own sides, no longer approaching.
  core::World world = weightlessWorld(0.01, core::kSymplecticEulerIntegrator);
  ASSERT_TRUE(world.addSpringNetwork(stick("low", {-0.2, 0.0, 0.0}, {0.2, 0.0, 0.0}, {0.0, 0.0, 10.0})).ok);
  ASSERT_TRUE(world.addSpringNetwork(stick("high", {0.05, -0.2, 0.1}, {0.05, 0.2, 0.1}, {1.0, 0.0, -20.0})).ok);
  const auto momentum = [&] {
    return Eigen::Vector3d(world.findSpringBody("low")->momentum() + world.findSpringBody("high")->momentum());
  };
  const Eigen::Vector3d before = momentum();
  world.step();
  EXPECT_LT((momentum() - before).norm(), 1e-12);
  const core::SpringNetworkBody& low = *world.findSpringBody("low");
  const core::SpringNetworkBody& high = *world.findSpringBody("high");
  EXPECT_GT(high.particles().position.row(2).minCoeff(), low.particles().position.row(2).maxCoeff());
  // They meet after 0.1 m / 30 m/s, where the high stick (moving at 1 m/s along x) crosses the low
  // one at x = 0.05 m + 1 m/s · t_meet: that point of the low stick, and the middle of the high one,
  // end the step with the same normal velocity (inelastic).
  const double t_meet = 0.1 / 30.0;
  const double s_low = (0.05 + 1.0 * t_meet + 0.2) / 0.4;
  const double v_low = (1.0 - s_low) * low.particles().velocity(2, 0) + s_low * low.particles().velocity(2, 1);
  const double v_high = 0.5 * (high.particles().velocity(2, 0) + high.particles().velocity(2, 1));
  EXPECT_NEAR(v_high - v_low, 0.0, 1e-9);
  EXPECT_EQ(world.lastCollisions().total.collisions, 1);
  EXPECT_EQ(world.lastCollisions().bodies[0].collisions, 1);
  EXPECT_EQ(world.lastCollisions().bodies[1].collisions, 1);
}

TEST(SelfCollision, BodiesCollideOnlyWhenBothEnableIt)
{
  for (bool triangle_enables : {false, true})
  {
    core::World world = weightlessWorld(0.01, core::kSymplecticEulerIntegrator);
    ASSERT_TRUE(world.addSpringNetwork(fixedTriangle(triangle_enables)).ok);
    ASSERT_TRUE(world.addSpringNetwork(stick("stick", {-0.1, 0.0, 0.1}, {0.1, 0.0, 0.1}, {0.0, 0.0, -40.0})).ok);
    world.step();
    const double z = world.findSpringBody("stick")->particles().position(2, 0);
    if (triangle_enables)
      EXPECT_GT(z, 0.0);
    else
      EXPECT_NEAR(z, 0.1 - 0.4, 1e-12) << "passes through a triangle that does not collide";
  }
}

TEST(SelfCollision, APairWithinItsThicknessIsPushedApartWithoutKineticEnergyGained)
{
  // A resting stick 2 mm above the fixed triangle (thickness 5 mm): the repulsion moves it up by a
  // tenth of the missing 3 mm over the step and leaves its velocity at rest.
  core::World world = weightlessWorld(0.01, core::kSymplecticEulerIntegrator);
  ASSERT_TRUE(world.addSpringNetwork(fixedTriangle(true)).ok);
  ASSERT_TRUE(
      world.addSpringNetwork(stick("stick", {-0.1, 0.0, 0.002}, {0.1, 0.0, 0.002}, Eigen::Vector3d::Zero())).ok);
  world.step();
  const core::SpringNetworkBody& s = *world.findSpringBody("stick");
  for (int i = 0; i < 2; ++i)
  {
    EXPECT_NEAR(s.particles().position(2, i), 0.002 + 0.1 * 0.003, 1e-12);
    EXPECT_EQ(s.particles().velocity.col(i).norm(), 0.0);
  }
  EXPECT_EQ(world.lastCollisions().bodies[1].proximity_pairs, 2);
}

// The number of intersecting pairs of `body`'s surface triangles (brute force).
int selfIntersections(const core::SpringNetworkBody& body)
{
  return particle_sim_test::countSurfaceIntersections(body.particles().position.leftCols(body.particles().size()),
                                                      body.surfaceTriangles());
}

// The folded cloth of folded_cloth.h stepped `steps` times by `type`: the steps after which two of its
// triangles intersect, the collisions the continuous detection stopped, and the largest energy
// (kinetic plus potential, `gravity` included) over the run.
struct FoldRun
{
  int intersected_steps = 0;
  int collisions = 0;
  int contacts = 0;  // proximity pairs and collisions
  double energy_start = 0.0;
  double energy_max = 0.0;
  double energy_end = 0.0;
};

FoldRun runFold(const core::WorldDef& world_def, const core::SpringNetworkDef& fold, int steps)
{
  core::World world(world_def);
  EXPECT_TRUE(world.addSpringNetwork(fold).ok);
  const core::SpringNetworkBody& cloth = *world.findSpringBody(fold.name);
  EXPECT_EQ(selfIntersections(cloth), 0) << "the start";
  FoldRun run;
  const auto energy = [&] { return cloth.kineticEnergy() + cloth.potentialEnergy(world_def.gravity); };
  run.energy_start = run.energy_max = energy();
  for (int k = 0; k < steps; ++k)
  {
    world.step();
    if (selfIntersections(cloth) > 0) ++run.intersected_steps;
    run.collisions += world.lastCollisions().total.collisions;
    run.contacts += world.lastCollisions().total.collisions + world.lastCollisions().total.proximity_pairs;
    run.energy_max = std::max(run.energy_max, energy());
  }
  run.energy_end = energy();
  return run;
}

std::vector<core::IntegratorType> everyMethod()
{
  std::vector<core::IntegratorType> types{core::kAutoIntegrator};
  for (const core::IntegratorInfo& info : core::integratorRegistry())
    types.push_back(info.type);
  return types;
}

TEST(SelfCollision, AFoldedClothDroppedOnItselfNeverIntersectsUnderAnyMethod)
{
  // A 15 × 15 cloth, 0.4 m wide, folded in half: its lower half lies on the ground, its upper half
  // 10 cm above it, joined by a half-circle crease. The upper half falls onto the lower one and
  // lands at about 1.4 m/s, 1.4 cm a step: more than the 5 mm thickness. After every step no two of its triangles
  // intersect, and it ends with less energy than it started with. (While it lands, the ground's projection of the lower
  // half raises the springs' energy for a step or two, with self-collision or without: energy is checked step by step
  // in the test below, where nothing but the cloth itself acts.)
  for (core::IntegratorType type : everyMethod())
  {
    core::WorldDef world_def;
    world_def.dt = 0.01;
    world_def.integrator.type = type;
    const FoldRun run = runFold(world_def, particle_sim_test::foldedCloth("fold", 15, 0.4, 0.1, 0.0, kThickness), 150);
    EXPECT_EQ(run.intersected_steps, 0) << core::toString(type);
    EXPECT_GT(run.contacts, 0) << core::toString(type);
    EXPECT_LT(run.energy_end, run.energy_start) << core::toString(type);
  }
}

TEST(SelfCollision, AFoldedClothClosingOnItselfInFreeSpaceNeverIntersectsAndLosesEnergy)
{
  // Without gravity or ground, the upper half of the folded cloth is thrown at its lower half at
  // 3 m/s (3 cm a step, six times the thickness): only the cloth's own forces and its collisions
  // act. It never intersects, and it ends with less energy (kinetic plus springs) than it started
  // with. (In the step of the impact the springs' energy jumps: a particle stopped at the contact
  // stretches the springs to neighbours that go on for the rest of the step; the cloth's damping
  // and the implicit methods take it out within a few steps. README, "Self-collision".)
  for (core::IntegratorType type : everyMethod())
  {
    core::WorldDef world_def;
    world_def.dt = 0.01;
    world_def.gravity.setZero();
    world_def.ground.enabled = false;
    world_def.integrator.type = type;
    core::SpringNetworkDef fold = particle_sim_test::foldedCloth("fold", 15, 0.4, 0.1, 0.0, kThickness);
    fold.velocities.assign(fold.positions.size(), Eigen::Vector3d::Zero());
    for (std::size_t i = 0; i < fold.positions.size(); ++i)
      fold.velocities[i].z() = -3.0 * fold.positions[i].z() / 0.1;  // the crease graded from 0 to −3 m/s
    const FoldRun run = runFold(world_def, fold, 100);
    EXPECT_EQ(run.intersected_steps, 0) << core::toString(type);
    EXPECT_GT(run.collisions, 0) << core::toString(type);
    EXPECT_LT(run.energy_end, run.energy_start) << core::toString(type);
  }
}
TEST(SelfCollision, AFoldedClothStruckByAFastSphereNeverIntersects)
{
  // A towel hung over a rail: the folded cloth of folded_cloth.h turned so that its crease is on
  // top, held along the crease's top row, its two 0.2 m halves hanging 3 cm apart. A sphere of
  // radius 6 cm flies through it at 6 m/s (3 cm a step, as much as the gap), across the layers at
  // the halves' mid-height: it drives the near layer into the far one and drags both. After every
  // step no two of the cloth's triangles intersect. The sphere does work on the cloth, so energy is
  // checked once it has gone: from then on the cloth never has more energy (kinetic plus potential)
  // than it had when the sphere left, and it ends with less. (Not step by step: in a step where the
  // swinging layers meet, the springs' energy can rise by a few per cent, README "Self-collision".)
  constexpr double kSize = 0.4, kGap = 0.03, kTop = 1.0, kRadius = 0.06, kSpeed = 6.0;
  for (core::IntegratorType type : everyMethod())
  {
    core::WorldDef world_def;
    world_def.dt = 0.005;
    world_def.ground.enabled = false;
    world_def.integrator.type = type;
    world_def.spheres.push_back(core::SphereColliderDef{"ball", Eigen::Vector3d(0.0, -0.5, kTop - 0.1), kRadius, {}});
    core::SpringNetworkDef towel = particle_sim_test::foldedCloth("towel", 15, kSize, kGap, 0.0, kThickness);
    // (x, y, z) -> (y, z, x), a rotation, then shifted: the crease's far point (largest x) goes to the
    // top, the layers hang in the planes y = -gap / 2 and y = +gap / 2.
    double crease = -1e9;
    for (const Eigen::Vector3d& x : towel.positions)
      crease = std::max(crease, x.x());
    for (Eigen::Vector3d& x : towel.positions)
      x = Eigen::Vector3d(x.y() - 0.5 * kSize, x.z() - 0.5 * kGap, kTop + x.x() - crease);
    towel.pins.clear();
    for (std::size_t i = 0; i < towel.positions.size(); ++i)
      if (towel.positions[i].z() > kTop - 1e-9) towel.pins.push_back(static_cast<int>(i));
    ASSERT_EQ(towel.pins.size(), 15u);

    core::World world(world_def);
    ASSERT_TRUE(world.addSpringNetwork(towel).ok);
    const core::SpringNetworkBody& cloth = *world.findSpringBody("towel");
    ASSERT_EQ(selfIntersections(cloth), 0) << "the start";
    const auto energy = [&] { return cloth.kineticEnergy() + cloth.potentialEnergy(world_def.gravity); };
    int intersected_steps = 0, contacts = 0;
    bool was_gone = false;
    double largest_swing = 0.0, energy_when_gone = 0.0, energy_after_gone = 0.0;
    const int steps = 200;  // 1 s; the sphere has passed the cloth by 0.15 s
    for (int k = 0; k < steps; ++k)
    {
      const double t = k * world_def.dt;
      const Eigen::Vector3d centre(0.0, -0.5 + kSpeed * t, kTop - 0.1);
      const bool gone = centre.y() - kRadius > 0.5;
      ASSERT_TRUE(world.setSphereCenter("ball", gone ? Eigen::Vector3d(0.0, 5.0, 0.0) : centre).ok);
      world.step();
      if (selfIntersections(cloth) > 0) ++intersected_steps;
      contacts += world.lastCollisions().total.collisions + world.lastCollisions().total.proximity_pairs;
      largest_swing = std::max(largest_swing, cloth.particles().position.row(1).cwiseAbs().maxCoeff());
      ASSERT_TRUE(cloth.particles().position.allFinite()) << core::toString(type) << " step " << k;
      const double e = energy();
      if (gone && !was_gone) energy_when_gone = e;
      if (gone) energy_after_gone = std::max(energy_after_gone, e);
      was_gone = gone;
    }
    EXPECT_EQ(intersected_steps, 0) << core::toString(type);
    EXPECT_GT(contacts, 0) << core::toString(type) << ": the layers must be pressed together";
    EXPECT_GT(largest_swing, 0.05) << core::toString(type) << ": the sphere must strike the cloth";
    EXPECT_LE(energy_after_gone, energy_when_gone) << core::toString(type);
    EXPECT_LT(energy(), energy_when_gone) << core::toString(type);
  }
}

TEST(SelfCollision, FiveClothsDroppedOnASphereNeverPassThroughThemselvesOrEachOther)
{
  // Five 11 × 11 cloths, 0.5 m wide, stacked 3 cm apart and each turned 10° from the one below, fall
  // onto a sphere of radius 0.3 m, drape over it and slide off it together. After every step no cloth intersects itself
  // or any other, and the pile ends with less energy than it started with.
  core::WorldDef world_def;
  world_def.dt = 0.005;
  world_def.integrator.type = core::kImplicitEulerIntegrator;
  world_def.spheres.push_back(core::SphereColliderDef{"ball", Eigen::Vector3d(0.0, 0.0, 0.3), 0.3, {}});
  core::World world(world_def);
  for (int k = 0; k < 5; ++k)
  {
    core::ClothGridDef grid;
    grid.name = "cloth_" + std::to_string(k);
    grid.nu = grid.nv = 11;
    const double angle = k * 10.0 * M_PI / 180.0;
    grid.edge_u = 0.5 * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
    grid.edge_v = 0.5 * Eigen::Vector3d(-std::sin(angle), std::cos(angle), 0.0);
    grid.origin = Eigen::Vector3d(0.0, 0.0, 0.7 + 0.03 * k) - 0.5 * (grid.edge_u + grid.edge_v);
    grid.mass = 0.05;
    grid.contact_thickness = 0.003;
    core::SpringNetworkDef def = core::buildClothGrid(grid);
    def.self_collision = core::SelfCollisionDef{true, kThickness};
    ASSERT_TRUE(world.addSpringNetwork(def).ok);
  }
  std::vector<const core::SpringNetworkBody*> cloths;
  for (int k = 0; k < 5; ++k)
    cloths.push_back(world.findSpringBody("cloth_" + std::to_string(k)));
  const auto energy = [&] {
    double e = 0.0;
    for (const core::SpringNetworkBody* c : cloths)
      e += c->kineticEnergy() + c->potentialEnergy(world_def.gravity);
    return e;
  };
  const double energy_start = energy();
  int intersected_steps = 0, between_steps = 0, contacts = 0;
  for (int step = 0; step < 300; ++step)
  {
    world.step();
    contacts += world.lastCollisions().total.proximity_pairs + world.lastCollisions().total.collisions;
    bool self = false, between = false;
    for (std::size_t a = 0; a < cloths.size(); ++a)
    {
      self = self || selfIntersections(*cloths[a]) > 0;
      for (std::size_t b = a + 1; b < cloths.size(); ++b)
        between = between || particle_sim_test::countIntersectionsBetween(
                                 cloths[a]->particles().position, cloths[a]->surfaceTriangles(),
                                 cloths[b]->particles().position, cloths[b]->surfaceTriangles()) > 0;
    }
    intersected_steps += self;
    between_steps += between;
  }
  EXPECT_EQ(intersected_steps, 0);
  EXPECT_EQ(between_steps, 0);
  EXPECT_GT(contacts, 0);
  EXPECT_LT(energy(), energy_start);
}

TEST(SelfCollision, TheCandidateSearchChangesTheCostButNeverTheResult)
{
  // Five 17 × 17 cloths, 0.7 m, 5 cm apart and turned 9° each, fall on a sphere and land on each
  // other (config/scenes/cloth_pile.yaml, implicit Euler), stepped twice: by a solver whose
  // candidates, grown by a margin of half an edge, serve while they cover every path, and by one
  // that grows them by no margin and searches afresh every step. Every position and velocity is the
  // same bit for bit after every step while the layers collide (a pass that skipped the pairs that
  // pairs before them in the same pass had moved made them differ in 47 of the 100 steps).
  core::Environment env;
  env.ground.enabled = true;
  env.spheres.push_back(core::SphereColliderDef{"ball", Eigen::Vector3d(0.0, 0.0, 0.3), 0.25, {}});
  constexpr int kCloths = 5;
  std::vector<std::unique_ptr<core::SpringNetworkBody>> owned;
  std::vector<core::SpringNetworkBody*> reusing, searching;
  for (int k = 0; k < kCloths; ++k)
  {
    const core::SpringNetworkDef def = particle_sim_test::clothPileLayer(k);
    owned.push_back(std::make_unique<core::SpringNetworkBody>(def));
    reusing.push_back(owned.back().get());
    owned.push_back(std::make_unique<core::SpringNetworkBody>(def));
    searching.push_back(owned.back().get());
  }
  const std::vector<int> report_index = {0, 1, 2, 3, 4};
  core::SelfCollisionSolver reuser, searcher;
  reuser.setCandidateMargin(0.5);
  searcher.setCandidateMargin(0.0);
  core::CollisionReport reused_report, searched_report;
  reused_report.bodies.resize(kCloths);
  searched_report.bodies.resize(kCloths);
  const double dt = 0.005;
  int collisions = 0, reused_steps = 0, searched_steps = 0, differing_steps = 0;
  for (int step = 0; step < 100; ++step)
  {
    for (int k = 0; k < kCloths; ++k)
    {
      reusing[k]->step(dt, env);
      searching[k]->step(dt, env);
    }
    reuser.resolve(dt, reusing, report_index, reused_report);
    searcher.forgetCandidates();
    searcher.resolve(dt, searching, report_index, searched_report);
    collisions += reused_report.total.collisions;
    reused_steps += reused_report.searches == 0;
    searched_steps += searched_report.searches > 0;
    bool same = true;
    for (int k = 0; k < kCloths; ++k)
      same = same && reusing[k]->particles().position == searching[k]->particles().position &&
             reusing[k]->particles().velocity == searching[k]->particles().velocity;
    differing_steps += !same;
  }
  EXPECT_EQ(differing_steps, 0);
  EXPECT_GT(collisions, 0);
  EXPECT_GT(reused_steps, 0);
  EXPECT_EQ(searched_steps, 100);
}

TEST(SelfCollision, ALongRopeCoiledOntoTheGroundNeverCrossesItself)
{
  // A rope of 80 capsules, 2 m long and 1 cm thick, held almost upright with its lower end 5 cm above
  // the ground, is let go: it falls and coils onto the ground. After every step no two of its
  // segments that are not neighbours come closer than 0 (they never cross).
  for (core::IntegratorType type : {core::kImplicitEulerIntegrator, core::kSymplecticEulerIntegrator})
  {
    core::WorldDef world_def;
    world_def.dt = 0.005;
    world_def.integrator.type = type;
    core::World world(world_def);
    core::RopeDef rope;
    rope.name = "rope";
    rope.particles = 81;
    rope.start = Eigen::Vector3d(0.0, 0.0, 0.05);
    rope.end = Eigen::Vector3d(0.15, 0.1, 2.04);
    rope.mass = 0.2;
    rope.stretch_stiffness = 2000.0;
    rope.bend_stiffness = 0.2;
    core::SpringNetworkDef def = core::buildRope(rope);
    def.self_collision = core::SelfCollisionDef{true, 0.01};
    ASSERT_TRUE(world.addSpringNetwork(def).ok);
    const core::SpringNetworkBody& body = *world.findSpringBody("rope");
    int crossed_steps = 0, contacts = 0;
    for (int step = 0; step < 400; ++step)
    {
      world.step();
      contacts += world.lastCollisions().total.proximity_pairs;
      crossed_steps += particle_sim_test::countChainCrossings(body.particles().position, 0, 81, 1e-9) > 0;
    }
    EXPECT_EQ(crossed_steps, 0) << core::toString(type);
    EXPECT_GT(contacts, 0) << core::toString(type) << ": the coil must touch itself";
    EXPECT_LT(body.particles().position.row(2).maxCoeff(), 0.2) << core::toString(type) << ": on the ground";
  }
}
}  // namespace
