// What the node shows (~status, /diagnostics, the status line, ~step's and
// ~set_spring_constants' answers), built from a const world without a ROS master: fields against
// the world they describe, energy conservation of free flight, and the diagnostic levels at the
// thresholds README "Diagnostics" names.

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>

#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/verlet.h"
#include "particle_sim/ros/status_report.h"
#include "test_helpers.h"

using namespace particle_sim;
using namespace particle_sim::ros_interface;
using diagnostic_msgs::DiagnosticStatus;

namespace
{
// A rope of 10 particles pinned at both ends, 2 m long at rest but stretched to 3 m (strain 0.5)
// along x at height 2 m and at `y` [m], stepped by `integrator` with `linear_solver`.
core::RopeDef tautRope(const std::string& name, double y, core::IntegratorType integrator,
                       core::LinearSolverType linear_solver)
{
  core::RopeDef rope;
  rope.name = name;
  rope.particles = 10;
  rope.start = {0.0, y, 2.0};
  rope.end = {3.0, y, 2.0};
  rope.rest_length = 2.0;
  rope.pins = {0, -1};
  rope.integrator.type = integrator;
  rope.integrator.linear_solver = linear_solver;
  return rope;
}

// A world without ground (free flight) holding a fountain that bursts 5 particles straight up at
// 2 m/s from 1 m high, mass 0.01 kg each, and the taut rope "taut" at y = 0 (tautRope()).
core::World makeWorld(core::IntegratorType rope_integrator = core::kImplicitEulerIntegrator,
                      core::LinearSolverType linear_solver = core::LinearSolverType::Auto)
{
  core::WorldDef def;
  def.ground.enabled = false;
  core::World world{def};
  core::EmitterDef fountain;
  fountain.name = "fountain";
  fountain.origin = {0.0, 0.0, 1.0};
  fountain.rate = 0.0;
  fountain.burst_count = 5;
  fountain.speed = 2.0;
  fountain.spread = 0.0;
  fountain.lifetime = 100.0;
  fountain.particle_mass = 0.01;
  EXPECT_TRUE(world.addEmitter(fountain).ok);
  EXPECT_TRUE(world.addRope(tautRope("taut", 0.0, rope_integrator, linear_solver)).ok);
  return world;
}

// A world without ground holding network `n`: two particles 1 m apart joined by one soft spring
// (10 N/m) that tears past 10 % strain, particle 0 pinned and particle 1 leaving at 200 m/s along
// the spring, so that the first step of 1 ms stretches it by about 20 % and it breaks.
core::World makeTearingWorld()
{
  core::WorldDef def;
  def.ground.enabled = false;
  core::World world{def};
  core::SpringNetworkDef net;
  net.name = "n";
  net.positions = {{0.0, 0.0, 1.0}, {1.0, 0.0, 1.0}};
  net.masses = {0.1, 0.1};
  net.velocities = {Eigen::Vector3d::Zero(), {200.0, 0.0, 0.0}};
  core::Spring spring;
  spring.i = 0;
  spring.j = 1;
  spring.rest_length = 1.0;
  spring.stiffness = 10.0;
  net.springs = {spring};
  net.pins = {0};
  net.tear_strain = 0.1;
  EXPECT_TRUE(world.addSpringNetwork(net).ok);
  return world;
}

// A world without ground holding two square grid cloths (0.2 m, 5 × 5 particles) that collide with
// themselves and each other (self_collision, thickness 1 cm), `upper` lying 5 mm above `lower`,
// closer than their thickness, and between them in the world's order a rope `plain` that does not.
core::World makeCollidingWorld()
{
  core::WorldDef def;
  def.ground.enabled = false;
  core::World world{def};
  auto cloth = [](const std::string& name, double height) {
    core::ClothGridDef grid;
    grid.name = name;
    grid.nu = 5;
    grid.nv = 5;
    grid.origin = {0.0, 0.0, height};  // [m]
    grid.edge_u = {0.2, 0.0, 0.0};
    grid.edge_v = {0.0, 0.2, 0.0};
    grid.self_collision.enabled = true;
    grid.self_collision.thickness = 0.01;  // [m]
    return grid;
  };
  EXPECT_TRUE(world.addClothGrid(cloth("lower", 1.0)).ok);
  core::RopeDef rope;
  rope.name = "plain";
  rope.start = {0.0, 1.0, 1.0};
  rope.end = {1.0, 1.0, 1.0};
  EXPECT_TRUE(world.addRope(rope).ok);
  EXPECT_TRUE(world.addClothGrid(cloth("upper", 1.005)).ok);
  return world;
}

const std::string* findValue(const diagnostic_updater::DiagnosticStatusWrapper& stat, const std::string& key)
{
  for (const auto& pair : stat.values)
  {
    if (pair.key == key) return &pair.value;
  }
  return nullptr;
}

LoopFigures runningOnTime()
{
  LoopFigures loop;
  loop.real_time_factor = 1.0;
  loop.target_real_time_factor = 1.0;
  loop.step_time_us = 12.5;
  loop.steps_per_tick = 20;
  return loop;
}
}  // namespace

