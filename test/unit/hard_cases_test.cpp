// The hard cases of config/scenes/hard, each run from its shipped scene: implicit Euler stays
// finite, never gains energy and converges as dt shrinks; explicit methods see instability coming
// (substeps), roll back blow-ups and only then freeze, reporting each event; the rest of the
// world goes on; fast particles never tunnel through spheres.

#include <gtest/gtest.h>

#include <cmath>

#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/rk4.h"
#include "particle_sim/core/integrators/symplectic_euler.h"
#include "particle_sim/core/integrators/verlet.h"
#include "particle_sim/scene/scene.h"

using namespace particle_sim;
using core::IntegratorType;
using core::SpringNetworkBody;

namespace
{
scene::SceneDef loadHard(const std::string& name)
{
  scene::SceneDef def;
  const core::Status status =
      scene::loadSceneFile(std::string(PARTICLE_SIM_SOURCE_DIR) + "/config/scenes/hard/" + name + ".yaml", def);
  EXPECT_TRUE(status.ok) << status.message;
  return def;
}

// Sets every spring body's integrator type (and optionally dt) before building.
std::unique_ptr<core::World> build(scene::SceneDef def, IntegratorType type, double dt = 0.0)
{
  if (dt > 0.0) def.world.dt = dt;
  for (auto& body : def.bodies)
  {
    std::visit(
        [&](auto& d) {
          if constexpr (!std::is_same_v<std::decay_t<decltype(d)>, core::EmitterDef>) d.integrator.type = type;
        },
        body);
  }
  std::unique_ptr<core::World> world;
  const core::Status status = scene::buildWorld(def, world);
  EXPECT_TRUE(status.ok) << status.message;
  return world;
}

bool finite(const SpringNetworkBody& body)
{
  const auto& p = body.particles();
  return p.position.leftCols(p.size()).allFinite() && p.velocity.leftCols(p.size()).allFinite();
}

// Steps `world` for `seconds`; with `check_energy`, expects the body's energy never to grow.
void run(core::World& world, const std::string& body_name, double seconds, bool check_energy)
{
  SpringNetworkBody& body = *world.findSpringBody(body_name);
  const Eigen::Vector3d g = world.environment().gravity;
  double energy = body.kineticEnergy() + body.potentialEnergy(g);
  const int steps = static_cast<int>(std::lround(seconds / world.dt()));
  for (int k = 0; k < steps; ++k)
  {
    world.step();
    ASSERT_TRUE(finite(body)) << body_name << " step " << k;
    const double now = body.kineticEnergy() + body.potentialEnergy(g);
    if (check_energy)
    {
      ASSERT_LE(now, energy + 1e-9 * (1.0 + std::abs(energy))) << body_name << " step " << k;
    }
    energy = now;
  }
}
}  // namespace

TEST(HardCases, VeryStiffSpringsUnderImplicitEulerStayFiniteLoseEnergyAndConverge)
{
  const scene::SceneDef def = loadHard("stiff_springs");
  auto world = build(def, core::kImplicitEulerIntegrator);
  run(*world, "rope", 2.0, true);
  EXPECT_FALSE(world->findSpringBody("rope")->frozen());

  // The rope's free end after 0.5 s approaches the fine-step answer as dt shrinks.
  auto freeEnd = [&](double dt) {
    auto w = build(def, core::kImplicitEulerIntegrator, dt);
    const int steps = static_cast<int>(std::lround(0.5 / dt));
    for (int k = 0; k < steps; ++k)
      w->step();
    return Eigen::Vector3d(w->findSpringBody("rope")->particles().position.col(9));
  };
  const Eigen::Vector3d reference = freeEnd(1.0 / 7680.0);
  const double e60 = (freeEnd(1.0 / 60.0) - reference).norm();
  const double e240 = (freeEnd(1.0 / 240.0) - reference).norm();
  const double e960 = (freeEnd(1.0 / 960.0) - reference).norm();
  EXPECT_LT(e240, e60);
  EXPECT_LT(e960, e240);
}

