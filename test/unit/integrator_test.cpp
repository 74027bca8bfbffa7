// The spring-body integrators: each converges to the analytic harmonic oscillator at its stated
// order, symplectic Euler keeps the energy bounded, implicit Euler and BDF2 never gain energy and
// stay stable where explicit methods blow up, internal forces conserve momentum, pins hold or follow
// their targets exactly, and a new spring constant gives the predicted frequency.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/integrators/bdf2.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/rk4.h"
#include "particle_sim/core/integrators/symplectic_euler.h"
#include "particle_sim/core/integrators/verlet.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/worker_pool.h"
#include "test_helpers.h"

using namespace particle_sim::core;
using particle_sim_test::noGravity;

namespace
{
const IntegratorType kAllIntegrators[] = {kSymplecticEulerIntegrator, kVerletIntegrator, kImplicitEulerIntegrator,
                                          kRk4Integrator, kBdf2Integrator};

Environment gravityOnly()
{
  Environment env;
  env.ground.enabled = false;
  return env;
}

// One undamped spring of rest length L and stiffness k; particle 0 is pinned at the origin and
// particle 1 (mass m) starts at rest at (L + A, 0, 0), so x(t) = L + A cos(sqrt(k/m) t).
struct Oscillator
{
  double k = 4.0 * M_PI * M_PI;  // omega = 2 pi, period 1 s with m = 1
  double m = 1.0;
  double L = 1.0;
  double A = 0.1;
  double omega() const { return std::sqrt(k / m); }

  SpringNetworkDef def(IntegratorType type) const
  {
    SpringNetworkDef d;
    d.name = "oscillator";
    d.positions = {Eigen::Vector3d::Zero(), Eigen::Vector3d(L + A, 0, 0)};
    d.masses = {m, m};
    Spring spring;
    spring.i = 0;
    spring.j = 1;
    spring.rest_length = L;
    spring.stiffness = k;
    spring.damping = 0.0;
    d.springs = {spring};
    d.pins = {0};
    d.integrator.type = type;
    d.integrator.verlet_damping = 1.0;
    d.integrator.cg_tolerance = 1e-12;
    return d;
  }
};

// Max over the steps in [0, T] of the max-norm error of particle 1 against the exact solution.
double maxOscillatorError(const Oscillator& osc, IntegratorType type, double dt, double duration)
{
  const SpringNetworkDef def = osc.def(type);
  EXPECT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
  SpringNetworkBody body(def);
  const Environment env = noGravity();
  const int steps = static_cast<int>(std::lround(duration / dt));
  double error = 0.0;
  for (int n = 1; n <= steps; ++n)
  {
    body.step(dt, env);
    const Eigen::Vector3d exact(osc.L + osc.A * std::cos(osc.omega() * n * dt), 0, 0);
    error = std::max(error, (body.particles().position.col(1) - exact).lpNorm<Eigen::Infinity>());
  }
  return error;
}

RopeDef rope(int particles, IntegratorType type)
{
  RopeDef def;
  def.name = "rope";
  def.particles = particles;
  def.integrator.type = type;
  return def;
}

double totalEnergy(const SpringNetworkBody& body, const Environment& env)
{
  return body.kineticEnergy() + body.potentialEnergy(env.gravity);
}

bool allFinite(const SpringNetworkBody& body)
{
  const ParticlePool& p = body.particles();
  return p.position.leftCols(p.size()).allFinite() && p.velocity.leftCols(p.size()).allFinite();
}

// Times at which x - L crosses zero upwards, by linear interpolation between steps.
struct CrossingRecorder
{
  double previous = 0.0;
  bool has_previous = false;
  std::vector<double> times;

  void add(double t, double dt, double value)
  {
    if (has_previous && previous < 0.0 && value >= 0.0) times.push_back(t - dt + dt * (-previous) / (value - previous));
    previous = value;
    has_previous = true;
  }
  double meanPeriod() const { return (times.back() - times.front()) / static_cast<double>(times.size() - 1); }
};
}  // namespace