TEST(StatusConversions, SimStatusDescribesTheWorldAndEveryBody)
{
  core::World world = makeWorld();
  for (int k = 0; k < 10; ++k)
    world.step();
  const SimStatus status = buildSimStatus(world, ros::Time(0.01), "sim", true, 2.0);
  EXPECT_EQ(status.header.stamp, ros::Time(0.01));
  EXPECT_EQ(status.header.frame_id, "sim");
  EXPECT_EQ(status.sim_time, world.simTime());
  EXPECT_EQ(status.step_count, 10u);
  EXPECT_TRUE(status.paused);
  EXPECT_EQ(status.real_time_factor, 2.0);
  EXPECT_EQ(status.gravity.z, -9.81);  // [m/s^2]
  EXPECT_EQ(status.global_damping, 0.0);
  ASSERT_EQ(status.bodies.size(), 2u);

  const BodyStatus& fountain = status.bodies[0];
  EXPECT_EQ(fountain.name, "fountain");
  EXPECT_EQ(fountain.type, "emitter");
  EXPECT_EQ(fountain.model, "fountain");
  EXPECT_EQ(fountain.particle_count, 5u);
  EXPECT_NEAR(fountain.mass, 5 * 0.01, 1e-15);  // [kg] live particles × particle mass

  const BodyStatus& rope = status.bodies[1];
  EXPECT_EQ(rope.name, "taut");
  EXPECT_EQ(rope.type, "rope");
  EXPECT_EQ(rope.model, "springs");
  EXPECT_EQ(rope.integrator, "implicit_euler");
  EXPECT_EQ(rope.last_integrator, "implicit_euler");
  EXPECT_EQ(rope.particle_count, 10u);
  EXPECT_EQ(rope.pinned_count, 2u);
  // The pins' reactions, as the core gives them (pin_force_test.cpp tests their physics).
  const auto& taut = static_cast<const core::SpringNetworkBody&>(*world.bodies()[1]);
  const Eigen::Vector3d pin_force = taut.pinLoad({}, Eigen::Vector3d::Zero()).force;
  EXPECT_EQ(rope.pin_force.x, pin_force.x());
  EXPECT_EQ(rope.pin_force.z, pin_force.z());
  EXPECT_GT(rope.pin_force.z, 0.0);                     // they hold it up
  EXPECT_NEAR(rope.mass, core::RopeDef().mass, 1e-12);  // [kg] the rope's total, pinned ends included
  EXPECT_FALSE(rope.frozen);
  EXPECT_TRUE(rope.frozen_reason.empty());
  // An implicit step solves: a rope's system directly (integrator.linear_solver auto: no fill, so
  // cheaper than a few CG iterations), to within cg_tolerance without CG iterations after it.
  EXPECT_EQ(rope.linear_solver, "direct");
  EXPECT_EQ(rope.solver_iterations, 0u);
  EXPECT_LE(rope.solver_residual, core::IntegratorDef().cg_tolerance);
  EXPECT_GE(rope.max_strain, 0.0);
}

TEST(StatusConversions, BodiesBuiltOfAMaterialShowItsPresetOrByValue)
{
  core::World world = makeWorld();
  EXPECT_EQ(buildSimStatus(world, ros::Time(), "sim", false, 1.0).bodies[1].material, "");  // spring constants
  EXPECT_EQ(buildSimStatus(world, ros::Time(), "sim", false, 1.0, {{"taut", "nylon_rope"}}).bodies[1].material,
            "nylon_rope");
  EXPECT_EQ(buildSimStatus(world, ros::Time(), "sim", false, 1.0, {{"taut", ""}}).bodies[1].material, "by value");
  EXPECT_EQ(buildSimStatus(world, ros::Time(), "sim", false, 1.0, {{"other", "cotton"}}).bodies[1].material, "");
}

