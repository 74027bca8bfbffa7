// The integrator seam: a method defined here, in this file only, and registered through the entry
// the registry's own lines use (integratorEntry<Method>(), added for this test's lifetime by
// ScopedIntegratorRegistration), is a full integrator: parsed and named, listed, declaring its
// stability limit and kind, and stepping a SpringNetworkBody and a World. No other file knows it.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "particle_sim/core/integrators/registry.h"
#include "particle_sim/core/integrators/symplectic_euler.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/world.h"

using namespace particle_sim::core;

namespace
{
// Symplectic Euler the other way round, drift then kick: x += h v, then v += h f(x, v) / m. First
// order, explicit, stable for h ω <= 2 on an undamped oscillator (a throwaway method: the built-in
// symplectic Euler kicks first, so the two give different numbers from the first step on).
class DriftKickMethod : public IntegrationMethod
{
public:
  static constexpr const char* kName = "drift_kick";
  static constexpr bool kImplicit = false;
  static constexpr int kOrder = 1;
  static constexpr double kStabilityLimit = 2.0;

  explicit DriftKickMethod(int particles) : acceleration_(Eigen::Matrix3Xd::Zero(3, particles)) {}
  SolverReport step(double h, DynamicSystem& system, const IntegratorDef& /*settings*/) override
  {
    Eigen::Matrix3Xd& x = system.positions();
    Eigen::Matrix3Xd& v = system.velocities();
    x += h * v;
    system.accelerations(x, v, acceleration_);
    v += h * acceleration_;
    return SolverReport{};
  }

private:
  Eigen::Matrix3Xd acceleration_;
};

constexpr IntegratorType kDriftKickIntegrator = IntegratorType::of<DriftKickMethod>();

// One undamped spring (k = 4π² N/m, m = 1 kg, so ω = 2π rad/s, period 1 s), particle 0 pinned at
// the origin, particle 1 released at rest 0.1 m beyond its rest length 1 m; no gravity, no ground.
constexpr double kStiffness = 4.0 * M_PI * M_PI, kRest = 1.0, kAmplitude = 0.1;

SpringNetworkDef oscillator(IntegratorType type)
{
  SpringNetworkDef def;
  def.name = "oscillator";
  def.positions = {Eigen::Vector3d::Zero(), Eigen::Vector3d(kRest + kAmplitude, 0, 0)};
  def.masses = {1.0, 1.0};
  def.springs = {Spring{0, 1, kRest, kStiffness, 0.0, SpringClass::Stretch}};
  def.pins = {0};
  def.integrator.type = type;
  return def;
}

Environment noGravityNoGround()
{
  Environment env;
  env.gravity.setZero();
  env.ground.enabled = false;
  return env;
}
}  // namespace

TEST(IntegratorSeam, AMethodRegisteredByItsEntryIsNamedListedAndDeclared)
{
  IntegratorType unknown = kAutoIntegrator;
  ASSERT_FALSE(parseIntegratorType("drift_kick", unknown));
  const std::string built_in_names = integratorTypeNames();
  {
    const ScopedIntegratorRegistration registration(integratorEntry<DriftKickMethod>());
    ASSERT_TRUE(registration.status().ok) << registration.status().message;

    // Its identity is its own: neither `auto` nor any built-in method.
    EXPECT_NE(kDriftKickIntegrator, kAutoIntegrator);
    for (const IntegratorInfo& info : integratorRegistry())
      EXPECT_EQ(info.type == kDriftKickIntegrator, std::string(info.name) == "drift_kick") << info.name;

    IntegratorType parsed = kAutoIntegrator;
    ASSERT_TRUE(parseIntegratorType("drift_kick", parsed));
    EXPECT_EQ(parsed, kDriftKickIntegrator);
    EXPECT_STREQ(toString(kDriftKickIntegrator), "drift_kick");
    // Listed after the built-in methods, before `auto`.
    const std::string without_auto = built_in_names.substr(0, built_in_names.size() - std::string("auto").size());
    EXPECT_EQ(integratorTypeNames(), without_auto + "drift_kick, auto");
    EXPECT_EQ(stabilityLimit(kDriftKickIntegrator), 2.0);
    EXPECT_FALSE(isImplicit(kDriftKickIntegrator));
    ASSERT_NE(findIntegrator(kDriftKickIntegrator), nullptr);
    EXPECT_EQ(findIntegrator(kDriftKickIntegrator)->order, 1);

    // A second registration of the same method, or of a name taken by a built-in method or `auto`,
    // is refused and changes nothing.
    const ScopedIntegratorRegistration twice(integratorEntry<DriftKickMethod>());
    EXPECT_FALSE(twice.status().ok);
    EXPECT_EQ(twice.status().message, "integrator 'drift_kick' is already registered");
    IntegratorInfo named_auto = integratorEntry<DriftKickMethod>();
    named_auto.type = kAutoIntegrator;
    named_auto.name = "auto";
    EXPECT_FALSE(ScopedIntegratorRegistration(named_auto).status().ok);
    EXPECT_EQ(integratorTypeNames(), without_auto + "drift_kick, auto");
  }
  // Gone with its registration.
  IntegratorType parsed = kAutoIntegrator;
  EXPECT_FALSE(parseIntegratorType("drift_kick", parsed));
  EXPECT_EQ(findIntegrator(kDriftKickIntegrator), nullptr);
  EXPECT_EQ(integratorTypeNames(), built_in_names);
  // A definition naming it is refused again.
  IntegratorDef gone;
  gone.type = kDriftKickIntegrator;
  EXPECT_EQ(validate(gone).message, "integrator = 'drift_kick' is not registered; allowed: " + built_in_names);
}

