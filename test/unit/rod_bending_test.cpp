// Discrete rod bending (forces/rod_bending.h): curvature 2 tan(θ/2), forces = −gradient of the
// energy and Jacobian blocks against finite differences, no force on a straight rope, energy
// invariant under rigid motion, stability rows that bound the stiffest mode; and the rope built
// from a material with EI > 0 bends as an Euler–Bernoulli beam: a clamped cantilever's tip
// deflection converges to μ g L⁴ / (8 EI) at the rate the discretisation predicts.

#include "particle_sim/core/forces/rod_bending.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <random>

#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/forces/spring_body_forces.h"
#include "particle_sim/core/spring_network.h"

using namespace particle_sim::core;

namespace
{
constexpr double kPi = 3.14159265358979323846;
constexpr double kStep = 1e-6;  // finite-difference step [m]
using Corners = Eigen::Matrix<double, 3, 3>;
using Vector9 = Eigen::Matrix<double, 9, 1>;
using Matrix9 = Eigen::Matrix<double, 9, 9>;

const Eigen::VectorXd kMasses = Eigen::VectorXd::Ones(3);
const std::vector<char> kNotPinned(3, 0);

ForceContext context()
{
  return ForceContext{kMasses, kNotPinned, Eigen::Vector3d::Zero(), AirDef(), 0.0};
}

RodBendingForce oneBend(double stiffness, double damping)
{
  RodBendingDef def;
  def.bends.push_back({{0, 1, 2}, stiffness, damping});
  return RodBendingForce(def);
}

Vector9 forces(const RodBendingForce& element, const Corners& x, const Corners& v = Corners::Zero())
{
  Eigen::Matrix3Xd f = Eigen::Matrix3Xd::Zero(3, 3);
  element.addForces(context(), x, v, f);
  return Eigen::Map<const Vector9>(f.data());
}

double energy(const RodBendingForce& element, const Corners& x)
{
  double e = 0.0;
  element.addEnergy(context(), x, e);
  return e;
}

// Three corners bent by `angle` [rad] at the middle, edges of lengths a and b [m], placed by a
// random rotation and translation.
Corners bent(double angle, double a, double b, std::mt19937_64& random)
{
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const Eigen::Quaterniond rotation = Eigen::Quaterniond::UnitRandom();
  Corners x;
  x.col(0) = Eigen::Vector3d(-a, 0, 0);
  x.col(1) = Eigen::Vector3d::Zero();
  x.col(2) = b * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0);
  const Eigen::Vector3d shift(uniform(random), uniform(random), uniform(random));
  for (int m = 0; m < 3; ++m)
    x.col(m) = rotation * x.col(m) + shift;
  return x;
}

Matrix9 numericForceJacobian(const RodBendingForce& element, const Corners& x, const Corners& v, bool by_velocity)
{
  Matrix9 j;
  for (int m = 0; m < 3; ++m)
    for (int a = 0; a < 3; ++a)
    {
      Corners xp = x, xm = x, vp = v, vm = v;
      (by_velocity ? vp : xp)(a, m) += kStep;
      (by_velocity ? vm : xm)(a, m) -= kStep;
      j.col(3 * m + a) = (forces(element, xp, vp) - forces(element, xm, vm)) / (2.0 * kStep);
    }
  return j;
}
}  // namespace

TEST(RodBending, CurvatureIsTwoTanHalfTheTurningAngleWhateverTheEdgeLengths)
{
  std::mt19937_64 random(7);
  for (double angle : {0.0, 0.1, 0.7, 1.5, 2.5})
    for (auto [a, b] : {std::pair<double, double>{1.0, 1.0}, {0.3, 2.0}})
    {
      Eigen::Vector3d kappa;
      Eigen::Matrix<double, 3, 9> jacobian;
      const Corners x = bent(angle, a, b, random);
      ASSERT_TRUE(rodCurvature(x.col(0), x.col(1), x.col(2), kappa, jacobian));
      EXPECT_NEAR(kappa.norm(), 2.0 * std::tan(angle / 2.0), 1e-12) << angle;
      // The binormal is normal to both edges.
      EXPECT_NEAR(kappa.dot(x.col(1) - x.col(0)), 0.0, 1e-12);
      EXPECT_NEAR(kappa.dot(x.col(2) - x.col(1)), 0.0, 1e-12);
      // E = k/2 |κ|² = 2 k tan²(θ/2).
      EXPECT_NEAR(energy(oneBend(3.0, 0.0), x), 6.0 * std::pow(std::tan(angle / 2.0), 2), 1e-12);
    }
  // Folded back or with a zero-length edge: not defined, and no force.
  Eigen::Vector3d kappa;
  Eigen::Matrix<double, 3, 9> jacobian;
  EXPECT_FALSE(rodCurvature({0, 0, 0}, {1, 0, 0}, {0, 0, 0}, kappa, jacobian));
  EXPECT_FALSE(rodCurvature({0, 0, 0}, {0, 0, 0}, {1, 0, 0}, kappa, jacobian));
  Corners folded;
  folded << 0, 1, 0, 0, 0, 0, 0, 0, 0;
  EXPECT_EQ(forces(oneBend(3.0, 1.0), folded), Vector9::Zero());
}