TEST(StatusConversions, EmitterEnergyIsThatOfFreeFlightAndIsConserved)
{
  // Five particles at 2 m/s, 1 m high: E = 5 (m v² / 2 + m g z) = 5 (0.02 + 0.0981) J, whatever
  // the time (the emitter's ballistic step is exact).
  const double expected = 5.0 * (0.5 * 0.01 * 4.0 + 0.01 * 9.81 * 1.0);
  core::World world = makeWorld();
  for (int k = 0; k < 150; ++k)
  {
    world.step();
    if (k != 0 && k != 149) continue;
    const BodyStatus fountain = buildSimStatus(world, ros::Time(), "sim", false, 1.0).bodies[0];
    ASSERT_EQ(fountain.particle_count, 5u);
    EXPECT_NEAR(fountain.kinetic_energy + fountain.potential_energy, expected, 1e-12);
    EXPECT_GT(fountain.kinetic_energy, 0.0);
  }
}

TEST(StatusConversions, DiagnosticsAreOkWhenRunningOnTimeAndListEveryFigure)
{
  core::World world = makeWorld();
  world.step();
  diagnostic_updater::DiagnosticStatusWrapper stat;
  buildDiagnostics(world, runningOnTime(), 0.9, stat);  // strain 0.5 is below 0.9
  EXPECT_EQ(stat.level, DiagnosticStatus::OK);
  EXPECT_EQ(stat.message, "running");
  ASSERT_NE(findValue(stat, "steps per tick"), nullptr);
  EXPECT_EQ(*findValue(stat, "steps per tick"), "20");
  EXPECT_EQ(*findValue(stat, "live particles"), "15");
  EXPECT_EQ(*findValue(stat, "bodies"), "2");
  EXPECT_EQ(*findValue(stat, "frozen bodies"), "0");
  EXPECT_EQ(*findValue(stat, "paused"), "False");
  for (const char* key :
       {"sim time [s]", "real-time factor", "target real-time factor", "step time [us]", "implicit solves (last step)",
        "direct solves (last step)", "multigrid solves (last step)", "solver iterations (max, last step)",
        "solver residual (max, last step)", "solver velocity error [m/s] (max, last step)", "max strain",
        "torn springs", "torn triangles", "split particles", "stability events since last report"})
    EXPECT_NE(findValue(stat, key), nullptr) << key;
  EXPECT_EQ(*findValue(stat, "torn springs"), "0");  // the rope cannot tear
}

TEST(StatusConversions, TornSpringsShowInStatusDiagnosticsAndTheStatusLineOfBodiesThatCanTear)
{
  core::World world = makeTearingWorld();
  const auto& net = static_cast<const core::SpringNetworkBody&>(*world.bodies()[0]);
  EXPECT_EQ(buildSimStatus(world, ros::Time(), "sim", false, 1.0).bodies[0].torn_springs, 0u);
  const std::string before = statusLine(world, 1.0, 1.0, false);
  EXPECT_EQ(before.substr(before.size() - 22), " | torn: 'n' 0 springs") << before;
  world.step();
  ASSERT_EQ(net.tornSprings(), 1);  // the spring broke in the first step
  EXPECT_TRUE(net.springs().empty());
  EXPECT_EQ(buildSimStatus(world, ros::Time(), "sim", false, 1.0).bodies[0].torn_springs, 1u);
  diagnostic_updater::DiagnosticStatusWrapper stat;
  buildDiagnostics(world, runningOnTime(), 0.9, stat);
  ASSERT_NE(findValue(stat, "torn springs"), nullptr);
  EXPECT_EQ(*findValue(stat, "torn springs"), "1");
  const std::string line = statusLine(world, 1.0, 1.0, true);
  EXPECT_NE(line.find(" | torn: 'n' 1 spring | paused"), std::string::npos) << line;
  ASSERT_NE(findValue(stat, "torn triangles"), nullptr);
  EXPECT_EQ(*findValue(stat, "torn triangles"), "0");  // springs only
  ASSERT_NE(findValue(stat, "split particles"), nullptr);
  EXPECT_EQ(*findValue(stat, "split particles"), "0");  // a network splits no vertex
  EXPECT_EQ(buildSimStatus(world, ros::Time(), "sim", false, 1.0).bodies[0].torn_triangles, 0u);
  // It stays counted in later steps, and a reset mends it.
  world.step();
  EXPECT_EQ(buildSimStatus(world, ros::Time(), "sim", false, 1.0).bodies[0].torn_springs, 1u);
  world.reset();
  EXPECT_EQ(buildSimStatus(world, ros::Time(), "sim", false, 1.0).bodies[0].torn_springs, 0u);
}

