// Baraff–Witkin conditions: every gradient and Hessian against central finite differences on
// random deformed triangles and triangle pairs (near-degenerate ones included); zero force at
// rest; no force and no energy change under rigid motion.

#include "particle_sim/core/baraff_witkin.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <random>

using namespace particle_sim::core;

namespace
{
constexpr double kStep = 1e-6;  // finite-difference step [m]

// Central differences of a scalar function of a 3 x N matrix, as a 3N vector (corner-major).
template <int N>
Eigen::Matrix<double, 3 * N, 1> numericGradient(const std::function<double(const Eigen::Matrix<double, 3, N>&)>& f,
                                                const Eigen::Matrix<double, 3, N>& x)
{
  Eigen::Matrix<double, 3 * N, 1> g;
  for (int m = 0; m < N; ++m)
    for (int a = 0; a < 3; ++a)
    {
      Eigen::Matrix<double, 3, N> plus = x, minus = x;
      plus(a, m) += kStep;
      minus(a, m) -= kStep;
      g[3 * m + a] = (f(plus) - f(minus)) / (2.0 * kStep);
    }
  return g;
}

// Central differences of a gradient function, as a 3N x 3N matrix.
template <int N>
Eigen::Matrix<double, 3 * N, 3 * N> numericHessian(
    const std::function<Eigen::Matrix<double, 3 * N, 1>(const Eigen::Matrix<double, 3, N>&)>& gradient,
    const Eigen::Matrix<double, 3, N>& x)
{
  Eigen::Matrix<double, 3 * N, 3 * N> h;
  for (int m = 0; m < N; ++m)
    for (int a = 0; a < 3; ++a)
    {
      Eigen::Matrix<double, 3, N> plus = x, minus = x;
      plus(a, m) += kStep;
      minus(a, m) -= kStep;
      h.col(3 * m + a) = (gradient(plus) - gradient(minus)) / (2.0 * kStep);
    }
  return h;
}

// Relative difference, scaled by the larger magnitude (and at least 1).
template <typename A, typename B>
double relativeError(const A& a, const B& b)
{
  return (a - b).norm() / std::max(1.0, std::max(a.norm(), b.norm()));
}

struct RandomTriangle
{
  BwTriangle rest;
  Eigen::Matrix3d x;
};

// A rest triangle in (u, v) and a randomly deformed placement of it; `thinness` squashes the rest
// triangle (near-degenerate as it goes to 0).
RandomTriangle randomTriangle(std::mt19937_64& rng, double thinness = 1.0)
{
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  RandomTriangle t;
  const Eigen::Vector2d a(0, 0), b(0.5 + 0.5 * std::abs(uniform(rng)), 0.1 * uniform(rng)),
      c(0.3 * uniform(rng), thinness * (0.3 + 0.5 * std::abs(uniform(rng))));
  EXPECT_TRUE(makeBwTriangle(0, 1, 2, a, b, c, t.rest));
  for (int m = 0; m < 3; ++m)
  {
    const Eigen::Vector2d uv = m == 0 ? a : m == 1 ? b : c;
    t.x.col(m) = Eigen::Vector3d(uv.x(), uv.y(), 0.0) + 0.3 * Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng));
  }
  return t;
}
}  // namespace

TEST(BaraffWitkin, TriangleMapReproducesTheRestEdgesAndArea)
{
  BwTriangle t;
  ASSERT_TRUE(makeBwTriangle(0, 1, 2, {0, 0}, {2, 0}, {0, 1}, t));
  EXPECT_DOUBLE_EQ(t.area, 1.0);
  // At rest (positions = (u, v, 0)) w_u = (1, 0, 0) and w_v = (0, 1, 0).
  const Eigen::Matrix3d x = (Eigen::Matrix3d() << 0, 2, 0, 0, 0, 1, 0, 0, 0).finished();
  Eigen::Vector3d wu = Eigen::Vector3d::Zero(), wv = Eigen::Vector3d::Zero();
  for (int m = 0; m < 3; ++m)
  {
    wu += t.dwu[m] * x.col(m);
    wv += t.dwv[m] * x.col(m);
  }
  EXPECT_TRUE(wu.isApprox(Eigen::Vector3d::UnitX()));
  EXPECT_TRUE(wv.isApprox(Eigen::Vector3d::UnitY()));
  BwTriangle degenerate;
  EXPECT_FALSE(makeBwTriangle(0, 1, 2, {0, 0}, {1, 1}, {2, 2}, degenerate));
}

TEST(BaraffWitkin, StretchGradientsAndHessiansMatchFiniteDifferences)
{
  std::mt19937_64 rng(21);
  for (int trial = 0; trial < 60; ++trial)
  {
    const RandomTriangle t = randomTriangle(rng, trial < 50 ? 1.0 : 1e-3);
    Eigen::Vector2d c;
    std::array<Gradient9, 2> g;
    std::array<Hessian9, 2> h;
    stretchCondition(t.rest, t.x, 1.0, 0.9, c, g, &h);
    for (int d = 0; d < 2; ++d)
    {
      const auto value = [&](const Eigen::Matrix3d& y) {
        Eigen::Vector2d cy;
        std::array<Gradient9, 2> gy;
        stretchCondition(t.rest, y, 1.0, 0.9, cy, gy);
        return cy[d];
      };
      const auto gradient = [&](const Eigen::Matrix3d& y) {
        Eigen::Vector2d cy;
        std::array<Gradient9, 2> gy;
        stretchCondition(t.rest, y, 1.0, 0.9, cy, gy);
        return Gradient9(gy[d]);
      };
      EXPECT_LT(relativeError(g[d], numericGradient<3>(value, t.x)), 1e-6) << "trial " << trial << " d " << d;
      EXPECT_LT(relativeError(h[d], numericHessian<3>(gradient, t.x)), 1e-5) << "trial " << trial << " d " << d;
    }
  }
}

