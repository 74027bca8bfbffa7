// The spring force element: the force is the lecture's formula and acts equally and oppositely on
// both ends, its energy's negative gradient is the elastic force, and its Jacobian blocks are the
// derivatives of the force (central finite differences), the definite form staying semi-definite.

#include "particle_sim/core/spring.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

using namespace particle_sim::core;

namespace
{
// A random spring configuration: x_j sits at length `stretch` * rest_length from x_i along a
// random direction, so stretch < 1 is compressed and stretch > 1 stretched.
struct Config
{
  Eigen::Vector3d xi, xj, vi, vj;
  double rest_length, stiffness, damping;
};

Config randomConfig(std::mt19937_64& rng, double stretch)
{
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  auto vec = [&]() { return Eigen::Vector3d(unit(rng), unit(rng), unit(rng)); };
  Config c;
  c.rest_length = 0.5 + 1.5 * 0.5 * (unit(rng) + 1.0);  // [0.5, 2]
  c.stiffness = std::pow(10.0, 1.0 + unit(rng));        // [1, 100]
  c.damping = 5.0 * 0.5 * (unit(rng) + 1.0) + 0.1;      // [0.1, 5.1]
  c.xi = vec();
  Eigen::Vector3d direction = vec();
  while (direction.norm() < 0.1)
    direction = vec();
  c.xj = c.xi + stretch * c.rest_length * direction.normalized();
  c.vi = vec();
  c.vj = vec();
  return c;
}

// Central difference of `f` (R^3 -> R^3) at `x`: column k is (f(x + e e_k) - f(x - e e_k)) / 2e.
template <typename F>
Eigen::Matrix3d centralDifference(F f, const Eigen::Vector3d& x, double step)
{
  Eigen::Matrix3d jacobian;
  for (int k = 0; k < 3; ++k)
  {
    Eigen::Vector3d plus = x, minus = x;
    plus[k] += step;
    minus[k] -= step;
    jacobian.col(k) = (f(plus) - f(minus)) / (2.0 * step);
  }
  return jacobian;
}

// Compressed and stretched lengths, as multiples of the rest length.
const double kStretches[] = {0.3, 0.7, 0.95, 1.05, 1.4, 2.5};
}  // namespace

TEST(Spring, ForceMatchesTheLectureFormulaOnHandComputedCases)
{
  // Elastic only: l = 5 along (0.6, 0.8, 0), stretched by 3: f_i = 10 * 3 * d.
  Eigen::Vector3d f = springForce({0, 0, 0}, {3, 4, 0}, {0, 0, 0}, {0, 0, 0}, 2.0, 10.0, 0.0);
  EXPECT_NEAR((f - Eigen::Vector3d(18, 24, 0)).norm(), 0.0, 1e-12);

  // Compressed by 0.5 along +z with k = 4 (-2), closing at 2 m/s with k_d = 3 (-6): f_i = -8 z.
  f = springForce({1, 1, 1}, {1, 1, 3}, {1, 0, 0.5}, {0, 2, -1.5}, 2.5, 4.0, 3.0);
  EXPECT_NEAR((f - Eigen::Vector3d(0, 0, -8)).norm(), 0.0, 1e-12);

  // l = 5 along (0, 0.6, 0.8), L = 4, k = 2 (+2); (v_j - v_i).d = 1.4, k_d = 0.5 (+0.7): 2.7 d.
  f = springForce({1, 2, 3}, {1, 5, 7}, {0, 0, 0}, {1, 1, 1}, 4.0, 2.0, 0.5);
  EXPECT_NEAR((f - Eigen::Vector3d(0, 1.62, 2.16)).norm(), 0.0, 1e-12);

  // Coincident particles have no direction and get no force.
  f = springForce({1, 2, 3}, {1, 2, 3}, {0, 0, 0}, {1, 0, 0}, 1.0, 10.0, 1.0);
  EXPECT_TRUE(f.allFinite());
  EXPECT_EQ(f.norm(), 0.0);
}