TEST(RodBending, ForcesAreMinusTheEnergyGradient)
{
  std::mt19937_64 random(11);
  std::uniform_real_distribution<double> angle(0.05, 2.5), length(0.2, 2.0);
  const RodBendingForce element = oneBend(2.5, 0.0);
  for (int trial = 0; trial < 20; ++trial)
  {
    const Corners x = bent(angle(random), length(random), length(random), random);
    Vector9 gradient;
    for (int m = 0; m < 3; ++m)
      for (int a = 0; a < 3; ++a)
      {
        Corners plus = x, minus = x;
        plus(a, m) += kStep;
        minus(a, m) -= kStep;
        gradient[3 * m + a] = (energy(element, plus) - energy(element, minus)) / (2.0 * kStep);
      }
    const Vector9 f = forces(element, x);
    EXPECT_LT((f + gradient).norm(), 1e-6 * std::max(1.0, f.norm())) << "trial " << trial;
  }
}

TEST(RodBending, StraightRopeFeelsNoForceAndRigidMotionChangesNothing)
{
  std::mt19937_64 random(3);
  const RodBendingForce element = oneBend(4.0, 0.5);
  // Straight (edges of different lengths, moving rigidly along the rope): no force.
  const Corners straight = bent(0.0, 0.4, 1.3, random);
  Corners along;
  for (int m = 0; m < 3; ++m)
    along.col(m) = 0.7 * (straight.col(2) - straight.col(0));
  EXPECT_LT(forces(element, straight, along).norm(), 1e-12);
  // Bent: energy unchanged and forces rotated by a rigid rotation and translation.
  const Corners x = bent(0.9, 0.5, 0.8, random);
  const Eigen::Matrix3d rotation = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
  const Eigen::Vector3d shift(0.3, -2.0, 5.0);
  Corners moved;
  for (int m = 0; m < 3; ++m)
    moved.col(m) = rotation * x.col(m) + shift;
  EXPECT_NEAR(energy(element, moved), energy(element, x), 1e-12);
  const Vector9 f = forces(element, x), g = forces(element, moved);
  for (int m = 0; m < 3; ++m)
    EXPECT_LT((g.segment<3>(3 * m) - rotation * f.segment<3>(3 * m)).norm(), 1e-12);
  // Internal forces: no net force and no net torque.
  Eigen::Vector3d total = Eigen::Vector3d::Zero(), torque = Eigen::Vector3d::Zero();
  for (int m = 0; m < 3; ++m)
  {
    total += f.segment<3>(3 * m);
    torque += x.col(m).cross(f.segment<3>(3 * m));
  }
  EXPECT_LT(total.norm(), 1e-12);
  EXPECT_LT(torque.norm(), 1e-12);
}

// ∂f/∂v is exact everywhere (the damping force is linear in v); ∂f/∂x is the Gauss–Newton form,
// exact on a straight rope, off by −k Σ κ_a ∇²κ_a elsewhere: an error proportional to |κ|, which
// halves when the angle halves.
TEST(RodBending, JacobianBlocksMatchFiniteDifferencesOfTheForce)
{
  std::mt19937_64 random(5);
  const RodBendingForce element = oneBend(2.0, 0.3);
  Matrix9 dfdx, dfdv;
  for (int trial = 0; trial < 5; ++trial)
  {
    const Corners straight = bent(0.0, 0.5 + 0.2 * trial, 1.0, random);
    element.jacobians(element.definition().bends[0], straight, dfdx, dfdv);
    EXPECT_LT((dfdx - numericForceJacobian(element, straight, Corners::Zero(), false)).norm(), 1e-6 * dfdx.norm());
    const Corners v = Corners::Random(), x = bent(1.1, 0.7, 0.9, random);
    Matrix9 bent_dfdx, bent_dfdv;
    element.jacobians(element.definition().bends[0], x, bent_dfdx, bent_dfdv);
    EXPECT_LT((bent_dfdv - numericForceJacobian(element, x, v, true)).norm(), 1e-6 * bent_dfdv.norm())
        << "trial " << trial;
    // Symmetric and negative semi-definite.
    EXPECT_LT((dfdx - dfdx.transpose()).norm(), 1e-12 * dfdx.norm());
    Eigen::SelfAdjointEigenSolver<Matrix9> eigen(dfdx);
    EXPECT_LT(eigen.eigenvalues().maxCoeff(), 1e-9 * dfdx.norm());
  }
  double previous = 0.0;
  for (double angle : {0.2, 0.1, 0.05})
  {
    const Corners x = bent(angle, 0.6, 0.6, random);
    element.jacobians(element.definition().bends[0], x, dfdx, dfdv);
    const double error = (dfdx - numericForceJacobian(element, x, Corners::Zero(), false)).norm() / dfdx.norm();
    if (previous > 0.0)
    {
      EXPECT_NEAR(previous / error, 2.0, 0.1) << angle;
    }
    previous = error;
  }
}