TEST(IntegratorSeam, ABodyBuiltBeforeARegistrationRefusesTheNewMethod)
{
  SpringNetworkBody before(oscillator(kSymplecticEulerIntegrator));
  const ScopedIntegratorRegistration registration(integratorEntry<DriftKickMethod>());
  ASSERT_TRUE(registration.status().ok) << registration.status().message;
  IntegratorDef settings = before.integrator();
  settings.type = kDriftKickIntegrator;
  const Status refused = before.setIntegrator(settings);
  EXPECT_FALSE(refused.ok);
  EXPECT_EQ(refused.message, "integrator = 'drift_kick' was registered after body 'oscillator' was built");
  EXPECT_EQ(before.integrator().type, kSymplecticEulerIntegrator);  // unchanged
  SpringNetworkBody after(oscillator(kSymplecticEulerIntegrator));
  EXPECT_TRUE(after.setIntegrator(settings).ok);
  EXPECT_EQ(after.integrator().type, kDriftKickIntegrator);
}

TEST(IntegratorSeam, ARegisteredMethodStepsASpringBody)
{
  const ScopedIntegratorRegistration registration(integratorEntry<DriftKickMethod>());
  ASSERT_TRUE(registration.status().ok) << registration.status().message;
  const SpringNetworkDef def = oscillator(kDriftKickIntegrator);
  ASSERT_TRUE(validate(def, 10).ok);
  SpringNetworkBody body(def);
  const Environment env = noGravityNoGround();

  // One step of h = 0.01 s (h ω ≈ 0.063, one substep): drift first, so x does not move, then the
  // kick of the spring's force at the start, −k · 0.1 m. Symplectic Euler would move x already.
  const double h = 0.01;
  EXPECT_EQ(body.planStep(h, env).method, kDriftKickIntegrator);
  EXPECT_EQ(body.planStep(h, env).substeps, 1);
  body.step(h, env);
  EXPECT_EQ(body.lastIntegrator(), kDriftKickIntegrator);
  EXPECT_EQ(body.particles().position(0, 1), kRest + kAmplitude);
  EXPECT_NEAR(body.particles().velocity(0, 1), -h * kStiffness * kAmplitude, 1e-15);

  // Over one period it follows x(t) = rest + 0.1 cos(ω t) to first order: the max error halves
  // with the step.
  auto maxError = [&](double dt) {
    SpringNetworkBody run(def);
    double error = 0.0;
    const int steps = static_cast<int>(std::lround(1.0 / dt));
    for (int n = 1; n <= steps; ++n)
    {
      run.step(dt, env);
      const double exact = kRest + kAmplitude * std::cos(2.0 * M_PI * n * dt);
      error = std::max(error, std::abs(run.particles().position(0, 1) - exact));
    }
    return error;
  };
  const double coarse = maxError(1.0 / 200.0), fine = maxError(1.0 / 400.0);
  EXPECT_LT(coarse, 0.02);
  EXPECT_NEAR(std::log2(coarse / fine), 1.0, 0.1);

  // Its stability limit reaches the guard: a step too long for h ω <= 2 is split into as many
  // substeps as symplectic Euler (whose limit is also 2) gets, where an unknown limit would give 1.
  const SpringNetworkBody symplectic(oscillator(kSymplecticEulerIntegrator));
  EXPECT_GT(body.planStep(0.5, env).substeps, 1);
  EXPECT_EQ(body.planStep(0.5, env).substeps, symplectic.planStep(0.5, env).substeps);
}

TEST(IntegratorSeam, AWorldStepsABodyWithARegisteredMethodAsItsOwnOrAsTheWorldsDefault)
{
  const ScopedIntegratorRegistration registration(integratorEntry<DriftKickMethod>());
  ASSERT_TRUE(registration.status().ok) << registration.status().message;
  WorldDef world_def;
  world_def.dt = 0.01;
  world_def.gravity.setZero();
  world_def.ground.enabled = false;
  world_def.integrator.type = kDriftKickIntegrator;  // the world's default
  ASSERT_TRUE(validate(world_def).ok);
  World world(world_def);
  ASSERT_TRUE(world.addSpringNetwork(oscillator(kDriftKickIntegrator)).ok);
  RopeDef rope;  // sets no method: the world's
  rope.name = "rope";
  ASSERT_TRUE(world.addRope(rope).ok);
  world.step();
  for (const char* name : {"oscillator", "rope"})
  {
    const SpringNetworkBody* body = world.findSpringBody(name);
    ASSERT_NE(body, nullptr) << name;
    EXPECT_EQ(body->integrator().type, kDriftKickIntegrator) << name;
    EXPECT_EQ(body->lastIntegrator(), kDriftKickIntegrator) << name;
    EXPECT_STREQ(toString(body->lastIntegrator()), "drift_kick") << name;
    EXPECT_FALSE(body->frozen()) << name;
  }
  EXPECT_EQ(world.findSpringBody("oscillator")->particles().position(0, 1), kRest + kAmplitude);
  EXPECT_NEAR(world.findSpringBody("oscillator")->particles().velocity(0, 1), -0.01 * kStiffness * kAmplitude, 1e-15);
}
