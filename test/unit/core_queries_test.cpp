// What the front-ends show, asked of the core: the plan of the next step (substeps, auto's
// choice), the energies of every body kind and a body's cloth model. Each answer is checked
// against an independent truth: what the step then does, analytic energies, the builder's input.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/cloth_model.h"
#include "particle_sim/core/emitter.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/rk4.h"
#include "particle_sim/core/integrators/stability_guard.h"
#include "particle_sim/core/integrators/symplectic_euler.h"
#include "particle_sim/core/integrators/verlet.h"
#include "particle_sim/core/spring_network.h"

using namespace particle_sim::core;

namespace
{
Environment gravityOnly()
{
  Environment env;
  env.ground.enabled = false;
  return env;
}

// A 10-particle rope pinned at one end, with `stiffness` [N/m] and `type`.
SpringNetworkBody makeRope(double stiffness, IntegratorType type)
{
  RopeDef def;
  def.name = "rope";
  def.particles = 10;
  def.mass = 1.0;
  def.stretch_stiffness = stiffness;
  def.stretch_damping = 0.1;
  def.pins = {0};
  def.integrator.type = type;
  EXPECT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
  return SpringNetworkBody(buildRope(def));
}
}  // namespace

TEST(CoreQueries, SubstepPlanBeforeAStepIsWhatTheStepDoes)
{
  Environment env = gravityOnly();
  env.damping = 0.5;  // global damping counts in c_max: the plan must take it from env, as the step does
  const double dt = 1.0 / 60.0;
  for (const IntegratorType type : {kSymplecticEulerIntegrator, kVerletIntegrator, kRk4Integrator})
  {
    for (const double stiffness : {50.0, 5e3, 5e5})
    {
      SpringNetworkBody body = makeRope(stiffness, type);
      for (int n = 0; n < 20; ++n)
      {
        const SubstepPlan plan = body.planStep(dt, env);
        body.step(dt, env);
        ASSERT_FALSE(body.frozen()) << body.frozenReason();
        EXPECT_EQ(plan.method, type);
        EXPECT_EQ(plan.method, body.lastIntegrator());
        EXPECT_EQ(plan.substeps, body.lastSubsteps()) << toString(type) << ", k = " << stiffness << ", step " << n;
        EXPECT_EQ(plan.needed_substeps, plan.substeps);  // within max_substeps here
      }
    }
  }
  // The stiffest rope really needs substeps: the comparison above is not between ones.
  SpringNetworkBody stiff = makeRope(5e5, kVerletIntegrator);
  EXPECT_GT(stiff.planStep(dt, env).substeps, 1);

  // An implicit method takes the whole step at once.
  SpringNetworkBody implicit_body = makeRope(5e5, kImplicitEulerIntegrator);
  EXPECT_EQ(implicit_body.planStep(dt, env).substeps, 1);
  implicit_body.step(dt, env);
  EXPECT_EQ(implicit_body.lastSubsteps(), 1);
}

TEST(CoreQueries, SubstepPlanCapsAtMaxSubstepsAndSaysWhatWasNeeded)
{
  // Verlet's limit is 2, with the 10 % margin 1.8: h (ω + c) = 1e-3 s · 1e13 1/s = 1e10 needs
  // ceil(1e10 / 1.8) = 5555555556 substeps, more than an int holds; the cap is 64.
  SubstepPlan plan = StabilityGuard::planSubsteps(kVerletIntegrator, 1e-3, 1e13, 0.0, 64);
  EXPECT_EQ(plan.substeps, 64);
  EXPECT_EQ(plan.needed_substeps, 5555555556LL);

  // Exactly at 90 % of the limit one substep is enough; just above, two.
  const double margin = 0.9 * stabilityLimit(kVerletIntegrator);
  plan = StabilityGuard::planSubsteps(kVerletIntegrator, 1.0, margin, 0.0, 64);
  EXPECT_EQ(plan.substeps, 1);
  plan = StabilityGuard::planSubsteps(kVerletIntegrator, 1.0, std::nextafter(margin, 2.0), 0.0, 64);
  EXPECT_EQ(plan.substeps, 2);
  EXPECT_EQ(plan.needed_substeps, 2);

  // A bound beyond every count saturates instead of overflowing.
  plan =
      StabilityGuard::planSubsteps(kSymplecticEulerIntegrator, 1.0, std::numeric_limits<double>::infinity(), 0.0, 64);
  EXPECT_EQ(plan.substeps, 64);
  EXPECT_EQ(plan.needed_substeps, std::numeric_limits<long long>::max());

  // A body so stiff that max_substeps cannot hold it: the plan says so before its step, and the
  // step runs the capped count (then freezes, as it blows up).
  SpringNetworkBody body = makeRope(1e9, kVerletIntegrator);
  const Environment env = gravityOnly();
  plan = body.planStep(0.1, env);
  EXPECT_EQ(plan.substeps, body.integrator().max_substeps);
  EXPECT_GT(plan.needed_substeps, plan.substeps);
  body.step(0.1, env);
  EXPECT_EQ(body.lastSubsteps(), plan.substeps);
}