TEST(Integrator, NamesRoundTripAndValidateRefusesBadSettings)
{
  for (IntegratorType type : kAllIntegrators)
  {
    IntegratorType parsed = kRk4Integrator;
    ASSERT_TRUE(parseIntegratorType(toString(type), parsed));
    EXPECT_EQ(parsed, type);
    EXPECT_NE(std::string(integratorTypeNames()).find(toString(type)), std::string::npos);
  }
  IntegratorType parsed = kRk4Integrator;
  EXPECT_FALSE(parseIntegratorType("leapfrog", parsed));

  EXPECT_TRUE(validate(IntegratorDef{}).ok);
  IntegratorDef bad;
  bad.cg_tolerance = 0.0;
  Status s = validate(bad);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("cg_tolerance"), std::string::npos) << s.message;
  bad = IntegratorDef{};
  bad.cg_max_iterations = 0;
  s = validate(bad);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("cg_max_iterations"), std::string::npos) << s.message;
  bad = IntegratorDef{};
  bad.verlet_damping = 1.5;
  s = validate(bad);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("verlet_damping"), std::string::npos) << s.message;
}

TEST(Integrator, ConvergenceOrdersOnTheHarmonicOscillator)
{
  // Observed order log2(e(h) / e(h/2)) of the max position error over two periods.
  struct Case
  {
    IntegratorType type;
    double expected_order;
    double first_dt;
  };
  const Case cases[] = {
      {kSymplecticEulerIntegrator, 1.0, 1.0 / 100.0},
      {kImplicitEulerIntegrator, 1.0, 1.0 / 100.0},
      {kVerletIntegrator, 2.0, 1.0 / 50.0},
      {kRk4Integrator, 4.0, 1.0 / 40.0},
      {kBdf2Integrator, 2.0, 1.0 / 50.0},
  };
  const Oscillator osc;
  const double duration = 2.0;  // two periods
  for (const Case& c : cases)
  {
    std::vector<double> errors;
    for (int level = 0; level < 4; ++level)
      errors.push_back(maxOscillatorError(osc, c.type, c.first_dt / std::pow(2.0, level), duration));
    for (std::size_t level = 0; level + 1 < errors.size(); ++level)
    {
      // Errors stay well above round-off, so the ratio measures truncation.
      EXPECT_GT(errors[level + 1], 1e-11) << toString(c.type);
      const double order = std::log2(errors[level] / errors[level + 1]);
      EXPECT_NEAR(order, c.expected_order, 0.25) << toString(c.type) << " dt = " << c.first_dt / std::pow(2.0, level)
                                                 << " errors " << errors[level] << " -> " << errors[level + 1];
    }
  }
}

TEST(Integrator, SymplecticEulerKeepsTheEnergyBounded)
{
  // A swinging rope, one end pinned, no damping, released horizontally at z = 0 (so the initial
  // energy is 0); the energy error is measured against the largest kinetic energy reached.
  // Symplectic Euler's energy error is bounded and first order in dt (about 3.5% at dt = 1e-3
  // here, 0.6% at 2e-4), with no drift over ten swings.
  RopeDef def = rope(6, kSymplecticEulerIntegrator);
  def.start = {0, 0, 0};
  def.end = {1.5, 0, 0};
  def.stretch_damping = 0.0;
  def.pins = {0};
  ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
  SpringNetworkBody body(buildRope(def));
  const Environment env = gravityOnly();
  const double e0 = totalEnergy(body, env);
  const int steps = 100000;
  const double dt = 2e-4;
  double max_kinetic = 0.0, max_drift = 0.0, first_tenth = 0.0, last_tenth = 0.0;
  for (int n = 0; n < steps; ++n)
  {
    body.step(dt, env);
    const double drift = totalEnergy(body, env) - e0;
    max_kinetic = std::max(max_kinetic, body.kineticEnergy());
    max_drift = std::max(max_drift, std::abs(drift));
    if (n < steps / 10) first_tenth += drift / (steps / 10);
    if (n >= steps - steps / 10) last_tenth += drift / (steps / 10);
  }
  ASSERT_FALSE(body.frozen()) << body.frozenReason();
  ASSERT_GT(max_kinetic, 1.0);  // it did swing: m g (L / 2) is about 7 J
  EXPECT_LT(max_drift, 0.01 * max_kinetic);
  // No trend: the mean energy error of the last tenth is that of the first tenth.
  EXPECT_LT(std::abs(last_tenth - first_tenth), 0.002 * max_kinetic)
      << "first tenth " << first_tenth << " last tenth " << last_tenth;
}