TEST(StatusConversions, CollisionCountsShowInStatusDiagnosticsAndTheStatusLineOfBodiesThatCollide)
{
  core::World world = makeCollidingWorld();
  for (int k = 0; k < 3; ++k)
    world.step();
  const core::CollisionReport& report = world.lastCollisions();
  ASSERT_EQ(report.bodies.size(), world.bodies().size());

  // ~status: each body's counts of the last step, as the world reports them (zero for the rope).
  const SimStatus status = buildSimStatus(world, ros::Time(), "sim", false, 1.0);
  ASSERT_EQ(status.bodies.size(), 3u);
  for (std::size_t i = 0; i < status.bodies.size(); ++i)
  {
    EXPECT_EQ(status.bodies[i].proximity_pairs, report.bodies[i].proximity_pairs) << i;
    EXPECT_EQ(status.bodies[i].collisions, report.bodies[i].collisions) << i;
    EXPECT_EQ(status.bodies[i].impact_zone_particles, report.bodies[i].impact_zone_particles) << i;
  }
  EXPECT_EQ(status.bodies[1].proximity_pairs, 0);  // the rope does not collide
  EXPECT_EQ(status.bodies[1].collisions, 0);
  EXPECT_EQ(status.bodies[1].impact_zone_particles, 0);

  // Diagnostics: the world's passes and impact zones, each colliding body's contacts and collisions;
  // nothing of the kind for the rope.
  diagnostic_updater::DiagnosticStatusWrapper stat;
  buildDiagnostics(world, runningOnTime(), 0.9, stat);
  ASSERT_NE(findValue(stat, "collision passes (last step)"), nullptr);
  EXPECT_EQ(*findValue(stat, "collision passes (last step)"), std::to_string(report.passes));
  ASSERT_NE(findValue(stat, "impact zones (last step)"), nullptr);
  EXPECT_EQ(*findValue(stat, "impact zones (last step)"), std::to_string(report.impact_zones));
  for (const auto& [name, i] : {std::pair<std::string, std::size_t>{"lower", 0}, {"upper", 2}})
  {
    const std::string contacts = "contacts of '" + name + "' (last step)";
    const std::string collisions = "collisions of '" + name + "' (last step)";
    ASSERT_NE(findValue(stat, contacts), nullptr) << contacts;
    EXPECT_EQ(*findValue(stat, contacts), std::to_string(report.bodies[i].proximity_pairs));
    ASSERT_NE(findValue(stat, collisions), nullptr) << collisions;
    EXPECT_EQ(*findValue(stat, collisions), std::to_string(report.bodies[i].collisions));
  }
  for (const auto& pair : stat.values)
    EXPECT_EQ(pair.key.find("'plain'"), std::string::npos) << pair.key;

  // The status line: the contacts and collisions of the two cloths, in the world's order, and not
  // the rope.
  const std::string line = statusLine(world, 1.0, 1.0, true);
  const std::string expected = " | contacts: 'lower' " + std::to_string(report.bodies[0].proximity_pairs) + " (" +
                               std::to_string(report.bodies[0].collisions) + " collision";
  const std::size_t at = line.find(expected);
  ASSERT_NE(at, std::string::npos) << line;
  EXPECT_NE(line.find(", 'upper' " + std::to_string(report.bodies[2].proximity_pairs) + " (" +
                          std::to_string(report.bodies[2].collisions) + " collision",
                      at),
            std::string::npos)
      << line;
  EXPECT_EQ(line.find("'plain'"), std::string::npos) << line;
  EXPECT_EQ(line.substr(line.size() - 9), " | paused") << line;

  // A reset clears the last step's counts.
  world.reset();
  const SimStatus after_reset = buildSimStatus(world, ros::Time(), "sim", false, 1.0);
  for (std::size_t i = 0; i < after_reset.bodies.size(); ++i)
  {
    const core::CollisionCounts counts =
        i < world.lastCollisions().bodies.size() ? world.lastCollisions().bodies[i] : core::CollisionCounts{};
    EXPECT_EQ(after_reset.bodies[i].proximity_pairs, counts.proximity_pairs) << i;
    EXPECT_EQ(after_reset.bodies[i].collisions, counts.collisions) << i;
    EXPECT_EQ(after_reset.bodies[i].impact_zone_particles, counts.impact_zone_particles) << i;
  }
}