TEST(HardCases, VeryStiffSpringsUnderExplicitMethodsAreSubsteppedOrFrozenButNeverNaN)
{
  const scene::SceneDef def = loadHard("stiff_springs");
  for (IntegratorType type : {core::kSymplecticEulerIntegrator, core::kVerletIntegrator, core::kRk4Integrator})
  {
    auto world = build(def, type);
    run(*world, "rope", 0.5, false);
    const SpringNetworkBody& body = *world->findSpringBody("rope");
    EXPECT_FALSE(body.frozen()) << core::toString(type) << ": " << body.frozenReason();
    EXPECT_GT(body.lastSubsteps(), 1) << core::toString(type);
    EXPECT_GE(body.stabilityEvents(), 1) << core::toString(type);
    // Substepped, it swings like the implicit rope does: it stays near its length from the pin.
    EXPECT_LT((body.particles().position.col(9) - body.particles().position.col(0)).norm(), 1.1);
  }

  // Allowed too few substeps, a blow-up is caught, rolled back, retried up to the cap, then the
  // body is frozen at a finite state while another body in the same world goes on.
  scene::SceneDef capped = def;
  auto& rope = std::get<core::RopeDef>(capped.bodies[0]);
  rope.integrator.max_substeps = 4;
  core::RopeDef other = rope;
  other.name = "other";
  other.stretch_stiffness = 100.0;
  other.integrator.type = core::kImplicitEulerIntegrator;
  capped.bodies.push_back(other);
  auto world = build(capped, core::kSymplecticEulerIntegrator);
  ASSERT_TRUE(world->findSpringBody("other")->setIntegrator(other.integrator).ok);
  for (int k = 0; k < 60; ++k)
    world->step();
  const SpringNetworkBody& frozen = *world->findSpringBody("rope");
  EXPECT_TRUE(frozen.frozen());
  EXPECT_NE(frozen.frozenReason().find("even with 4 substeps"), std::string::npos) << frozen.frozenReason();
  EXPECT_TRUE(finite(frozen));
  const SpringNetworkBody& going = *world->findSpringBody("other");
  EXPECT_FALSE(going.frozen());
  // it fell and swung: its free end (the last of its particles) is well below where it started
  EXPECT_LT(going.particles().position(2, other.particles - 1), 1.5);
}

TEST(HardCases, ThousandToOneMassRatioStaysFiniteAndLosesNoEnergy)
{
  auto world = build(loadHard("mass_ratio"), core::kImplicitEulerIntegrator);
  run(*world, "weight", 3.0, true);
  // The heavy end hangs below the pin (it swung down).
  EXPECT_LT(world->findSpringBody("weight")->particles().position(2, 5), 2.5);
  auto explicit_world = build(loadHard("mass_ratio"), core::kVerletIntegrator);
  run(*explicit_world, "weight", 1.0, false);
  EXPECT_FALSE(explicit_world->findSpringBody("weight")->frozen());
}

TEST(HardCases, ThousandSegmentRopeStaysFiniteAndLosesNoEnergy)
{
  auto world = build(loadHard("long_rope"), core::kImplicitEulerIntegrator);
  run(*world, "rope", 0.25, true);
  const SpringNetworkBody& rope = *world->findSpringBody("rope");
  EXPECT_EQ(rope.particles().size(), 1001);
  EXPECT_TRUE(rope.lastSolve().converged);
}

TEST(HardCases, ClothStruckByAFastSphereNeverEndsInsideIt)
{
  const scene::SceneDef def = loadHard("cloth_struck");
  auto world = build(def, core::kImplicitEulerIntegrator);
  const SpringNetworkBody& cloth = *world->findSpringBody("cloth");
  bool struck = false;
  for (int k = 0; k < 600; ++k)
  {
    ASSERT_TRUE(scene::applyScriptedFrames(def, world->simTime() + world->dt(), *world).ok);
    world->step();
    ASSERT_TRUE(finite(cloth));
    const auto& sphere = world->environment().spheres[0];
    for (int i = 0; i < cloth.particles().size(); ++i)
    {
      const double distance = (cloth.particles().position.col(i) - sphere.center).norm();
      ASSERT_GE(distance, sphere.radius * (1.0 - 1e-9)) << "particle " << i << " step " << k;
      struck = struck || distance < 1.05 * sphere.radius;
    }
  }
  EXPECT_TRUE(struck) << "the sphere never reached the cloth";
}

TEST(HardCases, ThousandMetrePerSecondExplosionNeverTunnelsThroughTheSphere)
{
  auto world = build(loadHard("fast_explosion"), core::kImplicitEulerIntegrator);
  const core::Body& blast = *world->findBody("blast");
  const auto& sphere = world->environment().spheres[0];
  const Eigen::Vector3d origin(0, 0, 2);
  // Which particles head for the sphere: their ray from the origin hits it.
  std::vector<bool> aimed(blast.particles().size());
  int aimed_count = 0;
  for (int i = 0; i < blast.particles().size(); ++i)
  {
    const Eigen::Vector3d d = blast.particles().velocity.col(i).normalized();
    const Eigen::Vector3d to_centre = sphere.center - origin;
    const double along = to_centre.dot(d);
    aimed[i] = along > 0.0 && (to_centre - along * d).norm() < sphere.radius;
    aimed_count += aimed[i];
  }
  ASSERT_GT(aimed_count, 10);
  world->step();  // 1 m of flight: without the path test, these would be past the sphere
  for (int i = 0; i < blast.particles().size(); ++i)
  {
    const Eigen::Vector3d x = blast.particles().position.col(i);
    EXPECT_GE((x - sphere.center).norm(), sphere.radius * (1.0 - 1e-9));
    if (aimed[i])
    {
      EXPECT_LT(x.x(), sphere.center.x()) << "particle " << i << " went through the sphere";
    }
  }
}