TEST(Integrator, ImplicitMethodsNeverGainEnergy)
{
  // Undamped hanging rope released horizontally, at the usual stiffness, a stiff one, and a slack
  // one (rest length 1.5 times the span: every spring starts compressed, where the exact Jacobian
  // would make the system indefinite), with implicit Euler and with BDF2.
  struct Case
  {
    double stiffness, rest_length;
    IntegratorType type;
  };
  for (const Case& c : {Case{500.0, 0.0, kImplicitEulerIntegrator}, Case{1e5, 0.0, kImplicitEulerIntegrator},
                        Case{500.0, 3.0, kImplicitEulerIntegrator}, Case{500.0, 0.0, kBdf2Integrator},
                        Case{1e5, 0.0, kBdf2Integrator}, Case{500.0, 3.0, kBdf2Integrator}})
  {
    const double stiffness = c.stiffness;
    RopeDef def = rope(20, c.type);
    def.rest_length = c.rest_length;
    def.stretch_stiffness = stiffness;
    def.stretch_damping = 0.0;
    def.bend_stiffness = 0.1 * stiffness;
    def.bend_damping = 0.0;
    def.pins = {0};
    def.integrator.cg_tolerance = 1e-12;
    ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
    SpringNetworkBody body(buildRope(def));
    const Environment env = gravityOnly();
    // The energy that can change form: the rope's weight over its length.
    const double scale = def.mass * env.gravity.norm() * (def.end - def.start).norm();
    double before = totalEnergy(body, env);
    const double initial = before;
    for (int n = 0; n < 600; ++n)
    {
      body.step(1.0 / 60.0, env);
      const double after = totalEnergy(body, env);
      ASSERT_LE(after, before + 1e-9 * std::max(std::abs(before), scale))
          << toString(c.type) << " k = " << stiffness << " rest_length " << c.rest_length << " step " << n << " gained "
          << after - before << " J";
      before = after;
    }
    ASSERT_FALSE(body.frozen()) << body.frozenReason();
    // It did move: the rope fell and lost energy.
    EXPECT_LT(before, initial - 0.1 * scale)
        << toString(c.type) << " k = " << stiffness << " rest_length " << c.rest_length;
  }
}

TEST(Integrator, InternalForcesConserveMomentum)
{
  for (IntegratorType type : kAllIntegrators)
  {
    RopeDef def = rope(10, type);
    def.bend_stiffness = 50.0;
    def.bend_damping = 0.2;
    def.integrator.cg_tolerance = 1e-13;
    ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
    SpringNetworkDef network = buildRope(def);
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    network.velocities.clear();
    for (std::size_t i = 0; i < network.positions.size(); ++i)
      network.velocities.emplace_back(0.5 + unit(rng), -0.3 + unit(rng), 0.2 + unit(rng));
    ASSERT_TRUE(validate(network, 100).ok) << validate(network, 100).message;
    SpringNetworkBody body(network);
    const Environment env = noGravity();

    // The initial momentum is that of the given velocities.
    Eigen::Vector3d expected = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < network.velocities.size(); ++i)
      expected += network.masses[i] * network.velocities[i];
    const Eigen::Vector3d p0 = body.momentum();
    ASSERT_LE((p0 - expected).norm(), 1e-12 * expected.norm()) << toString(type);
    for (int n = 0; n < 300; ++n)
    {
      body.step(1.0 / 100.0, env);
      ASSERT_LE((body.momentum() - p0).norm(), 1e-9 * p0.norm()) << toString(type) << " step " << n;
    }
    ASSERT_FALSE(body.frozen()) << body.frozenReason();
  }
}

TEST(Integrator, PinnedParticlesNeverMove)
{
  for (IntegratorType type : kAllIntegrators)
  {
    RopeDef def = rope(12, type);
    def.pins = {0, -1};
    def.bend_stiffness = 20.0;
    ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
    SpringNetworkBody body(buildRope(def));
    const ParticlePool& p = body.particles();
    const int last = p.size() - 1;
    const Eigen::Vector3d first_start = p.position.col(0), last_start = p.position.col(last);
    const Environment env = gravityOnly();
    for (int n = 0; n < 500; ++n)
    {
      body.step(1.0 / 240.0, env);
      ASSERT_EQ(p.position.col(0), first_start) << toString(type) << " step " << n;
      ASSERT_EQ(p.position.col(last), last_start) << toString(type) << " step " << n;
    }
    EXPECT_EQ(p.inverse_mass[0], 0.0);
    EXPECT_EQ(p.inverse_mass[last], 0.0);
    EXPECT_TRUE(body.isPinned(0));
    EXPECT_TRUE(body.isPinned(last));
    EXPECT_EQ(body.pinnedCount(), 2);
    // The free middle sagged under gravity.
    EXPECT_LT(p.position(2, last / 2), first_start.z() - 0.05) << toString(type);
    EXPECT_FALSE(body.frozen()) << body.frozenReason();
  }
}