TEST(StatusConversions, BodiesWithoutSelfCollisionShowNoCollisionEntries)
{
  // Neither the fountain nor the rope collides with itself: no collision figure in the diagnostics
  // or the status line, and zero counts in ~status.
  core::World world = makeWorld();
  world.step();
  diagnostic_updater::DiagnosticStatusWrapper stat;
  buildDiagnostics(world, runningOnTime(), 0.9, stat);
  for (const auto& pair : stat.values)
  {
    EXPECT_EQ(pair.key.find("contacts"), std::string::npos) << pair.key;
    EXPECT_EQ(pair.key.find("collision"), std::string::npos) << pair.key;
    EXPECT_EQ(pair.key.find("impact zones"), std::string::npos) << pair.key;
  }
  const std::string line = statusLine(world, 1.0, 1.0, false);
  EXPECT_EQ(line.find("contacts"), std::string::npos) << line;
  const SimStatus status = buildSimStatus(world, ros::Time(), "sim", false, 1.0);
  for (const BodyStatus& body : status.bodies)
  {
    EXPECT_EQ(body.proximity_pairs, 0) << body.name;
    EXPECT_EQ(body.collisions, 0) << body.name;
    EXPECT_EQ(body.impact_zone_particles, 0) << body.name;
  }
}

TEST(StatusConversions, DiagnosticsCountTheImplicitSolvesAndThoseSolvedDirectly)
{
  // The rope is the only implicit body: solved directly by auto and direct, iteratively by cg and by
  // the multigrid's CG.
  for (const auto solver : {core::LinearSolverType::Auto, core::LinearSolverType::Direct,
                            core::LinearSolverType::ConjugateGradient, core::LinearSolverType::Multigrid})
  {
    SCOPED_TRACE(core::toString(solver));
    core::World world = makeWorld(core::kImplicitEulerIntegrator, solver);
    world.step();
    diagnostic_updater::DiagnosticStatusWrapper stat;
    buildDiagnostics(world, runningOnTime(), 0.9, stat);
    const bool direct = solver == core::LinearSolverType::Auto || solver == core::LinearSolverType::Direct;
    const bool multigrid = solver == core::LinearSolverType::Multigrid;
    ASSERT_NE(findValue(stat, "implicit solves (last step)"), nullptr);
    EXPECT_EQ(*findValue(stat, "implicit solves (last step)"), "1");
    EXPECT_EQ(*findValue(stat, "direct solves (last step)"), direct ? "1" : "0");
    ASSERT_NE(findValue(stat, "multigrid solves (last step)"), nullptr);
    EXPECT_EQ(*findValue(stat, "multigrid solves (last step)"), multigrid ? "1" : "0");
    EXPECT_EQ(*findValue(stat, "solver iterations (max, last step)") == "0", direct);
    EXPECT_EQ(buildSimStatus(world, ros::Time(), "sim", false, 1.0).bodies[1].linear_solver, direct      ? "direct"
                                                                                             : multigrid ? "multigrid"
                                                                                                         : "cg");
    EXPECT_EQ(statusLine(world, 1.0, 1.0, false).find("(multigrid)") != std::string::npos, multigrid);
    // The velocity error of the one solve, in ~status and the diagnostics alike.
    const auto& rope = static_cast<const core::SpringNetworkBody&>(*world.bodies()[1]);
    const double velocity_error = rope.lastSolve().velocity_error;
    EXPECT_LE(velocity_error, rope.integrator().cg_velocity_tolerance);
    EXPECT_EQ(buildSimStatus(world, ros::Time(), "sim", false, 1.0).bodies[1].solver_velocity_error, velocity_error);
    ASSERT_NE(findValue(stat, "solver velocity error [m/s] (max, last step)"), nullptr);
    EXPECT_NEAR(std::stod(*findValue(stat, "solver velocity error [m/s] (max, last step)")), velocity_error,
                1e-5 * velocity_error + 1e-300);  // printed to 6 digits
  }
  // No implicit body: nothing solved.
  core::World explicit_world = makeWorld(core::kVerletIntegrator);
  explicit_world.step();
  diagnostic_updater::DiagnosticStatusWrapper stat;
  buildDiagnostics(explicit_world, runningOnTime(), 0.9, stat);
  EXPECT_EQ(*findValue(stat, "implicit solves (last step)"), "0");
  EXPECT_EQ(*findValue(stat, "direct solves (last step)"), "0");
}