// On a straight uniform rope the Gershgorin rows bound the largest eigenvalue of M⁻¹ K (K the
// bending stiffness matrix); at an interior particle far from the ends the row is 16 k / l², the
// discrete beam operator's largest eigenvalue (stencil 1, −4, 6, −4, 1).
TEST(RodBending, StabilityRowsBoundTheStiffestBendingMode)
{
  const int n = 30;
  const double segment = 0.05, k = 0.8, mass = 0.01;
  RodBendingDef def;
  for (int i = 1; i + 1 < n; ++i)
    def.bends.push_back({{i - 1, i, i + 1}, k, 0.0});
  const RodBendingForce element(def);
  Eigen::Matrix3Xd x(3, n);
  std::vector<Eigen::Vector3d> rest;
  for (int i = 0; i < n; ++i)
  {
    x.col(i) = Eigen::Vector3d(i * segment, 0, 1);
    rest.push_back(x.col(i));
  }
  std::vector<double> stiffness_rows(n, 0.0), damping_rows(n, 0.0);
  element.addStabilityRows(rest, stiffness_rows, damping_rows);
  EXPECT_NEAR(stiffness_rows[n / 2], 16.0 * k / (segment * segment), 1e-9 * stiffness_rows[n / 2]);
  Eigen::MatrixXd stiffness = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  Matrix9 dfdx, dfdv;
  for (const RodBend& bend : def.bends)
  {
    element.jacobians(bend, x, dfdx, dfdv);
    for (int m = 0; m < 3; ++m)
      for (int c = 0; c < 3; ++c)
        stiffness.block<3, 3>(3 * bend.v[m], 3 * bend.v[c]) -= dfdx.block<3, 3>(3 * m, 3 * c);
  }
  const double largest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(stiffness / mass).eigenvalues().maxCoeff();
  const double bound = *std::max_element(stiffness_rows.begin(), stiffness_rows.end()) / mass;
  EXPECT_GE(bound, largest);
  EXPECT_LT(bound, 1.1 * largest);  // and tight: the bound sets the substeps
}

// ---------------------------------------------------------------------------------------------------
// Ropes built from a material.

namespace
{
RopeMaterial beamMaterial(double bending_stiffness)
{
  RopeMaterial material;
  material.linear_density = 0.1;
  material.axial_stiffness = 1e6;
  material.bending_stiffness = bending_stiffness;
  material.damping_ratio = 0.05;
  return material;
}
}  // namespace

TEST(RodBendingRope, OnlyARopeWithBendingStiffnessHasTheElement)
{
  RopeDef def;
  def.name = "rope";
  def.particles = 10;
  EXPECT_EQ(SpringNetworkBody(buildRope(def)).forces().find<RodBendingForce>(), nullptr);  // no material
  def.material = beamMaterial(0.0);
  EXPECT_EQ(SpringNetworkBody(buildRope(def)).forces().find<RodBendingForce>(), nullptr);  // a chain
  def.material = beamMaterial(0.02);
  const SpringNetworkDef net = buildRope(def);
  ASSERT_TRUE(validate(net, 100).ok) << validate(net, 100).message;
  const SpringNetworkBody body(net);
  const RodBendingForce* element = body.forces().find<RodBendingForce>();
  ASSERT_NE(element, nullptr);
  const double segment = 2.0 / 9.0;
  ASSERT_EQ(element->definition().bends.size(), 8u);
  for (const RodBend& bend : element->definition().bends)
  {
    EXPECT_EQ(bend.v[2] - bend.v[1], 1);
    EXPECT_EQ(bend.v[1] - bend.v[0], 1);
    EXPECT_NEAR(bend.stiffness, 0.02 / segment, 1e-12);
    // Same retardation time as the stretch springs: d / k = c / k_stretch.
    EXPECT_NEAR(bend.damping / bend.stiffness, net.springs[0].damping / net.springs[0].stiffness, 1e-15);
  }
}