TEST(Integrator, MovingPinTargetIsReachedExactlyEveryStep)
{
  for (IntegratorType type : kAllIntegrators)
  {
    RopeDef def = rope(10, type);
    def.pins = {0};
    ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
    SpringNetworkBody body(buildRope(def));
    const ParticlePool& p = body.particles();
    const Eigen::Vector3d center = p.position.col(0) - Eigen::Vector3d(0.3, 0, 0);
    const Environment env = gravityOnly();
    const double dt = 1.0 / 120.0;
    for (int n = 1; n <= 240; ++n)
    {
      // A gripper carrying the end around a circle of radius 0.3 m at 1 turn per second.
      const double angle = 2.0 * M_PI * n * dt;
      const Eigen::Vector3d target = center + 0.3 * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0);
      ASSERT_TRUE(body.setPinTarget(0, target).ok);
      EXPECT_EQ(body.pinTarget(0), target);
      body.step(dt, env);
      ASSERT_EQ(p.position.col(0), target)
          << toString(type) << " step " << n << " off by " << (p.position.col(0) - target).norm();
    }
    EXPECT_TRUE(allFinite(body));
    EXPECT_FALSE(body.frozen()) << body.frozenReason();
  }
}

TEST(Integrator, UnpinnedParticleIsReleasedAndFalls)
{
  for (IntegratorType type : kAllIntegrators)
  {
    RopeDef def = rope(10, type);
    def.pins = {0, -1};
    ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
    SpringNetworkBody body(buildRope(def));
    const ParticlePool& p = body.particles();
    const int last = p.size() - 1;
    const Environment env = gravityOnly();
    for (int n = 0; n < 120; ++n)
      body.step(1.0 / 120.0, env);
    const Eigen::Vector3d held = p.position.col(last);
    EXPECT_EQ(held, buildRope(def).positions[last]);

    ASSERT_TRUE(body.unpin(last).ok);
    EXPECT_FALSE(body.isPinned(last));
    EXPECT_EQ(body.pinnedCount(), 1);
    EXPECT_NEAR(p.inverse_mass[last], def.particles / def.mass, 1e-12);
    for (int n = 0; n < 60; ++n)
      body.step(1.0 / 120.0, env);
    EXPECT_LT(p.position(2, last), held.z() - 0.1) << toString(type);
    EXPECT_GT((p.position.col(last) - held).norm(), 0.1) << toString(type);
    // The other pin still holds.
    EXPECT_EQ(p.position.col(0), buildRope(def).positions[0]);
    // Pinning an index that does not exist is refused.
    EXPECT_FALSE(body.pin(p.size(), Eigen::Vector3d::Zero()).ok);
    EXPECT_FALSE(body.pin(-1, Eigen::Vector3d::Zero()).ok);
  }
}

TEST(Integrator, NewSpringConstantGivesThePredictedFrequency)
{
  // Period 2 pi sqrt(m / k): 1 s, then 1/2 s at 4 k, then 1/3 s at 9 k.
  for (IntegratorType type : {kRk4Integrator, kImplicitEulerIntegrator})
  {
    const Oscillator osc;
    SpringNetworkBody body(osc.def(type));
    const Environment env = noGravity();
    const double dt = type == kRk4Integrator ? 1e-3 : 1e-4;
    double t = 0.0;
    auto measure = [&](double duration) {
      CrossingRecorder crossings;
      const int steps = static_cast<int>(std::lround(duration / dt));
      for (int n = 0; n < steps; ++n)
      {
        body.step(dt, env);
        t += dt;
        crossings.add(t, dt, body.particles().position(0, 1) - osc.L);
      }
      return crossings;
    };
    CrossingRecorder before = measure(3.3);
    ASSERT_GE(before.times.size(), 3u);
    EXPECT_NEAR(before.meanPeriod(), 1.0, 0.01) << toString(type);

    ASSERT_TRUE(body.setSpringConstants(SpringClass::Stretch, 4.0 * osc.k, 0.0).ok);
    EXPECT_EQ(body.springs()[0].stiffness, 4.0 * osc.k);
    CrossingRecorder faster = measure(2.3);
    ASSERT_GE(faster.times.size(), 4u);
    EXPECT_NEAR(faster.meanPeriod(), 0.5, 0.005) << toString(type);

    ASSERT_TRUE(body.setSpringConstants(std::nullopt, 9.0 * osc.k, 0.0).ok);
    CrossingRecorder fastest = measure(1.6);
    ASSERT_GE(fastest.times.size(), 4u);
    EXPECT_NEAR(fastest.meanPeriod(), 1.0 / 3.0, 0.01 / 3.0) << toString(type);
  }
}

