// The integrator registry: every registered method says what it is (name, implicit or not, order,
// stability limit), the name functions and stabilityLimit() read the registry, and each method's
// declared order is the order measured on the analytic harmonic oscillator.

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/registry.h"
#include "particle_sim/core/integrators/rk4.h"
#include "particle_sim/core/integrators/symplectic_euler.h"
#include "particle_sim/core/integrators/verlet.h"
#include "particle_sim/core/spring_network.h"

using namespace particle_sim::core;

namespace
{
// Max over [0, duration] of |x_1 − exact| for one undamped spring (k = 4π², m = 1, so ω = 2π),
// particle 0 pinned, particle 1 released at rest 0.1 m beyond its rest length 1 m.
double oscillatorError(IntegratorType type, double dt, double duration)
{
  const double k = 4.0 * M_PI * M_PI, m = 1.0, rest = 1.0, amplitude = 0.1;
  SpringNetworkDef def;
  def.name = "oscillator";
  def.positions = {Eigen::Vector3d::Zero(), Eigen::Vector3d(rest + amplitude, 0, 0)};
  def.masses = {m, m};
  def.springs = {Spring{0, 1, rest, k, 0.0, SpringClass::Stretch}};
  def.pins = {0};
  def.integrator.type = type;
  def.integrator.cg_tolerance = 1e-12;
  EXPECT_TRUE(validate(def, 10).ok);
  SpringNetworkBody body(def);
  Environment env;
  env.gravity.setZero();
  env.ground.enabled = false;
  const double omega = std::sqrt(k / m);
  const int steps = static_cast<int>(std::lround(duration / dt));
  double error = 0.0;
  for (int n = 1; n <= steps; ++n)
  {
    body.step(dt, env);
    const double exact = rest + amplitude * std::cos(omega * n * dt);
    error = std::max(error, std::abs(body.particles().position(0, 1) - exact));
  }
  return error;
}
}  // namespace

TEST(IntegratorRegistry, EveryMethodDeclaresWhatItIsAndTheNameFunctionsReadIt)
{
  const std::vector<IntegratorInfo>& registry = integratorRegistry();
  ASSERT_FALSE(registry.empty());
  std::string names;
  for (const IntegratorInfo& info : registry)
  {
    names += std::string(info.name) + ", ";
    EXPECT_STREQ(toString(info.type), info.name);
    IntegratorType parsed = kAutoIntegrator;
    ASSERT_TRUE(parseIntegratorType(info.name, parsed)) << info.name;
    EXPECT_EQ(parsed, info.type) << info.name;
    EXPECT_EQ(findIntegrator(info.type), &info) << info.name;
    EXPECT_EQ(isImplicit(info.type), info.implicit) << info.name;
    EXPECT_EQ(stabilityLimit(info.type), info.stability_limit) << info.name;
    // Implicit methods are unconditionally stable; explicit ones have a finite limit h·ω > 0.
    EXPECT_EQ(std::isinf(info.stability_limit), info.implicit) << info.name;
    EXPECT_GT(info.stability_limit, 0.0) << info.name;
    EXPECT_GE(info.order, 1) << info.name;
    EXPECT_NE(info.make(3, {{0, 1}, {1, 2}}), nullptr) << info.name;
  }
  // `auto` is a policy, not a method: listed last, parsed, neither implicit nor registered.
  EXPECT_EQ(std::string(integratorTypeNames()), names + "auto");
  EXPECT_EQ(findIntegrator(kAutoIntegrator), nullptr);
  EXPECT_FALSE(isImplicit(kAutoIntegrator));
  EXPECT_TRUE(std::isinf(stabilityLimit(kAutoIntegrator)));
  // The classical limits on the imaginary axis (leapfrog 2, classical RK4 2√2),
  // as the same doubles the substep counts were computed with.
  EXPECT_EQ(stabilityLimit(kSymplecticEulerIntegrator), 2.0);
  EXPECT_EQ(stabilityLimit(kVerletIntegrator), 2.0);
  EXPECT_EQ(stabilityLimit(kRk4Integrator), 2.0 * std::sqrt(2.0));
  EXPECT_TRUE(isImplicit(kImplicitEulerIntegrator));
}

TEST(IntegratorRegistry, DeclaredOrderIsTheOrderMeasuredOnTheOscillator)
{
  // Observed order log2(e(h) / e(h/2)) of the max position error over two periods, from a first
  // step small enough for each order's asymptotic range and errors well above round-off.
  for (const IntegratorInfo& info : integratorRegistry())
  {
    const double first_dt = info.order >= 4 ? 1.0 / 40.0 : info.order >= 2 ? 1.0 / 50.0 : 1.0 / 100.0;
    std::vector<double> errors;
    for (int level = 0; level < 3; ++level)
      errors.push_back(oscillatorError(info.type, first_dt / std::pow(2.0, level), 2.0));
    for (std::size_t level = 0; level + 1 < errors.size(); ++level)
    {
      ASSERT_GT(errors[level + 1], 1e-11) << info.name;
      EXPECT_NEAR(std::log2(errors[level] / errors[level + 1]), info.order, 0.25)
          << info.name << " errors " << errors[level] << " -> " << errors[level + 1];
    }
  }
}