// A horizontal rope clamped by pinning its first two particles, bending under its own weight.
// Euler–Bernoulli: tip deflection δ = μ g L⁴ / (8 EI) for small deflections. The discrete rod with
// N segments over the free length L: vertex i (x_i = i l, i = 0 at the clamp, up to N − 1) carries
// the exact moment μ g (L − x_i)² / 2 of the lumped weights beyond it (half at the tip) and turns by
// θ_i = M_i l / EI, so δ_N = Σ θ_i (L − x_i) = μ g l⁴ N² (N + 1)² / (8 EI) = δ (1 + 1/N)²: first
// order, relative error 2/N + 1/N², because the clamp vertex has a full segment of bending length
// while half of it lies in the clamped segment. Solved statically (Newton on the rope's forces),
// with δ / L = 1e-4 so that the large-deflection and stretch terms, O((δ/L)²), stay below 1e-6.
TEST(RodBendingRope, ClampedCantileverTipDeflectionConvergesToEulerBernoulli)
{
  const double length = 1.0, mu = 0.1, g = 9.81, ratio = 1e-4;
  const double ei = mu * g * std::pow(length, 4) / (8.0 * ratio * length);
  const double exact = mu * g * std::pow(length, 4) / (8.0 * ei);
  double previous_error = 0.0;
  for (int segments : {20, 40, 80})
  {
    const double segment = length / segments;
    RopeDef def;
    def.name = "cantilever";
    def.particles = segments + 2;  // one clamped segment before the free length
    def.start = {-segment, 0, 1};
    def.end = {length, 0, 1};
    def.material = beamMaterial(ei);
    def.pins = {0, 1};
    ASSERT_TRUE(validate(def, 1000).ok) << validate(def, 1000).message;
    const SpringNetworkDef net = buildRope(def);
    const ForceSet forces = makeSpringBodyForces(net.springs, net.baraff_witkin, net.triangles, net.rod_bending);
    const int n = def.particles;
    Eigen::VectorXd mass(n);
    for (int i = 0; i < n; ++i)
      mass[i] = net.masses[i];
    std::vector<char> pinned(n, 0);
    pinned[0] = pinned[1] = 1;
    const ForceContext context{mass, pinned, Eigen::Vector3d(0, 0, -g), AirDef(), 0.0};
    Eigen::Matrix3Xd x(3, n), v = Eigen::Matrix3Xd::Zero(3, n), f(3, n);
    for (int i = 0; i < n; ++i)
      x.col(i) = net.positions[i];
    const int free = 3 * (n - 2);
    auto residual = [&](const Eigen::Matrix3Xd& at) {
      f.setZero();
      forces.computeForces(context, at, v, f);
      return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(f.data() + 6, free));
    };
    // Newton on the free particles' force balance, the Jacobian by central differences.
    for (int iteration = 0; iteration < 20; ++iteration)
    {
      const Eigen::VectorXd r = residual(x);
      if (r.norm() < 1e-12 * mu * g * length) break;
      Eigen::MatrixXd jacobian(free, free);
      for (int c = 0; c < free; ++c)
      {
        Eigen::Matrix3Xd plus = x, minus = x;
        plus.data()[6 + c] += 1e-7;
        minus.data()[6 + c] -= 1e-7;
        jacobian.col(c) = (residual(plus) - residual(minus)) / 2e-7;
      }
      const Eigen::VectorXd step = jacobian.partialPivLu().solve(-r);
      for (int c = 0; c < free; ++c)
        x.data()[6 + c] += step[c];
    }
    // Solved to the rounding floor: 1e-16 m on positions of 1 m times the stiffest bending
    // stiffness 16 EI / l³ is about 1e-7 N per particle at 80 segments, 1e-6 of the weight μ g L.
    EXPECT_LT(residual(x).norm(), 1e-5 * mu * g * length);
    const double deflection = 1.0 - x(2, n - 1);
    const double error = deflection / exact - 1.0;
    const double predicted = 2.0 / segments + 1.0 / (segments * segments);
    std::printf("cantilever, %d segments: tip deflection %.9g m, Euler-Bernoulli %.9g m, error %.6f, predicted %.6f\n",
                segments, deflection, exact, error, predicted);
    EXPECT_NEAR(error, predicted, 100.0 * ratio * ratio) << segments << " segments";
    if (previous_error > 0.0)
    {
      // First order: the error halves with the segment length (2.025 and 2.012 predicted).
      EXPECT_NEAR(previous_error / error, 4.0 * (segments + 1.0) / (2.0 * segments + 1.0), 1e-3);
    }
    previous_error = error;
  }
}