TEST(Integrator, ImplicitSolveConvergesAndReportsIt)
{
  // The conjugate gradient's report (a rope would otherwise be solved directly: linear_solver auto).
  // Each solve ends within one of the two rules: the relative residual, or the velocity error.
  auto within = [](const SolverReport& report, const IntegratorDef& settings) {
    return report.relative_residual <= settings.cg_tolerance || report.velocity_error <= settings.cg_velocity_tolerance;
  };
  RopeDef def = rope(20, kImplicitEulerIntegrator);
  def.bend_stiffness = 50.0;
  def.pins = {0};
  def.integrator.linear_solver = LinearSolverType::ConjugateGradient;
  ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
  SpringNetworkBody body(buildRope(def));
  const Environment env = gravityOnly();
  for (int n = 0; n < 60; ++n)
  {
    body.step(1.0 / 60.0, env);
    const SolverReport& report = body.lastSolve();
    EXPECT_GT(report.iterations, 0) << "step " << n;
    EXPECT_LE(report.iterations, body.integrator().cg_max_iterations);
    EXPECT_TRUE(within(report, body.integrator())) << "step " << n;
    EXPECT_TRUE(report.converged) << "step " << n;
  }

  // A slack rope (every spring compressed) still gives a definite system that converges.
  RopeDef slack_def = def;
  slack_def.name = "slack";
  slack_def.rest_length = 3.0;  // span 2 m
  ASSERT_TRUE(validate(slack_def, 100).ok) << validate(slack_def, 100).message;
  SpringNetworkBody slack(buildRope(slack_def));
  for (int n = 0; n < 60; ++n)
  {
    slack.step(1.0 / 60.0, env);
    EXPECT_TRUE(slack.lastSolve().converged) << "slack rope step " << n;
    EXPECT_TRUE(within(slack.lastSolve(), slack.integrator())) << "slack rope step " << n;
  }

  // Capped at one iteration, the report says it did not converge.
  IntegratorDef capped = body.integrator();
  capped.cg_tolerance = 1e-12;
  capped.cg_velocity_tolerance = 1e-12;
  capped.cg_max_iterations = 1;
  ASSERT_TRUE(body.setIntegrator(capped).ok);
  body.step(1.0 / 60.0, env);
  EXPECT_EQ(body.lastSolve().iterations, 1);
  EXPECT_FALSE(body.lastSolve().converged);
  EXPECT_GT(body.lastSolve().relative_residual, capped.cg_tolerance);
  EXPECT_GT(body.lastSolve().velocity_error, capped.cg_velocity_tolerance);

  // The direct solver: no CG iteration, within the tolerance, and reported as direct.
  IntegratorDef direct = body.integrator();
  direct.linear_solver = LinearSolverType::Direct;
  ASSERT_TRUE(body.setIntegrator(direct).ok);
  body.step(1.0 / 60.0, env);
  EXPECT_TRUE(body.lastSolve().direct);
  EXPECT_EQ(body.lastSolve().iterations, 0);
  EXPECT_TRUE(body.lastSolve().converged);
  EXPECT_LE(body.lastSolve().relative_residual, direct.cg_tolerance);

  // The explicit methods do no solve.
  IntegratorDef symplectic;
  symplectic.type = kSymplecticEulerIntegrator;
  ASSERT_TRUE(body.setIntegrator(symplectic).ok);
  body.step(1.0 / 600.0, env);
  EXPECT_EQ(body.lastSolve().iterations, 0);
}