TEST(StatusConversions, TheStatusLineSaysWhenOnlySomeCgSolvesHadTheMultigrid)
{
  // Two implicit ropes, the first on the multigrid's CG and the second on block Jacobi's: one of the
  // two solves had the multigrid, which the line and the diagnostics both say.
  core::World world = makeWorld(core::kImplicitEulerIntegrator, core::LinearSolverType::Multigrid);
  ASSERT_TRUE(
      world.addRope(tautRope("plain", 1.0, core::kImplicitEulerIntegrator, core::LinearSolverType::ConjugateGradient))
          .ok);
  world.step();
  const std::string line = statusLine(world, 1.0, 1.0, false);
  EXPECT_NE(line.find("| CG (some multigrid) "), std::string::npos) << line;
  diagnostic_updater::DiagnosticStatusWrapper stat;
  buildDiagnostics(world, runningOnTime(), 0.9, stat);
  ASSERT_NE(findValue(stat, "implicit solves (last step)"), nullptr);
  EXPECT_EQ(*findValue(stat, "implicit solves (last step)"), "2");
  EXPECT_EQ(*findValue(stat, "multigrid solves (last step)"), "1");
  EXPECT_EQ(*findValue(stat, "direct solves (last step)"), "0");
}

TEST(StatusConversions, DiagnosticsWarnBelowNinetyPercentOfTheTargetRealTimeFactorOnlyWhileRunning)
{
  core::World world = makeWorld();
  LoopFigures loop = runningOnTime();
  loop.real_time_factor = 0.89;  // just below 90 % of 1
  diagnostic_updater::DiagnosticStatusWrapper slow;
  buildDiagnostics(world, loop, 0.9, slow);
  EXPECT_EQ(slow.level, DiagnosticStatus::WARN);
  EXPECT_EQ(slow.message, "real-time factor 0.89 below 90 % of the target 1");

  loop.real_time_factor = 0.91;
  diagnostic_updater::DiagnosticStatusWrapper on_time;
  buildDiagnostics(world, loop, 0.9, on_time);
  EXPECT_EQ(on_time.level, DiagnosticStatus::OK);

  // Paused (now or at some time in the window), or as fast as possible: no target to miss.
  loop.real_time_factor = 0.0;
  loop.paused_in_window = true;
  diagnostic_updater::DiagnosticStatusWrapper paused;
  buildDiagnostics(world, loop, 0.9, paused);
  EXPECT_EQ(paused.level, DiagnosticStatus::OK);
  EXPECT_EQ(paused.message, "paused");
  loop.paused_in_window = false;
  loop.target_real_time_factor = 0.0;
  diagnostic_updater::DiagnosticStatusWrapper fastest;
  buildDiagnostics(world, loop, 0.9, fastest);
  EXPECT_EQ(fastest.level, DiagnosticStatus::OK);
}

TEST(StatusConversions, DiagnosticsWarnOfStabilityEventsAndStrainAboveTheThreshold)
{
  core::World world = makeWorld();
  LoopFigures loop = runningOnTime();
  loop.stability_events = 3;
  diagnostic_updater::DiagnosticStatusWrapper stat;
  buildDiagnostics(world, loop, 0.4, stat);  // the rope starts at strain 0.5
  EXPECT_EQ(stat.level, DiagnosticStatus::WARN);
  EXPECT_EQ(stat.message, "3 stability events since the last report (see ~status); max strain 0.5 of 'taut' above 0.4");
  EXPECT_EQ(*findValue(stat, "stability events since last report"), "3");
  EXPECT_EQ(*findValue(stat, "max strain"), "0.5");
}