TEST(Spring, ForceIsZeroAtRestLengthWithEqualVelocities)
{
  const Eigen::Vector3d v(0.7, -1.2, 3.0);
  EXPECT_NEAR(springForce({1, 2, 3}, {3, 2, 3}, v, v, 2.0, 250.0, 4.0).norm(), 0.0, 1e-12);
  EXPECT_NEAR(springForce({0, 0, 0}, {0, 3, 4}, v, v, 5.0, 1e4, 10.0).norm(), 0.0, 1e-10);
}

TEST(Spring, ForceOnJIsTheOppositeOfTheForceOnI)
{
  std::mt19937_64 rng(7);
  for (double stretch : kStretches)
  {
    for (int trial = 0; trial < 20; ++trial)
    {
      const Config c = randomConfig(rng, stretch);
      const Eigen::Vector3d fi = springForce(c.xi, c.xj, c.vi, c.vj, c.rest_length, c.stiffness, c.damping);
      const Eigen::Vector3d fj = springForce(c.xj, c.xi, c.vj, c.vi, c.rest_length, c.stiffness, c.damping);
      EXPECT_LE((fi + fj).norm(), 1e-12 * (1.0 + fi.norm())) << "stretch " << stretch;
      // The force is along the spring.
      const Eigen::Vector3d d = (c.xj - c.xi).normalized();
      EXPECT_LE((fi - fi.dot(d) * d).norm(), 1e-12 * (1.0 + fi.norm()));
    }
  }
}

TEST(Spring, PositionJacobianIsTheFiniteDifferenceDerivativeOfTheElasticForce)
{
  std::mt19937_64 rng(42);
  for (double stretch : kStretches)
  {
    for (int trial = 0; trial < 20; ++trial)
    {
      const Config c = randomConfig(rng, stretch);
      Eigen::Matrix3d dfdx, dfdv;
      springJacobians(c.xi, c.xj, c.rest_length, c.stiffness, c.damping, false, dfdx, dfdv);
      // Without damping the blocks are the exact derivatives of f_i (damping's position
      // dependence is left out by design, so it is switched off here).
      const double step = 1e-6 * c.rest_length;
      const Eigen::Matrix3d by_xi = centralDifference(
          [&](const Eigen::Vector3d& x) { return springForce(x, c.xj, c.vi, c.vj, c.rest_length, c.stiffness, 0.0); },
          c.xi, step);
      const Eigen::Matrix3d by_xj = centralDifference(
          [&](const Eigen::Vector3d& x) { return springForce(c.xi, x, c.vi, c.vj, c.rest_length, c.stiffness, 0.0); },
          c.xj, step);
      const double scale = dfdx.norm();
      EXPECT_LE((dfdx - by_xi).norm(), 1e-6 * scale) << "stretch " << stretch << "\n" << dfdx << "\n" << by_xi;
      EXPECT_LE((-dfdx - by_xj).norm(), 1e-6 * scale) << "stretch " << stretch;
      // The tangent stiffness is symmetric.
      EXPECT_LE((dfdx - dfdx.transpose()).norm(), 1e-12 * scale);
    }
  }
}

TEST(Spring, VelocityJacobianIsTheFiniteDifferenceDerivativeOfTheForce)
{
  std::mt19937_64 rng(43);
  for (double stretch : kStretches)
  {
    for (int trial = 0; trial < 20; ++trial)
    {
      const Config c = randomConfig(rng, stretch);
      for (bool definite : {false, true})
      {
        Eigen::Matrix3d dfdx, dfdv;
        springJacobians(c.xi, c.xj, c.rest_length, c.stiffness, c.damping, definite, dfdx, dfdv);
        const Eigen::Matrix3d by_vi = centralDifference(
            [&](const Eigen::Vector3d& v) {
              return springForce(c.xi, c.xj, v, c.vj, c.rest_length, c.stiffness, c.damping);
            },
            c.vi, 1e-6);
        const Eigen::Matrix3d by_vj = centralDifference(
            [&](const Eigen::Vector3d& v) {
              return springForce(c.xi, c.xj, c.vi, v, c.rest_length, c.stiffness, c.damping);
            },
            c.vj, 1e-6);
        const double scale = dfdv.norm();
        ASSERT_GT(scale, 0.0);
        EXPECT_LE((dfdv - by_vi).norm(), 1e-6 * scale) << "stretch " << stretch;
        EXPECT_LE((-dfdv - by_vj).norm(), 1e-6 * scale) << "stretch " << stretch;
      }
    }
  }
}

