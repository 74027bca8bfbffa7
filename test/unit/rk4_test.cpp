// RK4 (src/core/integrators/rk4.cpp) inside a step that the stability guard splits into substeps:
// every substep starts from the state the previous one ended in, so a step of dt split into n
// substeps is n RK4 steps of dt / n, and stays fourth order.

#include "particle_sim/core/integrators/rk4.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/spring_network.h"

using namespace particle_sim::core;

namespace
{
Environment noGround(const Eigen::Vector3d& gravity)
{
  Environment env;
  env.gravity = gravity;
  env.ground.enabled = false;
  return env;
}

// The undamped oscillator of integrator_test.cpp (particle 1, 1 kg on a 4π² N/m spring of rest
// length 1 m pinned at the origin, released at rest 0.1 m out: x(t) = 1 + 0.1 cos 2πt) plus a
// stiff spring that never moves: particle 3 (1 kg) sits at rest exactly at its rest length from
// the pinned particle 2, so it feels no force, but it raises the body's bound ω_max until the
// stability guard splits a step of dt into exactly `substeps` RK4 substeps.
struct SplitOscillator
{
  static constexpr double kStiffness = 4.0 * M_PI * M_PI;  // [N/m], ω = 2π rad/s
  static constexpr double kRest = 1.0;                     // [m]
  static constexpr double kAmplitude = 0.1;                // [m]

  static SpringNetworkDef def(double dt, int substeps)
  {
    SpringNetworkDef d;
    d.name = "oscillator";
    d.positions = {Eigen::Vector3d::Zero(), Eigen::Vector3d(kRest + kAmplitude, 0, 0), Eigen::Vector3d(0, 1, 0),
                   Eigen::Vector3d(1, 1, 0)};
    d.masses = {1.0, 1.0, 1.0, 1.0};
    // The guard asks for ceil(dt ω_max / (0.9 · 2√2)) substeps, with ω_max = sqrt(2 k / m) (Gershgorin
    // row of a spring): aim at substeps − 1/2 of them.
    const double omega_max = (substeps - 0.5) * 0.9 * Rk4Method::kStabilityLimit / dt;
    const double stiff = 0.5 * omega_max * omega_max;  // [N/m] with m = 1 kg
    d.springs = {{0, 1, kRest, kStiffness, 0.0, SpringClass::Stretch}, {2, 3, 1.0, stiff, 0.0, SpringClass::Stretch}};
    d.pins = {0, 2};
    d.integrator.type = kRk4Integrator;
    return d;
  }
  static double exact(double t) { return kRest + kAmplitude * std::cos(std::sqrt(kStiffness) * t); }
};
}  // namespace

// n substeps of one step are n RK4 steps of the substep's length: the same state to round-off,
// on the oscillator and on a stiff rope swinging under gravity.
TEST(Rk4, StepSplitIntoSubstepsIsTheSameAsStepsOfTheSubstepLength)
{
  const Environment env = noGround(Eigen::Vector3d::Zero());
  const double dt = 0.1;
  const int n = 4;
  SpringNetworkBody split(SplitOscillator::def(dt, n));
  SpringNetworkBody direct(SplitOscillator::def(dt, n));
  ASSERT_EQ(split.planStep(dt, env).substeps, n);
  ASSERT_EQ(direct.planStep(dt / n, env).substeps, 1);
  for (int step = 1; step <= 10; ++step)
  {
    split.step(dt, env);
    ASSERT_EQ(split.lastSubsteps(), n);
    for (int k = 0; k < n; ++k)
      direct.step(dt / n, env);
    const Eigen::Matrix3Xd& x = split.particles().position;
    EXPECT_LE((x - direct.particles().position).lpNorm<Eigen::Infinity>(), 1e-14) << "step " << step;
    EXPECT_LE((split.particles().velocity - direct.particles().velocity).lpNorm<Eigen::Infinity>(), 1e-13)
        << "step " << step;
    // And both are on the analytic oscillation (RK4 at h = 0.025 s: about 1e-5 m).
    EXPECT_NEAR(x(0, 1), SplitOscillator::exact(step * dt), 2e-5) << "step " << step;
  }

  // A stiff undamped rope released horizontally under gravity, one end pinned, at 1/60 s.
  RopeDef rope;
  rope.name = "rope";
  rope.particles = 10;
  rope.start = {0, 0, 0};
  rope.end = {1, 0, 0};
  rope.mass = 1.0;
  rope.stretch_stiffness = 5000.0;
  rope.stretch_damping = 0.0;
  rope.pins = {0};
  rope.integrator.type = kRk4Integrator;
  ASSERT_TRUE(validate(rope, 100).ok) << validate(rope, 100).message;
  const Environment gravity = noGround(Eigen::Vector3d(0, 0, -9.81));
  const double frame = 1.0 / 60.0;
  SpringNetworkBody split_rope(buildRope(rope));
  SpringNetworkBody direct_rope(buildRope(rope));
  const int substeps = split_rope.planStep(frame, gravity).substeps;
  ASSERT_GT(substeps, 1);
  ASSERT_EQ(direct_rope.planStep(frame / substeps, gravity).substeps, 1);
  for (int step = 1; step <= 30; ++step)  // half a second: the rope swings down past the vertical
  {
    split_rope.step(frame, gravity);
    ASSERT_EQ(split_rope.lastSubsteps(), substeps);
    for (int k = 0; k < substeps; ++k)
      direct_rope.step(frame / substeps, gravity);
    EXPECT_LE((split_rope.particles().position - direct_rope.particles().position).lpNorm<Eigen::Infinity>(), 1e-12)
        << "step " << step;
    EXPECT_LE((split_rope.particles().velocity - direct_rope.particles().velocity).lpNorm<Eigen::Infinity>(), 1e-10)
        << "step " << step;
  }
  EXPECT_LT(split_rope.particles().position(2, 9), -0.5);  // it did swing down
}

// Split into four substeps at every step length, RK4 converges at order 4 on the oscillator.
TEST(Rk4, ConvergesAtOrderFourWhenEveryStepIsSplit)
{
  const Environment env = noGround(Eigen::Vector3d::Zero());
  const int n = 4;
  const double duration = 2.0;  // two periods
  std::vector<double> errors;
  for (double dt : {1.0 / 10.0, 1.0 / 20.0, 1.0 / 40.0, 1.0 / 80.0})
  {
    SpringNetworkBody body(SplitOscillator::def(dt, n));
    double error = 0.0;
    const int steps = static_cast<int>(std::lround(duration / dt));
    for (int step = 1; step <= steps; ++step)
    {
      body.step(dt, env);
      EXPECT_EQ(body.lastSubsteps(), n) << "dt = " << dt;
      error = std::max(error, std::abs(body.particles().position(0, 1) - SplitOscillator::exact(step * dt)));
    }
    errors.push_back(error);
  }
  for (std::size_t level = 0; level + 1 < errors.size(); ++level)
  {
    EXPECT_GT(errors[level + 1], 1e-11);  // truncation, not round-off
    EXPECT_NEAR(std::log2(errors[level] / errors[level + 1]), 4.0, 0.25)
        << "errors " << errors[level] << " -> " << errors[level + 1];
  }
  // At dt = 0.1 s in four substeps: the error of RK4 at 0.025 s (about 1e-5 m over two periods).
  EXPECT_LT(errors[0], 2e-5);
}