TEST(Integrator, ImplicitEulerStaysStableWhereSymplecticEulerBlowsUp)
{
  // k / m = 1e7 at dt = 1/60: omega dt is about 53, far beyond the explicit limit of 2.
  auto stiffRope = [](IntegratorType type) {
    RopeDef def = rope(10, type);
    def.mass = 1.0;  // 0.1 kg per particle
    def.stretch_stiffness = 1e6;
    def.stretch_damping = 0.0;
    def.pins = {0};
    EXPECT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
    return def;
  };
  const Environment env = gravityOnly();
  const double dt = 1.0 / 60.0;

  // Both implicit methods: implicit Euler and BDF2.
  for (IntegratorType type : {kImplicitEulerIntegrator, kBdf2Integrator})
  {
    const RopeDef implicit_def = stiffRope(type);
    SpringNetworkBody implicit_body(buildRope(implicit_def));
    const double rope_length = (implicit_def.end - implicit_def.start).norm();
    for (int n = 0; n < 300; ++n)
      implicit_body.step(dt, env);
    EXPECT_FALSE(implicit_body.frozen()) << toString(type) << " " << implicit_body.frozenReason();
    EXPECT_TRUE(allFinite(implicit_body)) << toString(type);
    const ParticlePool& p = implicit_body.particles();
    for (int i = 0; i < p.size(); ++i)
      EXPECT_LT((p.position.col(i) - implicit_def.start).norm(), 1.5 * rope_length)
          << toString(type) << " particle " << i;
  }

  // Symplectic Euler allowed no substeps (max_substeps = 1) blows up; it is frozen, not NaN.
  RopeDef single_step_def = stiffRope(kSymplecticEulerIntegrator);
  single_step_def.integrator.max_substeps = 1;
  SpringNetworkBody explicit_body(buildRope(single_step_def));
  for (int n = 0; n < 300; ++n)
    explicit_body.step(dt, env);
  EXPECT_TRUE(explicit_body.frozen());
  EXPECT_FALSE(explicit_body.frozenReason().empty());
  // A frozen body keeps its last finite state and no longer moves.
  EXPECT_TRUE(allFinite(explicit_body));
  const Eigen::Matrix3Xd frozen_at = explicit_body.particles().position;
  explicit_body.step(dt, env);
  EXPECT_EQ(explicit_body.particles().position, frozen_at);

  // With its default cap it sees the instability coming, splits each step and stays finite.
  SpringNetworkBody substepped(buildRope(stiffRope(kSymplecticEulerIntegrator)));
  for (int n = 0; n < 300; ++n)
    substepped.step(dt, env);
  EXPECT_FALSE(substepped.frozen()) << substepped.frozenReason();
  EXPECT_TRUE(allFinite(substepped));
  EXPECT_GT(substepped.lastSubsteps(), 50);  // dt omega_max is about 105, the limit 2 (with 10 % margin)
  EXPECT_GE(substepped.stabilityEvents(), 1);
  EXPECT_NE(substepped.lastStabilityEvent().find("substeps"), std::string::npos) << substepped.lastStabilityEvent();
}

TEST(Integrator, ImplicitEulerKeepsAStiffRopeSwingingWithoutEnergyCorrections)
{
  // A stiff rope (μ = 0.05 kg/m, EA = 5e4 N: axial waves at 1000 m/s) of 300 segments, pinned at one
  // end, released from horizontal at dt = 1/60 (h ω ≈ 500 for a segment). Each linearised step
  // stretches the turning segments along their tangents; the plain Newton iterations then diverged
  // and the step's energy excess was taken out of the velocities, often all of them (the rope
  // stopped in mid-air: 14 such events in these 120 steps before). Backward Euler converged with a
  // line search needs no such correction: no stability event, the energy never grows (gravity and
  // the rope's own damping only), and the rope falls: its free end more than half its length below
  // the pin after 2 s (6.6 m; a rigid rod hinged at one end would be near vertical by then).
  RopeDef def;
  def.name = "stiff";
  def.particles = 301;
  def.start = {0.0, 0.0, 0.0};
  def.end = {10.0, 0.0, 0.0};
  RopeMaterial material;
  material.linear_density = 0.05;
  material.axial_stiffness = 5e4;
  material.damping_ratio = 0.05;
  def.material = material;
  def.pins = {0};
  def.integrator.type = kImplicitEulerIntegrator;
  ASSERT_TRUE(validate(def, 1000).ok) << validate(def, 1000).message;
  SpringNetworkBody body(buildRope(def));
  const Environment env = gravityOnly();
  double energy = body.kineticEnergy() + body.potentialEnergy(env.gravity);
  for (int step = 0; step < 120; ++step)
  {
    body.step(1.0 / 60.0, env);
    const double now = body.kineticEnergy() + body.potentialEnergy(env.gravity);
    EXPECT_LE(now, energy + 1e-9 * (1.0 + std::abs(energy))) << "step " << step;
    energy = now;
  }
  EXPECT_EQ(body.stabilityEvents(), 0) << body.lastStabilityEvent();
  EXPECT_LT(body.particles().position(2, 300), -5.0);
}