TEST(Spring, DefiniteJacobianIsNegativeSemiDefiniteAndExactWhenStretched)
{
  std::mt19937_64 rng(44);
  for (double stretch : kStretches)
  {
    for (int trial = 0; trial < 20; ++trial)
    {
      const Config c = randomConfig(rng, stretch);
      Eigen::Matrix3d exact_dfdx, exact_dfdv, dfdx, dfdv;
      springJacobians(c.xi, c.xj, c.rest_length, c.stiffness, c.damping, false, exact_dfdx, exact_dfdv);
      springJacobians(c.xi, c.xj, c.rest_length, c.stiffness, c.damping, true, dfdx, dfdv);
      const double scale = c.stiffness;

      // -dfdx and -dfdv are symmetric positive semi-definite, compressed or not.
      for (const Eigen::Matrix3d* block : {&dfdx, &dfdv})
      {
        const Eigen::Matrix3d minus = -*block;
        EXPECT_LE((minus - minus.transpose()).norm(), 1e-12 * scale);
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(minus);
        EXPECT_GE(eigen.eigenvalues().minCoeff(), -1e-12 * scale) << "stretch " << stretch << "\n" << minus;
      }

      const Eigen::Vector3d d = (c.xj - c.xi).normalized();
      if (stretch > 1.0)
      {
        // Stretched: the definite form is the exact derivative.
        EXPECT_LE((dfdx - exact_dfdx).norm(), 1e-12 * scale) << "stretch " << stretch;
      }
      else
      {
        // Compressed: the exact one has a positive (unstable) transverse eigenvalue
        // k (L/l - 1), which the definite form clamps to 0, leaving -k d d^T.
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(exact_dfdx);
        EXPECT_NEAR(eigen.eigenvalues().maxCoeff(), c.stiffness * (1.0 / stretch - 1.0), 1e-10 * scale);
        EXPECT_LE((dfdx + c.stiffness * d * d.transpose()).norm(), 1e-12 * scale) << "stretch " << stretch;
      }
      // Along the spring both forms give the full stiffness: dfdx d = -k d.
      EXPECT_LE((dfdx * d + c.stiffness * d).norm(), 1e-12 * scale);
      // The velocity block does not depend on the definite flag.
      EXPECT_LE((dfdv - exact_dfdv).norm(), 1e-12 * scale);
    }
  }
}

TEST(Spring, JacobianPartsMakeTheDefiniteJacobian)
{
  // along_x d dᵀ + isotropic_x I and along_v d dᵀ are the definite blocks, compressed or stretched,
  // to rounding; coincident ends have no direction and no parts.
  std::mt19937_64 rng(45);
  for (double stretch : kStretches)
  {
    for (int trial = 0; trial < 20; ++trial)
    {
      const Config c = randomConfig(rng, stretch);
      Eigen::Matrix3d dfdx, dfdv;
      springJacobians(c.xi, c.xj, c.rest_length, c.stiffness, c.damping, true, dfdx, dfdv);
      Eigen::Vector3d d;
      double along_x = 0.0, isotropic_x = 0.0, along_v = 0.0;
      ASSERT_TRUE(
          springJacobianParts(c.xi, c.xj, c.rest_length, c.stiffness, c.damping, d, along_x, isotropic_x, along_v));
      EXPECT_NEAR(d.norm(), 1.0, 1e-15);
      const Eigen::Matrix3d parts_dfdx = along_x * d * d.transpose() + isotropic_x * Eigen::Matrix3d::Identity();
      EXPECT_LE((parts_dfdx - dfdx).norm(), 1e-14 * c.stiffness) << "stretch " << stretch;
      EXPECT_LE((along_v * d * d.transpose() - dfdv).norm(), 1e-14 * c.damping) << "stretch " << stretch;
    }
  }
  Eigen::Vector3d d;
  double along_x = 0.0, isotropic_x = 0.0, along_v = 0.0;
  const Eigen::Vector3d x(0.25, -1.0, 2.0);
  EXPECT_FALSE(springJacobianParts(x, x, 1.0, 10.0, 1.0, d, along_x, isotropic_x, along_v));
}

