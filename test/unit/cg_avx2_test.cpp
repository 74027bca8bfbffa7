// The conjugate gradient's AVX2 passes (core/integrators/cg_avx2.h) against the arithmetic they
// stand for, written out here in the scalar order they promise, bit for bit; and the padded
// vectors they run on. The golden test TheConjugateGradientsScalarAndAvx2PassesGiveTheSameStates
// checks the passes inside whole simulations; these check each pass alone, on cases a scene may
// never produce (a pair with j = i, runs that add at one end only).

#include "particle_sim/core/integrators/cg_avx2.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "particle_sim/core/integrators/implicit_euler_solver.h"
#include "particle_sim/core/integrators/padded_vectors.h"

namespace core = particle_sim::core;

namespace
{
constexpr int kStride = core::PaddedVectors::kStride;

core::PaddedVectors randomVectors(int count, std::mt19937& random)
{
  std::uniform_real_distribution<double> uniform(-2.0, 2.0);
  core::PaddedVectors v;
  v.setZero(count);
  for (int i = 0; i < count; ++i)
    v.col(i) = Eigen::Vector3d(uniform(random), uniform(random), uniform(random));
  return v;
}

// Bit for bit, padding lanes included (they must stay zero).
void expectSameBits(const core::PaddedVectors& a, const core::PaddedVectors& b)
{
  ASSERT_EQ(a.count(), b.count());
  for (int k = 0; k < kStride * a.count(); ++k)
    EXPECT_EQ(a.data()[k], b.data()[k]) << "double " << k << " (particle " << k / kStride << ")";
}
}  // namespace

TEST(PaddedVectors, AreAlignedZeroedAndCopiedWhole)
{
  core::PaddedVectors v;
  v.setZero(5);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(v.data()) % 64, 0u);
  for (int k = 0; k < kStride * 5; ++k)
    EXPECT_EQ(v.data()[k], 0.0);
  v.col(3) = Eigen::Vector3d(1.0, 2.0, 3.0);
  EXPECT_EQ(v.data()[kStride * 3 + 2], 3.0);
  EXPECT_EQ(v.data()[kStride * 3 + 3], 0.0);
  const core::PaddedVectors copy = v;
  EXPECT_NE(copy.data(), v.data());
  expectSameBits(copy, v);
}