TEST(CoreQueries, AutoChoiceBeforeAStepIsTheMethodTheStepRuns)
{
  // The rule: Verlet while the substeps it needs (h (ω_max + c_max) within 90 % of its limit 2 in
  // each) fit in max_substeps and cost no more than the implicit step's estimate, else implicit Euler.
  EXPECT_EQ(StabilityGuard::chooseAuto(1.0, 1.35, 0.45, 1.0, 64), kVerletIntegrator);  // 1.8: one substep
  EXPECT_EQ(StabilityGuard::chooseAuto(1.0, 1.8, 0.0, std::nextafter(1.0, 0.0), 64), kImplicitEulerIntegrator);
  EXPECT_EQ(StabilityGuard::chooseAuto(1.0, 9.0, 0.0, 5.0, 64), kVerletIntegrator);  // 5 substeps
  EXPECT_EQ(StabilityGuard::chooseAuto(1.0, std::nextafter(9.0, 10.0), 0.0, 5.0, 64), kImplicitEulerIntegrator);
  EXPECT_EQ(StabilityGuard::chooseAuto(1.0, 9.0, 0.0, 1e9, 4), kImplicitEulerIntegrator);  // 5 > max_substeps

  const Environment env = gravityOnly();
  const double dt = 1.0 / 60.0;
  for (const double stiffness : {20.0, 5e5})
  {
    SpringNetworkBody body = makeRope(stiffness, kAutoIntegrator);
    const SubstepPlan plan = body.planStep(dt, env);
    EXPECT_EQ(plan.method, stiffness < 1e3 ? kVerletIntegrator : kImplicitEulerIntegrator);
    body.step(dt, env);
    EXPECT_EQ(body.lastIntegrator(), plan.method);
    EXPECT_EQ(body.lastSubsteps(), plan.substeps);
    EXPECT_EQ(body.autoChoice().rfind(std::string(toString(plan.method)) + ":", 0), 0u) << body.autoChoice();

    // After new constants the plan follows them, and so does the next step.
    ASSERT_TRUE(body.setSpringConstants(std::nullopt, stiffness < 1e3 ? 5e5 : 20.0, 0.1).ok);
    const SubstepPlan replanned = body.planStep(dt, env);
    EXPECT_NE(replanned.method, plan.method);
    body.step(dt, env);
    EXPECT_EQ(body.lastIntegrator(), replanned.method);
  }
}

TEST(CoreQueries, EmitterEnergiesAreThoseOfFreeParticles)
{
  // Two fountain particles with no spread leave (0, 0, 100) straight up at 10 m/s: after t they
  // move at 10 − g t and stand at 100 + 10 t − g t² / 2.
  EmitterDef def;
  def.name = "up";
  def.origin = Eigen::Vector3d(0.0, 0.0, 100.0);
  def.rate = 0.0;
  def.burst_count = 2;
  def.speed = 10.0;
  def.spread = 0.0;
  def.lifetime = 10.0;
  def.particle_mass = 0.25;
  ASSERT_TRUE(validate(def).ok) << validate(def).message;
  EmitterBody emitter(def);
  const Environment env = gravityOnly();
  const double g = 9.81, m = 0.25, dt = 0.01;
  for (int n = 0; n < 50; ++n)
    emitter.step(dt, env);
  ASSERT_EQ(emitter.particles().size(), 2);
  const double t = emitter.particles().age[0];
  EXPECT_NEAR(t, 50 * dt, 1e-12);
  const double v = 10.0 - g * t, z = 100.0 + 10.0 * t - 0.5 * g * t * t;
  const Body& body = emitter;  // asked through the body interface, as a front-end does
  EXPECT_NEAR(body.kineticEnergy(), 2 * 0.5 * m * v * v, 1e-9);
  EXPECT_NEAR(body.potentialEnergy(env.gravity), 2 * m * g * z, 1e-9);
  // Ballistic motion conserves their mechanical energy: that of the start.
  EXPECT_NEAR(body.kineticEnergy() + body.potentialEnergy(env.gravity), 2 * (0.5 * m * 100.0 + m * g * 100.0), 1e-9);
}

TEST(CoreQueries, SpringBodyEnergiesThroughTheBodyInterface)
{
  // One free particle of 2 kg at height 3 m moving at (1, 2, 2) m/s, no springs: ½ m |v|² = 9 J,
  // m g z = 58.86 J.
  SpringNetworkDef def;
  def.name = "dot";
  def.positions = {Eigen::Vector3d(0.5, -1.0, 3.0)};
  def.velocities = {Eigen::Vector3d(1.0, 2.0, 2.0)};
  def.masses = {2.0};
  ASSERT_TRUE(validate(def, 10).ok) << validate(def, 10).message;
  SpringNetworkBody dot(def);
  const Body& body = dot;
  const Environment env = gravityOnly();
  EXPECT_NEAR(body.kineticEnergy(), 9.0, 1e-12);
  EXPECT_NEAR(body.potentialEnergy(env.gravity), 2.0 * 9.81 * 3.0, 1e-12);
}

TEST(CoreQueries, ClothModelIsTheOneTheBuilderWasAskedFor)
{
  for (const ClothModel model : {ClothModel::Springs, ClothModel::BaraffWitkin})
  {
    ClothGridDef def(model);
    def.name = "sheet";
    def.nu = 4;
    def.nv = 4;
    ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
    const SpringNetworkBody cloth(buildClothGrid(def));
    EXPECT_EQ(cloth.clothModel(), model) << toString(model);
  }
  // A rope is made of springs.
  EXPECT_EQ(makeRope(50.0, kVerletIntegrator).clothModel(), ClothModel::Springs);
}