TEST(Spring, JacobianPartsOfManyAreEachSpringsBitForBit)
{
  // springJacobianPartsOf(), four springs at a time or one, gives for every spring the bits that
  // springJacobianParts() gives it alone: compressed and stretched springs, a spring at its rest
  // length (transverse factor 0), coincident ends, a zero stiffness (a −0 part), a non-finite
  // position, and a count that leaves springs over after the groups of four.
  std::mt19937_64 rng(46);
  std::vector<Spring> springs;
  std::vector<Eigen::Vector3d> positions;
  auto add = [&](const Eigen::Vector3d& xi, const Eigen::Vector3d& xj, double rest_length, double stiffness) {
    Spring spring;
    spring.i = static_cast<int>(positions.size());
    spring.j = spring.i + 1;
    spring.rest_length = rest_length;
    spring.stiffness = stiffness;
    spring.damping = 0.5;
    springs.push_back(spring);
    positions.push_back(xi);
    positions.push_back(xj);
  };
  // The unusual springs first, in groups of four.
  add({0.0, 0.0, 0.0}, {3.0, 4.0, 0.0}, 5.0, 100.0);  // at its rest length
  add({1.0, 2.0, 3.0}, {1.0, 2.0, 3.0}, 1.0, 100.0);  // coincident
  add({0.0, 0.0, 0.0}, {0.0, 0.0, 2.0}, 1.0, 0.0);    // no stiffness
  add({0.0, 0.0, 0.0}, {0.0, 0.0, 0.5}, 1.0, 0.0);    // no stiffness, compressed
  add({0.0, std::nan(""), 0.0}, {0.0, 1.0, 0.0}, 1.0, 10.0);
  add({0.0, 0.0, 0.0}, {std::numeric_limits<double>::infinity(), 1.0, 0.0}, 1.0, 10.0);
  add({0.0, 0.0, 0.0}, {1e-300, 0.0, 0.0}, 1.0, 10.0);  // its square underflows: coincident too
  for (double stretch : kStretches)
  {
    for (int trial = 0; trial < 7; ++trial)
    {
      const Config c = randomConfig(rng, stretch);
      add(c.xi, c.xj, c.rest_length, c.stiffness);
    }
  }
  ASSERT_NE(springs.size() % 4, 0u);
  std::vector<double> x;
  for (const Eigen::Vector3d& p : positions)
    x.insert(x.end(), {p.x(), p.y(), p.z()});

  const int count = static_cast<int>(springs.size());
  for (bool vectorized : {true, false})
  {
    SpringJacobianParts parts;
    parts.resize(springs.size());
    // Two calls, the first range ending inside a group of four.
    springJacobianPartsOf(springs.data(), 0, 10, x.data(), vectorized, parts);
    springJacobianPartsOf(springs.data(), 10, count, x.data(), vectorized, parts);
    int coincident = 0;
    for (int s = 0; s < count; ++s)
    {
      const Spring& spring = springs[s];
      Eigen::Vector3d d;
      double along_x = 0.0, isotropic_x = 0.0, along_v = 0.0;
      const bool has_parts = springJacobianParts(positions[spring.i], positions[spring.j], spring.rest_length,
                                                 spring.stiffness, spring.damping, d, along_x, isotropic_x, along_v);
      ASSERT_EQ(parts.coincident[s] != 0, !has_parts) << "spring " << s << (vectorized ? ", four at a time" : "");
      if (!has_parts)
      {
        ++coincident;
        continue;
      }
      auto bits = [](double value) {
        std::uint64_t b = 0;
        std::memcpy(&b, &value, sizeof b);
        return b;
      };
      const double expected[5] = {d.x(), d.y(), d.z(), along_x, isotropic_x};
      const double got[5] = {parts.d_x[s], parts.d_y[s], parts.d_z[s], parts.along_x[s], parts.isotropic_x[s]};
      for (int k = 0; k < 5; ++k)
        EXPECT_EQ(bits(got[k]), bits(expected[k]))
            << "spring " << s << " number " << k << (vectorized ? ", four at a time" : "");
    }
    EXPECT_EQ(coincident, 2);
  }
}