TEST(HardCases, StiffnessJumpOfTenThousandIsTakenByAutoAndImplicitEuler)
{
  const scene::SceneDef def = loadHard("stiffness_jump");
  auto world = build(def, core::kAutoIntegrator);
  SpringNetworkBody& rope = *world->findSpringBody("rope");
  run(*world, "rope", 0.5, false);
  EXPECT_EQ(rope.lastIntegrator(), core::kVerletIntegrator) << rope.autoChoice();
  ASSERT_TRUE(rope.setSpringConstants(std::nullopt, 100.0 * 1e4, 0.0).ok);
  run(*world, "rope", 0.5, true);  // implicit Euler after the jump: no energy gained
  EXPECT_EQ(rope.lastIntegrator(), core::kImplicitEulerIntegrator) << rope.autoChoice();
  EXPECT_NE(rope.autoChoice().find("implicit_euler"), std::string::npos) << rope.autoChoice();

  // Explicit Verlet through the same jump: more substeps after it, never NaN.
  auto explicit_world = build(def, core::kVerletIntegrator);
  SpringNetworkBody& verlet = *explicit_world->findSpringBody("rope");
  run(*explicit_world, "rope", 0.5, false);
  const int before = verlet.lastSubsteps();
  ASSERT_TRUE(verlet.setSpringConstants(std::nullopt, 100.0 * 1e4, 0.0).ok);
  run(*explicit_world, "rope", 0.5, false);
  EXPECT_GT(verlet.lastSubsteps(), before);
  EXPECT_FALSE(verlet.frozen()) << verlet.frozenReason();
}

TEST(HardCases, PinTargetJumpingOneMetreInOneStepStaysFinite)
{
  for (IntegratorType type : {core::kImplicitEulerIntegrator, core::kSymplecticEulerIntegrator, core::kRk4Integrator})
  {
    auto world = build(loadHard("pin_jump"), type);
    SpringNetworkBody& rope = *world->findSpringBody("rope");
    run(*world, "rope", 0.5, false);
    ASSERT_TRUE(rope.setPinTarget(0, rope.pinTarget(0) + Eigen::Vector3d(0, 1.0, 0)).ok);
    run(*world, "rope", 1.0, false);
    EXPECT_FALSE(rope.frozen()) << core::toString(type) << ": " << rope.frozenReason();
    EXPECT_EQ(rope.particles().position.col(0), Eigen::Vector3d(0, 1, 2)) << core::toString(type);
    EXPECT_LT((rope.particles().position.col(1) - rope.particles().position.col(0)).norm(), 0.5)
        << core::toString(type) << ": the rope followed its end";
  }
}

TEST(AutoIntegrator, PicksVerletWhileItsSubstepsCostLessThanAnImplicitStepAndSaysWhy)
{
  core::RopeDef def;
  def.name = "r";
  def.particles = 10;
  def.mass = 1.0;
  def.stretch_stiffness = 100.0;  // omega_max = sqrt(4 k / m) = 63 1/s
  def.stretch_damping = 0.0;
  def.pins = {0};
  def.integrator.type = core::kAutoIntegrator;
  SpringNetworkBody body(core::buildRope(def));
  EXPECT_NEAR(body.frequencyBound(), std::sqrt(4.0 * 100.0 / 0.1), 1e-9);
  // An implicit step of this short chain costs 11 substeps and the direct solve (the chain has no
  // fill: a few CG iterations' flops).
  core::Environment env;
  body.step(0.01, env);  // dt omega = 0.63: one substep
  EXPECT_EQ(body.lastIntegrator(), core::kVerletIntegrator);
  EXPECT_EQ(body.lastSubsteps(), 1);
  EXPECT_NE(body.autoChoice().find("verlet: 1 substep costs no more than an implicit Euler step"), std::string::npos)
      << body.autoChoice();
  body.step(0.1, env);  // 6.3: four substeps, still cheaper
  EXPECT_EQ(body.lastIntegrator(), core::kVerletIntegrator) << body.autoChoice();
  EXPECT_EQ(body.lastSubsteps(), 4);
  body.step(0.5, env);  // 31.6: 18 substeps, dearer than the implicit step
  EXPECT_EQ(body.lastIntegrator(), core::kImplicitEulerIntegrator);
  EXPECT_NE(body.autoChoice().find("implicit_euler: Verlet would need 18 substeps, more than an implicit Euler step"),
            std::string::npos)
      << body.autoChoice();
  ASSERT_TRUE(body.setSpringConstants(std::nullopt, 1.0, 0.0).ok);  // softer: re-decided
  body.step(0.5, env);
  EXPECT_EQ(body.lastIntegrator(), core::kVerletIntegrator) << body.autoChoice();
}