TEST(StatusConversions, StatusLineShowsTimeRateParticlesStepAndTheImplicitSolves)
{
  core::World world = makeWorld();
  for (int k = 0; k < 10; ++k)
    world.step();
  // The rope is solved directly (linear_solver auto).
  const std::string line = statusLine(world, 0.987, 42.26, true);
  EXPECT_EQ(line.rfind("sim time 0.010 s | real-time factor 0.99 | live particles 15 | step 42.3 us | direct solve, "
                       "residual ",
                       0),
            0u)
      << line;
  EXPECT_EQ(line.substr(line.size() - 9), " | paused");
  EXPECT_NE(line.find(" m/s | paused"), std::string::npos) << line;  // the velocity error

  // By the conjugate gradient: its iterations.
  core::World cg_world = makeWorld(core::kImplicitEulerIntegrator, core::LinearSolverType::ConjugateGradient);
  cg_world.step();
  const std::string cg_line = statusLine(cg_world, 1.0, 1.0, false);
  EXPECT_EQ(cg_line.rfind("sim time 0.001 s | real-time factor 1.00 | live particles 15 | step 1.0 us | CG ", 0), 0u)
      << cg_line;
  EXPECT_NE(cg_line.find(" iterations, residual "), std::string::npos) << cg_line;
  EXPECT_EQ(cg_line.substr(cg_line.size() - 4), " m/s") << cg_line;  // the velocity error

  // Without an implicit body, no solver figures.
  core::World explicit_world = makeWorld(core::kVerletIntegrator);
  explicit_world.step();
  EXPECT_EQ(statusLine(explicit_world, 1.0, 1.0, false),
            "sim time 0.001 s | real-time factor 1.00 | live particles 15 | step 1.0 us");
}

TEST(StatusConversions, StepReportCountsStepsAndEvents)
{
  core::World world = makeWorld();
  world.step();
  EXPECT_EQ(stabilityEventCount(world), 0);
  EXPECT_EQ(stepReport(world, 1, 0), "advanced 1 steps");
}

TEST(StatusConversions, SpringConstantsReportSaysWhatTheChangeMeansForStability)
{
  // Verlet at dt = 1 ms on a soft rope: one substep.
  core::World world = makeWorld(core::kVerletIntegrator);
  core::SpringNetworkBody& rope = *world.findSpringBody("taut");
  ASSERT_TRUE(rope.setSpringConstants(core::SpringClass::Stretch, 100.0, 0.1).ok);
  std::string report = springConstantsReport(rope, "taut", "stretch", 100.0, 0.1, world);
  EXPECT_EQ(report.rfind("set stretch springs of 'taut' to 100 N/m, 0.1 N·s/m; omega_max <= ", 0), 0u) << report;
  EXPECT_NE(report.find(" 1/s, so verlet takes 1 substep(s) per step of 0.001 s"), std::string::npos) << report;

  // So stiff that even max_substeps (64) cannot keep h ω below the limit: it says it will freeze.
  ASSERT_TRUE(rope.setSpringConstants(core::SpringClass::Stretch, 1e9, 0.1).ok);
  report = springConstantsReport(rope, "taut", "stretch", 1e9, 0.1, world);
  EXPECT_NE(report.find("verlet takes 64 substep(s)"), std::string::npos) << report;
  EXPECT_NE(report.find("above max_substeps: expect it to freeze)"), std::string::npos) << report;

  // Implicit Euler has no stability limit: nothing about substeps.
  core::World implicit_world = makeWorld(core::kImplicitEulerIntegrator);
  const core::SpringNetworkBody& implicit_rope = *implicit_world.findSpringBody("taut");
  report = springConstantsReport(implicit_rope, "taut", "all", 500.0, 0.5, implicit_world);
  EXPECT_EQ(report.find("substep"), std::string::npos) << report;
  EXPECT_EQ(report.find("auto"), std::string::npos) << report;
}