TEST(Spring, ForcesOfManyAreEachSpringsAddedInOrderBitForBit)
{
  // addSpringForcesOf(), four springs at a time or two, gives every particle the bits of adding
  // springForce() of each spring in the order of the list (+f at end i, −f at end j), and each
  // spring springEnergy()'s bits. The network: runs of springs that share their end i (as a cloth's
  // point starts five of its springs, which the vector form holds in registers), ends shared across
  // runs, a spring of zero length inside a group of four, and a count that leaves springs over after
  // the groups of four; then both ends, end i alone and end j alone (a chunk's runs).
  std::mt19937_64 rng(47);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const int particles = 60;
  std::vector<double> x(3 * particles), v(3 * particles);
  for (double& c : x)
    c = unit(rng);
  for (double& c : v)
    c = unit(rng);
  std::vector<Spring> springs;
  std::uniform_int_distribution<int> particle(0, particles - 1), run_length(1, 6);
  while (springs.size() < 203)
  {
    const int i = particle(rng);
    for (int k = run_length(rng); k > 0; --k)
    {
      Spring spring;
      spring.i = i;
      spring.j = particle(rng);
      if (spring.j == i) continue;
      spring.rest_length = 0.5 + 0.5 * (unit(rng) + 1.0);
      spring.stiffness = std::pow(10.0, 2.0 + unit(rng));
      spring.damping = 0.5 * (unit(rng) + 1.0);
      springs.push_back(spring);
    }
  }
  springs.resize(203);
  // Springs 41 and 42 join two particles at the same place (no direction: no force), one of them
  // to a particle that other springs pull.
  std::copy_n(&x[3 * 7], 3, &x[3 * 8]);
  springs[41].i = 7;
  springs[41].j = 8;
  springs[42].i = 8;
  springs[42].j = 7;
  const int count = static_cast<int>(springs.size());
  ASSERT_NE(count % 4, 0);

  auto bits = [](double value) {
    std::uint64_t b = 0;
    std::memcpy(&b, &value, sizeof b);
    return b;
  };
  for (const auto& [add_i, add_j] : {std::pair{true, true}, std::pair{true, false}, std::pair{false, true}})
  {
    // The definition: one spring after the other.
    std::vector<double> expected(3 * particles, 0.0);
    std::vector<double> expected_energy(count);
    double expected_sum = 0.25;
    for (int s = 0; s < count; ++s)
    {
      const Spring& spring = springs[s];
      const Eigen::Map<const Eigen::Vector3d> xi(&x[3 * spring.i]), xj(&x[3 * spring.j]);
      const Eigen::Vector3d f = springForce(xi, xj, Eigen::Map<const Eigen::Vector3d>(&v[3 * spring.i]),
                                            Eigen::Map<const Eigen::Vector3d>(&v[3 * spring.j]), spring.rest_length,
                                            spring.stiffness, spring.damping);
      if (add_i) Eigen::Map<Eigen::Vector3d>(&expected[3 * spring.i]) += f;
      if (add_j) Eigen::Map<Eigen::Vector3d>(&expected[3 * spring.j]) -= f;
      expected_energy[s] = springEnergy(xi, xj, spring.rest_length, spring.stiffness);
      expected_sum += expected_energy[s];
    }
    for (bool vectorized : {true, false})
    {
      const std::string form =
          std::string(vectorized ? "four at a time" : "scalar") + (add_i ? ", end i" : "") + (add_j ? ", end j" : "");
      std::vector<double> force(3 * particles, 0.0);
      std::vector<double> energy(count);
      double sum = 0.25;
      // Two calls, the first ending inside a group of four.
      addSpringForcesOf(springs.data(), springs.data() + 10, x.data(), v.data(), force.data(), energy.data(), &sum,
                        add_i, add_j, vectorized);
      addSpringForcesOf(springs.data() + 10, springs.data() + count, x.data(), v.data(), force.data(),
                        energy.data() + 10, &sum, add_i, add_j, vectorized);
      for (int c = 0; c < 3 * particles; ++c)
        EXPECT_EQ(bits(force[c]), bits(expected[c])) << "particle " << c / 3 << " coordinate " << c % 3 << ", " << form;
      for (int s = 0; s < count; ++s)
        EXPECT_EQ(bits(energy[s]), bits(expected_energy[s])) << "spring " << s << ", " << form;
      EXPECT_EQ(bits(sum), bits(expected_sum)) << form;
    }
  }
}