TEST(Integrator, NonFiniteStateIsRolledBackAndFrozenInAnyChunkAtAnyThreadCount)
{
  // A chain of 0.1 m springs whose last particle is 1e300 m away: that spring's length overflows,
  // its force is NaN (∞ · 0), and so is the state of its two particles after an explicit step, the
  // only non-finite ones, in the third chunk of particles. The energy is NaN too, which no
  // comparison with the energy before calls a blow-up: only the finiteness check sees it. The step
  // must be rolled back, retried and the body frozen at its last good state.
  const int particles = 2 * kParticlesPerVectorChunk + 10;
  SpringNetworkDef def;
  def.name = "chain";
  for (int i = 0; i < particles; ++i)
    def.positions.emplace_back(i + 1 < particles ? 0.1 * i : 1e300, 0.0, 1.0);
  def.masses.assign(particles, 1.0);
  for (int i = 0; i + 1 < particles; ++i)
    def.springs.push_back(Spring{i, i + 1, 0.1, 10.0, 0.0, SpringClass::Stretch});
  def.integrator.type = kSymplecticEulerIntegrator;
  for (const int threads : {1, 2})
  {
    SCOPED_TRACE(testing::Message() << threads << " threads");
    SpringNetworkBody body(def);
    WorkerPool workers(threads);
    body.setWorkers(&workers);
    body.step(0.01, noGravity());
    EXPECT_TRUE(body.frozen());
    EXPECT_NE(body.frozenReason().find("blew up"), std::string::npos) << body.frozenReason();
    const ParticlePool& p = body.particles();
    EXPECT_TRUE(p.position.leftCols(p.size()).allFinite());
    EXPECT_TRUE(p.velocity.leftCols(p.size()).allFinite());
    EXPECT_EQ(p.position(0, particles - 1), 1e300);  // the last good state: the start
  }
}