TEST(BaraffWitkin, ShearGradientAndHessianMatchFiniteDifferences)
{
  std::mt19937_64 rng(22);
  for (int trial = 0; trial < 60; ++trial)
  {
    const RandomTriangle t = randomTriangle(rng, trial < 50 ? 1.0 : 1e-3);
    double c;
    Gradient9 g;
    Hessian9 h;
    shearCondition(t.rest, t.x, c, g, &h);
    const auto value = [&](const Eigen::Matrix3d& y) {
      double cy;
      Gradient9 gy;
      shearCondition(t.rest, y, cy, gy);
      return cy;
    };
    const auto gradient = [&](const Eigen::Matrix3d& y) {
      double cy;
      Gradient9 gy;
      shearCondition(t.rest, y, cy, gy);
      return gy;
    };
    EXPECT_LT(relativeError(g, numericGradient<3>(value, t.x)), 1e-6) << "trial " << trial;
    EXPECT_LT(relativeError(h, numericHessian<3>(gradient, t.x)), 1e-5) << "trial " << trial;
  }
}

TEST(BaraffWitkin, BendGradientAndHessianMatchFiniteDifferences)
{
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 200 && checked < 60; ++trial)
  {
    // Two triangles sharing the edge x1 -> x2, folded by a random angle, then randomly perturbed;
    // the last ones are slivers (x0 close to the edge).
    Eigen::Matrix<double, 3, 4> x;
    const double sliver = checked < 50 ? 1.0 : 0.02;
    x.col(1) = Eigen::Vector3d(0, 0, 0);
    x.col(2) = Eigen::Vector3d(1, 0, 0);
    x.col(0) = Eigen::Vector3d(0.5 + 0.3 * uniform(rng), -sliver * (0.5 + 0.4 * std::abs(uniform(rng))), 0);
    const double fold = 2.5 * uniform(rng);
    x.col(3) = Eigen::Vector3d(0.5 + 0.3 * uniform(rng), 0.7 * std::cos(fold), 0.7 * std::sin(fold));
    x += 0.1 * Eigen::Matrix<double, 3, 4>::Random();
    if (std::abs(std::abs(dihedralAngle(x)) - M_PI) < 0.2) continue;  // keep away from the ±π cut
    ++checked;
    BwBend bend;
    bend.v = {0, 1, 2, 3};
    double c;
    Gradient12 g;
    Hessian12 h;
    bendCondition(bend, x, c, g, &h);
    const auto value = [&](const Eigen::Matrix<double, 3, 4>& y) { return dihedralAngle(y); };
    const auto gradient = [&](const Eigen::Matrix<double, 3, 4>& y) {
      double cy;
      Gradient12 gy;
      bendCondition(bend, y, cy, gy);
      return gy;
    };
    EXPECT_LT(relativeError(g, numericGradient<4>(value, x)), 1e-5) << "trial " << trial;
    EXPECT_LT(relativeError(h, numericHessian<4>(gradient, x)), 1e-4) << "trial " << trial;
  }
  EXPECT_EQ(checked, 60);
}

TEST(BaraffWitkin, RestStateHasZeroConditionsAndRigidMotionChangesNothing)
{
  std::mt19937_64 rng(24);
  const RandomTriangle t = randomTriangle(rng);
  // At rest (positions = (u, v, 0) of the rest triangle): no stretch, no shear.
  Eigen::Matrix3d rest;
  BwTriangle known;
  ASSERT_TRUE(makeBwTriangle(0, 1, 2, {0.1, 0.2}, {1.3, 0.1}, {0.4, 0.9}, known));
  rest << 0.1, 1.3, 0.4, 0.2, 0.1, 0.9, 0, 0, 0;
  Eigen::Vector2d c;
  std::array<Gradient9, 2> g;
  stretchCondition(known, rest, 1.0, 1.0, c, g);
  EXPECT_NEAR(c.norm(), 0.0, 1e-14);
  double shear;
  Gradient9 gs;
  shearCondition(known, rest, shear, gs);
  EXPECT_NEAR(shear, 0.0, 1e-14);

  // A rigid motion (rotation + translation) of any deformed state leaves every condition as it is.
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d shift(0.3, -2.0, 5.0);
  const Eigen::Matrix3d moved = (rotation * t.x).colwise() + shift;
  Eigen::Vector2d c1, c2;
  stretchCondition(t.rest, t.x, 1.0, 1.0, c1, g);
  stretchCondition(t.rest, moved, 1.0, 1.0, c2, g);
  EXPECT_NEAR((c1 - c2).norm(), 0.0, 1e-12);
  double s1, s2;
  shearCondition(t.rest, t.x, s1, gs);
  shearCondition(t.rest, moved, s2, gs);
  EXPECT_NEAR(s1, s2, 1e-12);
  Eigen::Matrix<double, 3, 4> pair = Eigen::Matrix<double, 3, 4>::Random();
  const Eigen::Matrix<double, 3, 4> moved_pair = (rotation * pair).colwise() + shift;
  EXPECT_NEAR(dihedralAngle(pair), dihedralAngle(moved_pair), 1e-12);
  // A flat pair has angle 0.
  Eigen::Matrix<double, 3, 4> flat;
  flat << 0.5, 0, 1, 0.5, -1, 0, 0, 1, 0, 0, 0, 0;
  EXPECT_NEAR(dihedralAngle(flat), 0.0, 1e-15);
}