TEST(Spring, EnergyNegativeGradientIsTheElasticForce)
{
  // Hand case: stretched by 3 with k = 10 stores 10 * 9 / 2 = 45 J.
  EXPECT_NEAR(springEnergy({0, 0, 0}, {3, 4, 0}, 2.0, 10.0), 45.0, 1e-12);
  EXPECT_EQ(springEnergy({1, 2, 3}, {3, 2, 3}, 2.0, 10.0), 0.0);

  std::mt19937_64 rng(45);
  for (double stretch : kStretches)
  {
    for (int trial = 0; trial < 20; ++trial)
    {
      const Config c = randomConfig(rng, stretch);
      const double step = 1e-6 * c.rest_length;
      Eigen::Vector3d gradient_i, gradient_j;
      for (int k = 0; k < 3; ++k)
      {
        Eigen::Vector3d plus = c.xi, minus = c.xi;
        plus[k] += step;
        minus[k] -= step;
        gradient_i[k] = (springEnergy(plus, c.xj, c.rest_length, c.stiffness) -
                         springEnergy(minus, c.xj, c.rest_length, c.stiffness)) /
                        (2.0 * step);
        plus = c.xj;
        minus = c.xj;
        plus[k] += step;
        minus[k] -= step;
        gradient_j[k] = (springEnergy(c.xi, plus, c.rest_length, c.stiffness) -
                         springEnergy(c.xi, minus, c.rest_length, c.stiffness)) /
                        (2.0 * step);
      }
      const Eigen::Vector3d elastic = springForce(c.xi, c.xj, c.vi, c.vj, c.rest_length, c.stiffness, 0.0);
      const double scale = c.stiffness * c.rest_length;
      EXPECT_LE((-gradient_i - elastic).norm(), 1e-6 * scale) << "stretch " << stretch;
      EXPECT_LE((-gradient_j + elastic).norm(), 1e-6 * scale) << "stretch " << stretch;
      EXPECT_GE(springEnergy(c.xi, c.xj, c.rest_length, c.stiffness), 0.0);
    }
  }
}

TEST(Spring, ClassAndNamesRoundTrip)
{
  for (SpringClass spring_class : {SpringClass::Stretch, SpringClass::Shear, SpringClass::Bend})
  {
    SpringClass parsed = SpringClass::Stretch;
    ASSERT_TRUE(parseSpringClass(toString(spring_class), parsed));
    EXPECT_EQ(parsed, spring_class);
  }
  SpringClass parsed = SpringClass::Bend;
  EXPECT_FALSE(parseSpringClass("twist", parsed));
}