TEST(CgAvx2, PassesGiveTheScalarOrdersBits)
{
  if (!core::cg_avx2::available())
  {
    // Without AVX2 the solver must keep to its scalar passes, whatever it is asked.
    core::ImplicitEulerSolver::setUseAvx2(true);
    EXPECT_FALSE(core::ImplicitEulerSolver::useAvx2());
    return;
  }
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uniform(-3.0, 3.0);
  const int n = 37;

  // Pair product: runs of pairs sharing end i, one pair with j = i, and each kind of run.
  std::vector<std::array<int, 2>> ends = {{0, 1}, {0, 5}, {0, 0}, {2, 1}, {2, 3}, {4, 36}, {9, 8}, {9, 20}, {30, 2}};
  std::vector<std::array<double, 6>> cs(ends.size());
  for (auto& c : cs)
    for (double& value : c)
      value = uniform(random);
  const core::PaddedVectors p = randomVectors(n, random);
  for (const auto& [add_i, add_j] : std::vector<std::pair<bool, bool>>{{true, true}, {true, false}, {false, true}})
  {
    core::PaddedVectors wide = randomVectors(n, random);
    core::PaddedVectors expected = wide;
    core::cg_avx2::addPairProducts(add_i, add_j, ends.data(), cs.data(), 0, static_cast<int>(ends.size()), p.data(),
                                   wide.data());
    for (std::size_t k = 0; k < ends.size(); ++k)
    {
      const auto& c = cs[k];
      const int i = ends[k][0], j = ends[k][1];
      const double d0 = p.col(j)(0) - p.col(i)(0), d1 = p.col(j)(1) - p.col(i)(1), d2 = p.col(j)(2) - p.col(i)(2);
      const Eigen::Vector3d w((c[0] * d0 + c[1] * d1) + c[2] * d2, (c[1] * d0 + c[3] * d1) + c[4] * d2,
                              (c[2] * d0 + c[4] * d1) + c[5] * d2);
      if (add_i) expected.col(i) += w;
      if (add_j) expected.col(j) -= w;
    }
    SCOPED_TRACE(testing::Message() << "add_i " << add_i << ", add_j " << add_j);
    expectSameBits(wide, expected);
  }

  // The product's diagonal, the curvature with pinned rows, the update and the direction.
  std::vector<double> scale(n), inverse_mass(n);
  std::vector<Eigen::Matrix3d> inverse_diagonal(n);
  std::vector<char> pinned(n, 0);
  for (int i = 0; i < n; ++i)
  {
    scale[i] = uniform(random);
    inverse_mass[i] = 1.0 + uniform(random) * uniform(random);
    inverse_diagonal[i] = Eigen::Matrix3d::Random();
    pinned[i] = i % 7 == 3;
  }
  core::PaddedVectors scaled, expected_scaled;
  scaled.setZero(n);
  expected_scaled.setZero(n);
  core::cg_avx2::scaleRows(scale.data(), 0, n, p.data(), scaled.data());
  for (int i = 0; i < n; ++i)
    expected_scaled.col(i) = scale[i] * p.col(i);
  expectSameBits(scaled, expected_scaled);

  core::PaddedVectors product = randomVectors(n, random), expected_product = product;
  const double curvature = core::cg_avx2::curvature(pinned.data(), 0, n, p.data(), product.data());
  Eigen::Vector3d sums = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i)
  {
    if (pinned[i]) expected_product.col(i).setZero();
    sums += p.col(i).cwiseProduct(expected_product.col(i));
  }
  expectSameBits(product, expected_product);
  EXPECT_EQ(curvature, (sums(0) + sums(1)) + sums(2));

  const double alpha = 0.37;
  core::PaddedVectors delta_v = randomVectors(n, random), residual = randomVectors(n, random), preconditioned;
  preconditioned.setZero(n);
  core::PaddedVectors expected_delta_v = delta_v, expected_residual = residual,
                      expected_preconditioned = preconditioned;
  const core::cg_avx2::UpdateSums got =
      core::cg_avx2::updateIterate(0, n, alpha, inverse_mass.data(), inverse_diagonal.data(), p.data(), product.data(),
                                   delta_v.data(), residual.data(), preconditioned.data());
  Eigen::Vector3d rz = Eigen::Vector3d::Zero(), r2 = Eigen::Vector3d::Zero(), weighted = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i)
  {
    expected_delta_v.col(i) += alpha * p.col(i);
    const Eigen::Vector3d r = expected_residual.col(i) - alpha * product.col(i);
    expected_residual.col(i) = r;
    // z = D⁻¹ r in the order Eigen evaluates a 3x3 block times a 3-vector, which the scalar pass uses.
    const Eigen::Matrix3d& m = inverse_diagonal[i];
    const Eigen::Vector3d z((m(0, 0) * r(0) + m(0, 1) * r(1)) + m(0, 2) * r(2),
                            (m(1, 0) * r(0) + m(1, 1) * r(1)) + m(1, 2) * r(2),
                            m(2, 0) * r(0) + (m(2, 1) * r(1) + m(2, 2) * r(2)));
    ASSERT_EQ(z, (m * r).eval()) << "Eigen's order of a block product changed: the scalar pass's too";
    expected_preconditioned.col(i) = z;
    rz += r.cwiseProduct(z);
    r2 += r.cwiseAbs2();
    weighted += inverse_mass[i] * r.cwiseAbs2();
  }
  expectSameBits(delta_v, expected_delta_v);
  expectSameBits(residual, expected_residual);
  expectSameBits(preconditioned, expected_preconditioned);
  EXPECT_EQ(got.preconditioned, (rz(0) + rz(1)) + rz(2));
  EXPECT_EQ(got.squared, (r2(0) + r2(1)) + r2(2));
  EXPECT_EQ(got.weighted, (weighted(0) + weighted(1)) + weighted(2));

  const double beta = 0.61;
  core::PaddedVectors direction = randomVectors(n, random), expected_direction = direction;
  core::cg_avx2::updateDirection(pinned.data(), 0, n, beta, preconditioned.data(), direction.data());
  for (int i = 0; i < n; ++i)
  {
    expected_direction.col(i) = preconditioned.col(i) + beta * expected_direction.col(i);
    if (pinned[i]) expected_direction.col(i).setZero();
  }
  expectSameBits(direction, expected_direction);
}