TEST(Integrator, AnExplicitStepKeepsTheStateItStartedFrom)
{
  // Symplectic Euler and Verlet write the new state beside the old one, which the body keeps as the
  // start of the step. Each step of a chain whose pinned end is lifted with constant acceleration
  // (so its velocity differs from step to step) must leave: the positions it started from as
  // stepStartPositions(), bit for bit; the pin moved along the straight line from where it started
  // (its velocity (target − x0) / dt, whatever the substeps); and the pin's reaction
  // m (v1 − v0) / dt − f(x1, v1) with the velocity v0 the pin had before the step, not the one the
  // substep gave it. With one substep a step and with several, on one thread and two, over three
  // chunks of particles.
  const int particles = 2 * kParticlesPerVectorChunk + 10;
  SpringNetworkDef def;
  def.name = "chain";
  for (int i = 0; i < particles; ++i)
    def.positions.emplace_back(0.01 * i, 0.0, 1.0);
  def.masses.assign(particles, 0.001);
  for (int i = 0; i + 1 < particles; ++i)
    def.springs.push_back(Spring{i, i + 1, 0.01, 10.0, 0.001, SpringClass::Stretch});
  def.pins = {0};
  const Environment env = gravityOnly();
  for (const IntegratorType type : {kSymplecticEulerIntegrator, kVerletIntegrator})
    for (const double dt : {1e-3, 1e-2})  // ω_max ≈ 200 1/s: one substep, then several
      for (const int threads : {1, 2})
      {
        SCOPED_TRACE(testing::Message() << toString(type) << ", dt " << dt << ", " << threads << " threads");
        def.integrator.type = type;
        SpringNetworkBody body(def);
        WorkerPool workers(threads);
        body.setWorkers(&workers);
        const Eigen::Vector3d top = body.particles().position.col(0);
        Eigen::Matrix3Xd force(3, particles), reactions(3, particles);
        int substeps = 0;
        for (int n = 1; n <= 5; ++n)
        {
          const Eigen::Matrix3Xd x0 = body.particles().position.leftCols(particles);
          const Eigen::Vector3d v0 = body.particles().velocity.col(0);
          const double t = n * dt;
          const Eigen::Vector3d target = top + Eigen::Vector3d(0.0, 0.0, 0.5 * 3.0 * t * t);
          ASSERT_TRUE(body.setPinTarget(0, target).ok);
          body.step(dt, env);
          ASSERT_FALSE(body.frozen()) << body.frozenReason();
          substeps = std::max(substeps, body.lastSubsteps());
          EXPECT_TRUE((body.stepStartPositions().leftCols(particles).array() == x0.array()).all()) << "step " << n;
          const ParticlePool& p = body.particles();
          EXPECT_LT((p.velocity.col(0) - (target - x0.col(0)) / dt).norm(), 1e-12) << "step " << n;
          body.computeForces(p.position.leftCols(particles), p.velocity.leftCols(particles), env.gravity, force);
          body.pinReactions(reactions);
          const Eigen::Vector3d expected = 0.001 * Eigen::Vector3d((p.velocity.col(0) - v0) / dt) - force.col(0);
          EXPECT_EQ(reactions.col(0), expected) << "step " << n;
        }
        EXPECT_EQ(substeps > 1, dt == 1e-2) << substeps << " substeps";
      }
}

// The blow-up check of an explicit step weighs the energy after the step against the energy before
// it, which it takes from the last step while nothing has changed it. A change between two steps
// (stiffer springs, a released pin, another gravity) is a change of energy, not a blow-up: each
// here multiplies the energy by far more than the check's allowance of 100 times, and the step
// after it runs as usual, with no stability event.
TEST(Integrator, EnergyChangedBetweenStepsIsNoBlowUp)
{
  auto stretchedPair = [] {
    SpringNetworkDef def;
    def.name = "pair";
    def.positions = {Eigen::Vector3d(0.0, 0.0, 1000.0), Eigen::Vector3d(1.1, 0.0, 1000.0)};  // 10 % stretched
    def.masses = {1.0, 1.0};
    def.springs = {Spring{0, 1, 1.0, 1.0, 0.0, SpringClass::Stretch}};
    def.pins = {0};
    def.integrator.type = kSymplecticEulerIntegrator;
    return def;
  };
  const double dt = 1e-4;  // ω dt ≤ 0.15 at k = 1e6 N/m: no substeps needed
  Environment env = noGravity();
  auto settle = [&](SpringNetworkBody& body) {
    for (int n = 0; n < 10; ++n)
      body.step(dt, env);
    ASSERT_EQ(body.stabilityEvents(), 0) << body.lastStabilityEvent();
  };

  {  // stiffer: 0.005 J becomes 5000 J
    SpringNetworkBody body(stretchedPair());
    settle(body);
    ASSERT_TRUE(body.setSpringConstants(std::nullopt, 1e6, 0.0).ok);
    body.step(dt, env);
    EXPECT_EQ(body.stabilityEvents(), 0) << body.lastStabilityEvent();
    EXPECT_FALSE(body.frozen());
  }
  {  // released: a pin carried at 10 km/s has no kinetic energy until it is let go (5e7 J)
    SpringNetworkBody body(stretchedPair());
    settle(body);
    ASSERT_TRUE(body.setPinTarget(0, body.pinTarget(0) + Eigen::Vector3d(1.0, 0.0, 0.0)).ok);
    body.step(dt, env);
    ASSERT_TRUE(body.unpin(0).ok);
    body.step(dt, env);
    EXPECT_EQ(body.stabilityEvents(), 0) << body.lastStabilityEvent();
  }
  {  // gravity switched on 1 km up: 9810 J of potential energy per kilogram
    SpringNetworkBody body(stretchedPair());
    settle(body);
    env.gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
    body.step(dt, env);
    EXPECT_EQ(body.stabilityEvents(), 0) << body.lastStabilityEvent();
    env = noGravity();
  }
}
