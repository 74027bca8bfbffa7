// Smoothed-aggregation multigrid (SmoothedAggregation), the preconditioner of the linear solver
// `multigrid`: its tentative prolongator rebuilds each level's rigid-body modes from the next level's
// (Q R = B, aggregate by aggregate); its cycle is the symmetric positive definite operator the
// conjugate gradient needs, zero on pinned rows; and the implicit step it preconditions reaches the
// direct solve's answer, in iterations that grow far slower with the size of the cloth than block
// Jacobi's, which double with its side.
#include "particle_sim/core/integrators/smoothed_aggregation.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/environment.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/worker_pool.h"

using namespace particle_sim::core;

namespace
{
// The implicit system of an n x n sheet of springs crumpled at random (structural and shear
// springs, and with `bend` bend springs two particles long, ten times weaker): per spring along
// unit d, C = a d dᵀ + b I with a, b > 0 (the definite stiffness a stretched spring's h² ∂f/∂x
// gives), A_ii += C, A_jj += C, A_ij = A_ji = −C, and masses on the diagonal; the two corners of
// the first row pinned. Blocks in the solver's pattern order; `springs` lists (i, j) of the
// structural and shear springs, `bends` of the bend springs.
struct SheetSystem
{
  int particles = 0;
  std::vector<int> row_start, column;
  std::vector<Eigen::Matrix3d> blocks;
  Eigen::Matrix3Xd x;
  std::vector<char> pinned;
  std::vector<std::pair<int, int>> springs, bends;
};

SheetSystem crumpledSheet(int n, unsigned seed, bool bend = false)
{
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  SheetSystem s;
  s.particles = n * n;
  s.x.resize(3, s.particles);
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < n; ++a)
      s.x.col(b * n + a) = Eigen::Vector3d(a + jitter(random), b + jitter(random), jitter(random)) / (n - 1);
  std::vector<std::pair<int, int>>& springs = s.springs;
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < n; ++a)
    {
      const int i = b * n + a;
      if (a + 1 < n) springs.emplace_back(i, i + 1);
      if (b + 1 < n) springs.emplace_back(i, i + n);
      if (a + 1 < n && b + 1 < n) springs.emplace_back(i, i + n + 1);
      if (bend && a + 2 < n) s.bends.emplace_back(i, i + 2);
      if (bend && b + 2 < n) s.bends.emplace_back(i, i + 2 * n);
    }
  std::vector<std::vector<int>> columns(s.particles);
  for (int i = 0; i < s.particles; ++i)
    columns[i].push_back(i);
  for (const auto& [i, j] : springs)
  {
    columns[i].push_back(j);
    columns[j].push_back(i);
  }
  for (const auto& [i, j] : s.bends)
  {
    columns[i].push_back(j);
    columns[j].push_back(i);
  }
  s.row_start.push_back(0);
  for (std::vector<int>& c : columns)
  {
    std::sort(c.begin(), c.end());
    s.column.insert(s.column.end(), c.begin(), c.end());
    s.row_start.push_back(static_cast<int>(s.column.size()));
  }
  auto block = [&](int i, int j) -> Eigen::Matrix3d& {
    const auto first = s.column.begin() + s.row_start[i], last = s.column.begin() + s.row_start[i + 1];
    return s.blocks[std::lower_bound(first, last, j) - s.column.begin()];
  };
  s.blocks.assign(s.column.size(), Eigen::Matrix3d::Zero());
  const double mass = 1.0 / s.particles;
  for (int i = 0; i < s.particles; ++i)
    block(i, i) = mass * Eigen::Matrix3d::Identity();
  std::uniform_real_distribution<double> factor(0.5, 2.0);
  auto addSprings = [&](const std::vector<std::pair<int, int>>& list, double scale) {
    for (const auto& [i, j] : list)
    {
      const Eigen::Vector3d d = (s.x.col(j) - s.x.col(i)).normalized();
      const Eigen::Matrix3d c =
          scale * (0.3 * factor(random) * d * d.transpose() + 0.01 * factor(random) * Eigen::Matrix3d::Identity());
      block(i, i) += c;
      block(j, j) += c;
      block(i, j) -= c;
      block(j, i) -= c;
    }
  };
  addSprings(springs, 1.0);
  addSprings(s.bends, 0.1);
  s.pinned.assign(s.particles, 0);
  s.pinned[0] = s.pinned[n - 1] = 1;
  return s;
}

Eigen::Matrix3Xd randomFiltered(int particles, const std::vector<char>& pinned, unsigned seed)
{
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal;
  Eigen::Matrix3Xd r(3, particles);
  for (int i = 0; i < particles; ++i)
    r.col(i) = pinned[i] ? Eigen::Vector3d::Zero() : Eigen::Vector3d(normal(random), normal(random), normal(random));
  return r;
}

double dot(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b)
{
  return a.cwiseProduct(b).sum();
}

// A block-sparse matrix of the multigrid as an Eigen sparse matrix.
Eigen::SparseMatrix<double> toSparse(const SmoothedAggregation::BlockRows& m)
{
  std::vector<Eigen::Triplet<double>> entries;
  const int rb = m.row_block, cb = m.column_block;
  for (int row = 0; row < m.rows; ++row)
    for (int k = m.start[row]; k < m.start[row + 1]; ++k)
      for (int r = 0; r < rb; ++r)
        for (int c = 0; c < cb; ++c)
          entries.emplace_back(rb * row + r, cb * m.column[k] + c, m.values[rb * cb * k + cb * r + c]);
  Eigen::SparseMatrix<double> sparse(rb * m.rows, cb * m.columns);
  sparse.setFromTriplets(entries.begin(), entries.end());
  return sparse;
}
}  // namespace

TEST(SmoothedAggregation, CoarsensTheSheetAndRebuildsEachLevelsModesFromTheNext)
{
  const SheetSystem s = crumpledSheet(40, 1);
  SmoothedAggregation multigrid;
  multigrid.setPattern(s.particles, s.row_start, s.column);
  ASSERT_TRUE(multigrid.setup(s.blocks, s.x, s.pinned));
  // 1600 particles: aggregates of about 3 x 3 (a particle and its neighbours), down to at most
  // kCoarsestNodes, each level several times smaller than the one above.
  ASSERT_GE(multigrid.levels(), 3);
  EXPECT_EQ(multigrid.nodes(0), s.particles);
  EXPECT_LE(multigrid.nodes(multigrid.levels() - 1), SmoothedAggregation::kCoarsestNodes);
  for (int level = 1; level < multigrid.levels(); ++level)
    EXPECT_LT(4 * multigrid.nodes(level), multigrid.nodes(level - 1)) << "level " << level;
  // The finest modes are the rigid-body motions: translations, and rotations about an axis through
  // each aggregate's centroid, so that mode 3 (about x) moves no particle along x and is
  // perpendicular to x − c; zero on the pinned particles.
  const Eigen::VectorXd rotation_x = multigrid.modes(0, 3);
  for (int i = 0; i < s.particles; ++i)
  {
    EXPECT_EQ(rotation_x[3 * i], 0.0);
    if (s.pinned[i])
    {
      EXPECT_EQ(multigrid.modes(0, 0).segment<3>(3 * i).norm(), 0.0);
    }
  }
  // Q R = B on every level: the tentative prolongator times the next level's modes gives this level's
  // modes back, to rounding.
  for (int level = 0; level + 1 < multigrid.levels(); ++level)
    for (int mode = 0; mode < SmoothedAggregation::kModes; ++mode)
    {
      const Eigen::VectorXd modes = multigrid.modes(level, mode);
      const Eigen::VectorXd rebuilt = multigrid.tentativeTimesCoarseModes(level, mode);
      EXPECT_LE((rebuilt - modes).norm(), 1e-12 * std::max(1.0, modes.norm()))
          << "level " << level << ", mode " << mode;
    }
}

TEST(SmoothedAggregation, TheCycleIsSymmetricPositiveDefiniteAndZeroOnPinnedRows)
{
  // The smaller sheets' hierarchies have few levels, where a coarse level's next may be the coarsest
  // (visited once); at 64² there are at least four, so the second level is visited twice
  // (visitNext()), and the test covers the W-cycle's second visit.
  for (const auto& [n, bend] :
       {std::pair{4, false}, {17, false}, {40, false}, {17, true}, {40, true}, {64, false}, {64, true}})
  {
    SCOPED_TRACE("n = " + std::to_string(n) + (bend ? ", bend springs" : ""));
    const SheetSystem s = crumpledSheet(n, 2, bend);
    SmoothedAggregation multigrid;
    multigrid.setPattern(s.particles, s.row_start, s.column);
    ASSERT_TRUE(multigrid.setup(s.blocks, s.x, s.pinned));
    if (n == 64)
    {
      ASSERT_GE(multigrid.levels(), 4);
    }
    Eigen::Matrix3Xd zu(3, s.particles), zv(3, s.particles);
    for (unsigned trial = 0; trial < 4; ++trial)
    {
      const Eigen::Matrix3Xd u = randomFiltered(s.particles, s.pinned, 10 + trial);
      const Eigen::Matrix3Xd v = randomFiltered(s.particles, s.pinned, 20 + trial);
      multigrid.apply(u, zu);
      multigrid.apply(v, zv);
      // uᵀ M⁻¹ v = vᵀ M⁻¹ u, and uᵀ M⁻¹ u > 0.
      const double uv = dot(u, zv), vu = dot(v, zu);
      EXPECT_NEAR(uv, vu, 1e-10 * std::max(std::abs(uv), dot(u, zu))) << "trial " << trial;
      EXPECT_GT(dot(u, zu), 0.0) << "trial " << trial;
      for (int i = 0; i < s.particles; ++i)
      {
        if (s.pinned[i])
        {
          EXPECT_EQ(zu.col(i).norm(), 0.0) << "pinned particle " << i;
        }
      }
    }
  }
}

// The smoother's steps (chebyshevSteps()) against the closed form of Chebyshev's polynomials: on the
// scalar system t x = t (an eigenvector of D⁻¹ A with eigenvalue t), from x = 0, the error 1 − x after
// the steps is T_k((θ − t) / δ) / T_k(θ / δ), T_k(y) = cos(k acos y) for |y| ≤ 1 and
// sign(y)^k cosh(k acosh |y|) beyond. So it is at most 1 / T_k(θ / δ) in size on [u / α, u], at most
// 1 from 0 up to 2 θ = u (1 + 1 / α), and above 1 past it: the reach that setupLevel() sets equal to
// damped Jacobi's.
TEST(SmoothedAggregation, TheSmoothersStepsScaleTheErrorByTheShiftedChebyshevPolynomial)
{
  constexpr int k = SmoothedAggregation::kSmoothingSweeps;
  auto chebyshev = [](double y) {
    return std::abs(y) <= 1.0 ? std::cos(k * std::acos(y))
                              : std::pow(y < 0.0 ? -1.0 : 1.0, k) * std::cosh(k * std::acosh(std::abs(y)));
  };
  for (const double upper : {0.7, 1.0, 3.5})
  {
    SCOPED_TRACE("upper " + std::to_string(upper));
    const SmoothedAggregation::ChebyshevSteps steps = SmoothedAggregation::chebyshevSteps(upper);
    const double lower = upper / SmoothedAggregation::kChebyshevRange;
    const double theta = 0.5 * (upper + lower), delta = 0.5 * (upper - lower);
    auto errorAfterSteps = [&](double t) {
      double x = 0.0, step = 0.0;
      for (int s = 0; s < k; ++s)
      {
        step = steps.keep[s] * step + steps.scale[s] * t * (1.0 - x);
        x += step;
      }
      return 1.0 - x;
    };
    const double bound = 1.0 / chebyshev(theta / delta);
    EXPECT_LT(bound, 0.6);  // α = 10, k = 2: 1 / T_2(11 / 9) = 0.503
    for (int sample = 0; sample <= 400; ++sample)
    {
      const double t = 2.4 * theta * sample / 400.0;
      const double error = errorAfterSteps(t);
      EXPECT_NEAR(error, chebyshev((theta - t) / delta) / chebyshev(theta / delta), 1e-12) << "t = " << t;
      if (t >= lower && t <= upper)
      {
        EXPECT_LE(std::abs(error), bound + 1e-12) << "t = " << t;
      }
      if (t <= 2.0 * theta)
      {
        EXPECT_LE(std::abs(error), 1.0 + 1e-12) << "t = " << t;
      }
    }
    EXPECT_GT(std::abs(errorAfterSteps(2.02 * theta)), 1.0);
  }
}

// The preconditioned operator B A (B the cycle, A the filtered system on the free rows) has its
// eigenvalues in (0, 1]: I − B A is the cycle's error operator, S (I − P B_c Pᵀ A) S with S the
// smoother's polynomial, self-adjoint and positive semidefinite in A's inner product, and below 1
// while the smoother contracts. The eigenvalues of B A are those of Lᵀ B L with A = L Lᵀ; dense, on
// sheets of three levels.
TEST(SmoothedAggregation, ThePreconditionedOperatorsEigenvaluesLieBetweenZeroAndOne)
{
  for (const auto& [n, bend] : {std::pair{17, false}, {17, true}, {24, true}})
  {
    SCOPED_TRACE("n = " + std::to_string(n) + (bend ? ", bend springs" : ""));
    const SheetSystem s = crumpledSheet(n, 3, bend);
    SmoothedAggregation multigrid;
    multigrid.setPattern(s.particles, s.row_start, s.column);
    ASSERT_TRUE(multigrid.setup(s.blocks, s.x, s.pinned));
    ASSERT_GE(multigrid.levels(), 3);
    std::vector<int> free;
    for (int i = 0; i < s.particles; ++i)
      for (int r = 0; r < 3 && !s.pinned[i]; ++r)
        free.push_back(3 * i + r);
    const int m = static_cast<int>(free.size());
    const Eigen::MatrixXd whole(toSparse(multigrid.matrixOf(0)));
    Eigen::MatrixXd a(m, m), b(m, m);
    Eigen::Matrix3Xd unit = Eigen::Matrix3Xd::Zero(3, s.particles), z(3, s.particles);
    for (int c = 0; c < m; ++c)
    {
      unit(free[c]) = 1.0;
      multigrid.apply(unit, z);
      unit(free[c]) = 0.0;
      for (int r = 0; r < m; ++r)
      {
        b(r, c) = z(free[r]);
        a(r, c) = whole(free[r], free[c]);
      }
    }
    EXPECT_LT((b - b.transpose()).norm(), 1e-10 * b.norm());
    const Eigen::LLT<Eigen::MatrixXd> cholesky(a);
    ASSERT_EQ(cholesky.info(), Eigen::Success) << "the filtered system is not positive definite";
    const Eigen::MatrixXd lower = cholesky.matrixL();
    const Eigen::MatrixXd symmetric = lower.transpose() * (0.5 * (b + b.transpose())) * lower;
    const Eigen::VectorXd eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(symmetric).eigenvalues();
    EXPECT_GT(eigenvalues.minCoeff(), 0.0);
    EXPECT_LE(eigenvalues.maxCoeff(), 1.0 + 1e-9);
    // The condition number CG sees: small, or the cycle would not be worth its cost. (Tried: with the
    // smoother's interval scaled by 0.6, so that it stops contracting below ρ(D⁻¹ A), the eigenvalues
    // go down to −1.2, the cycle indefinite, which TheCycleIsSymmetricPositiveDefinite…, on random
    // vectors, misses.)
    EXPECT_LT(eigenvalues.maxCoeff() / eigenvalues.minCoeff(), 5.0);  // measured 2.1 to 2.7
  }
}

// Each coarse level's matrix is the Galerkin product Pᵀ A P of the level above and its smoothed
// prolongator: the engine sums it by rows of A_c from a whole copy of A P, Eigen's sparse products
// here give it to rounding (a mode that pins left empty would have a zero row and column, and its
// diagonal set to one). The setup's passes shared with the threads (the Galerkin product by rows of
// A_c among them) give every level's matrix and prolongator the same bits at two threads as at one.
// A 64 x 64 sheet with bend springs: two chunks of the finest level, about 450 aggregates below it.
TEST(SmoothedAggregation, EachCoarseMatrixIsTheGalerkinProductWithTheSameBitsAtTwoThreads)
{
  const SheetSystem s = crumpledSheet(64, 3, true);
  SmoothedAggregation one, two;
  WorkerPool pool(2);
  two.setWorkers(&pool);
  for (SmoothedAggregation* multigrid : {&one, &two})
  {
    multigrid->setPattern(s.particles, s.row_start, s.column);
    ASSERT_TRUE(multigrid->setup(s.blocks, s.x, s.pinned));
    ASSERT_TRUE(multigrid->setup(s.blocks, s.x, s.pinned));  // the numbers again, on the plans laid out
  }
  ASSERT_GE(one.levels(), 3);
  for (int level = 0; level + 1 < one.levels(); ++level)
  {
    const Eigen::SparseMatrix<double> a = toSparse(one.matrixOf(level));
    const Eigen::SparseMatrix<double> p = toSparse(one.prolongatorOf(level));
    Eigen::SparseMatrix<double> expected = Eigen::SparseMatrix<double>(p.transpose()) * a * p;
    for (int d = 0; d < expected.rows(); ++d)
      if (expected.coeff(d, d) == 0.0) expected.coeffRef(d, d) = 1.0;
    const Eigen::SparseMatrix<double> difference = toSparse(one.matrixOf(level + 1)) - expected;
    double largest = 0.0, error = 0.0;
    for (int k = 0; k < expected.nonZeros(); ++k)
      largest = std::max(largest, std::abs(expected.valuePtr()[k]));
    for (int k = 0; k < difference.nonZeros(); ++k)
      error = std::max(error, std::abs(difference.valuePtr()[k]));
    EXPECT_GT(largest, 0.0);
    EXPECT_LE(error, 1e-13 * largest) << "level " << level + 1;
  }
  for (int level = 0; level < one.levels(); ++level)
  {
    EXPECT_EQ(one.matrixOf(level).values, two.matrixOf(level).values) << "level " << level;
    if (level + 1 < one.levels())
    {
      EXPECT_EQ(one.prolongatorOf(level).values, two.prolongatorOf(level).values) << "level " << level;
    }
  }
  EXPECT_GT(pool.sharedLoops(), 0u);
}

// The finest level's product may come from outside (the implicit solver's product by the springs'
// pairs): the cycle and multiplyFinest() then take it, once a smoothing sweep of a cycle and once a product, and give
// what the hierarchy's own blocks give, to rounding. The product here is the sheet's filtered matrix
// as an Eigen sparse matrix, its pinned rows zero (x is zero there).
TEST(SmoothedAggregation, AFinestProductFromOutsideGivesTheBlocksCycle)
{
  const SheetSystem s = crumpledSheet(40, 4, true);
  SmoothedAggregation multigrid;
  multigrid.setPattern(s.particles, s.row_start, s.column);
  ASSERT_TRUE(multigrid.setup(s.blocks, s.x, s.pinned));
  Eigen::SparseMatrix<double> filtered = toSparse(multigrid.matrixOf(0));
  for (int k = 0; k < filtered.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator entry(filtered, k); entry; ++entry)
      if (s.pinned[entry.row() / 3]) entry.valueRef() = 0.0;
  int calls = 0;
  multigrid.setFinestProduct([&](const double* x, double* y) {
    ++calls;
    Eigen::Map<Eigen::VectorXd>(y, 3 * s.particles) = filtered * Eigen::Map<const Eigen::VectorXd>(x, 3 * s.particles);
  });
  Eigen::Matrix3Xd by_blocks(3, s.particles), outside(3, s.particles);
  for (unsigned trial = 0; trial < 3; ++trial)
  {
    const Eigen::Matrix3Xd r = randomFiltered(s.particles, s.pinned, 30 + trial);
    multigrid.useFinestProduct(false);
    multigrid.apply(r, by_blocks);
    multigrid.useFinestProduct(true);
    calls = 0;
    multigrid.apply(r, outside);
    // One residual a smoothing sweep, before the coarse correction and after it.
    EXPECT_EQ(calls, 2 * SmoothedAggregation::kSmoothingSweeps) << "trial " << trial;
    EXPECT_LE((outside - by_blocks).cwiseAbs().maxCoeff(), 1e-12 * by_blocks.cwiseAbs().maxCoeff())
        << "trial " << trial;
    EXPECT_GT(by_blocks.cwiseAbs().maxCoeff(), 0.0);

    multigrid.useFinestProduct(false);
    multigrid.multiplyFinest(r, by_blocks);
    multigrid.useFinestProduct(true);
    multigrid.multiplyFinest(r, outside);
    EXPECT_EQ(calls, 2 * SmoothedAggregation::kSmoothingSweeps + 1) << "trial " << trial;
    EXPECT_LE((outside - by_blocks).cwiseAbs().maxCoeff(), 1e-12 * by_blocks.cwiseAbs().maxCoeff())
        << "trial " << trial;
  }
}

// The implicit solver hands its kept pairs to setup() beside blocks whose off-diagonal blocks are
// zero (FinestPairs) instead of adding them to its blocks first: every level's matrix and prolongator,
// and a cycle, are then the same bits as from the blocks with the pairs added to them in their
// order (the solver's movePairsIntoBlocks()). Each spring's C here is its off-diagonal block of the
// sheet made symmetric bit for bit (its lower triangle), as the solver's are; the pinned corners are
// filtered.
TEST(SmoothedAggregation, PairsBesideTheBlocksGiveTheSameHierarchyAsPairsInThem)
{
  const SheetSystem s = crumpledSheet(40, 5, true);
  auto blockIndex = [&](int i, int j) {
    const auto first = s.column.begin() + s.row_start[i], last = s.column.begin() + s.row_start[i + 1];
    return static_cast<int>(std::lower_bound(first, last, j) - s.column.begin());
  };
  std::vector<std::array<int, 2>> ends, blocks;
  std::vector<std::array<double, 6>> cs;
  std::vector<Eigen::Matrix3d> diagonal_only = s.blocks;
  for (const auto* list : {&s.springs, &s.bends})
    for (const auto& [i, j] : *list)
    {
      const Eigen::Matrix3d& c = s.blocks[blockIndex(i, j)];
      ends.push_back({i, j});
      blocks.push_back({blockIndex(i, j), blockIndex(j, i)});
      cs.push_back({c(0, 0), c(1, 0), c(2, 0), c(1, 1), c(2, 1), c(2, 2)});
      diagonal_only[blockIndex(i, j)].setZero();
      diagonal_only[blockIndex(j, i)].setZero();
    }
  std::vector<Eigen::Matrix3d> pairs_added = diagonal_only;
  for (std::size_t k = 0; k < cs.size(); ++k)
  {
    const Eigen::Matrix3d symmetric = symmetricBlock(cs[k]);
    pairs_added[blocks[k][0]] += symmetric;
    pairs_added[blocks[k][1]] += symmetric;
  }
  const FinestPairs pairs{static_cast<int>(ends.size()), ends.data(), blocks.data(), cs.data()};
  SmoothedAggregation summed, beside;
  summed.setPattern(s.particles, s.row_start, s.column);
  beside.setPattern(s.particles, s.row_start, s.column);
  for (int setup = 0; setup < 2; ++setup)  // the first lays out the levels, the second reuses them
  {
    ASSERT_TRUE(summed.setup(pairs_added, s.x, s.pinned));
    ASSERT_TRUE(beside.setup(diagonal_only, s.x, s.pinned, pairs));
  }
  ASSERT_GE(summed.levels(), 3);
  ASSERT_EQ(beside.levels(), summed.levels());
  for (int level = 0; level < summed.levels(); ++level)
  {
    EXPECT_EQ(beside.matrixOf(level).values, summed.matrixOf(level).values) << "level " << level;

    if (level + 1 < summed.levels())
    {
      EXPECT_EQ(beside.prolongatorOf(level).values, summed.prolongatorOf(level).values) << "level " << level;
    }
  }
  const Eigen::Matrix3Xd r = randomFiltered(s.particles, s.pinned, 40);
  Eigen::Matrix3Xd z_summed(3, s.particles), z_beside(3, s.particles);
  summed.apply(r, z_summed);
  beside.apply(r, z_beside);
  EXPECT_EQ(z_beside, z_summed);
  EXPECT_GT(z_summed.cwiseAbs().maxCoeff(), 0.0);
}

TEST(SmoothedAggregation, TheProlongatorSpreadsAnAggregateOverItsStrongCouplingsOnly)
{
  // A sheet with weak bend springs beside its structural and shear ones: P is smoothed by the
  // lumped matrix (its weak couplings in the diagonal), so that row i of P has blocks only in the
  // aggregates of i and of the particles it shares a structural or shear spring with, never in one
  // that only a bend spring reaches; and there are such aggregates (the bends reach two particles
  // across, past a 3 x 3 aggregate's neighbours), which the smoothing by A itself would have filled.
  const SheetSystem s = crumpledSheet(40, 4, true);
  SmoothedAggregation multigrid;
  multigrid.setPattern(s.particles, s.row_start, s.column);
  ASSERT_TRUE(multigrid.setup(s.blocks, s.x, s.pinned));
  ASSERT_GE(multigrid.levels(), 2);
  std::vector<std::vector<int>> spring_aggregates(s.particles), bend_aggregates(s.particles);
  for (int i = 0; i < s.particles; ++i)
    spring_aggregates[i].push_back(multigrid.aggregateOf(0, i));
  for (const auto& [i, j] : s.springs)
  {
    spring_aggregates[i].push_back(multigrid.aggregateOf(0, j));
    spring_aggregates[j].push_back(multigrid.aggregateOf(0, i));
  }
  for (const auto& [i, j] : s.bends)
  {
    bend_aggregates[i].push_back(multigrid.aggregateOf(0, j));
    bend_aggregates[j].push_back(multigrid.aggregateOf(0, i));
  }
  const SmoothedAggregation::BlockRows prolongator = multigrid.prolongatorOf(0);
  int reached_by_bends_only = 0;
  for (int i = 0; i < s.particles; ++i)
  {
    if (s.pinned[i]) continue;
    const std::vector<int>& allowed = spring_aggregates[i];
    for (int k = prolongator.start[i]; k < prolongator.start[i + 1]; ++k)
    {
      const int column = prolongator.column[k];
      EXPECT_NE(std::find(allowed.begin(), allowed.end(), column), allowed.end())
          << "particle " << i << ", aggregate " << column;
    }
    for (const int aggregate : bend_aggregates[i])
      reached_by_bends_only += std::find(allowed.begin(), allowed.end(), aggregate) == allowed.end();
  }
  EXPECT_GT(reached_by_bends_only, s.particles / 4);
}

TEST(SmoothedAggregation, ANegativeDefiniteSystemIsRefused)
{
  // −A: every coarse matrix Pᵀ (−A) P is negative definite, so the coarsest factorization has
  // negative pivots and setup() says so (the solver then falls back to block Jacobi's CG, which
  // reports the breakdown).
  SheetSystem s = crumpledSheet(17, 3);
  for (Eigen::Matrix3d& block : s.blocks)
    block = -block;
  SmoothedAggregation multigrid;
  multigrid.setPattern(s.particles, s.row_start, s.column);
  EXPECT_FALSE(multigrid.setup(s.blocks, s.x, s.pinned));
}

namespace
{
// A 1 m spring cloth of n x n particles (structural, shear and bend springs), hanging from two
// adjacent corners, implicit Euler at dt = 1/60 with `solver` to a relative residual of `tolerance`.
std::unique_ptr<SpringNetworkBody> hangingCloth(int n, LinearSolverType solver, double tolerance)
{
  ClothGridDef def(ClothModel::Springs);
  def.origin = {0.0, 0.0, 2.0};
  def.edge_u = {1.0, 0.0, 0.0};
  def.edge_v = {0.0, 1.0, 0.0};
  def.nu = def.nv = n;
  def.mass = 1.0;
  def.stretch.stiffness = def.shear.stiffness = 1000.0;
  def.bend.stiffness = 100.0;
  def.named_pins = {"corner_00", "corner_10"};
  def.integrator.type = kImplicitEulerIntegrator;
  def.integrator.linear_solver = solver;
  def.integrator.cg_tolerance = tolerance;
  def.integrator.cg_velocity_tolerance = 0.0;
  def.integrator.cg_max_iterations = 100000;
  return std::make_unique<SpringNetworkBody>(buildClothGrid(def));
}

Environment noGround()
{
  Environment env;
  env.ground.enabled = false;
  return env;
}
}  // namespace

TEST(SmoothedAggregation, ItsFlopCountsGrowLinearlyWithTheSheet)
{
  // The cycle's and the setup's flop counts (the `auto` linear solver's comparison with CG): the
  // cycle smooths and takes at least two residuals on the finest level, at least 2 · 2 · 9 flops a block of
  // A there, and the hierarchy's levels shrink geometrically, so both counts grow like the sheet's
  // particles (a 64² sheet has four times a 32² sheet's), and a setup costs more than a cycle.
  auto counts = [](int n) {
    const SheetSystem s = crumpledSheet(n, 5, true);
    SmoothedAggregation multigrid;
    multigrid.setPattern(s.particles, s.row_start, s.column);
    EXPECT_EQ(multigrid.cycleFlops(), 0.0) << "before the first setup";
    EXPECT_TRUE(multigrid.setup(s.blocks, s.x, s.pinned));
    EXPECT_GE(multigrid.cycleFlops(), 2.0 * 2.0 * 9.0 * static_cast<double>(s.column.size())) << n;
    EXPECT_GT(multigrid.setupFlops(), multigrid.cycleFlops()) << n;
    return std::make_pair(multigrid.cycleFlops(), multigrid.setupFlops());
  };
  const auto [cycle32, setup32] = counts(32);
  const auto [cycle64, setup64] = counts(64);
  EXPECT_NEAR(cycle64 / cycle32, 4.0, 0.6);
  EXPECT_NEAR(setup64 / setup32, 4.0, 0.6);
}

TEST(MultigridSolver, StepsTheClothAsTheDirectSolveDoes)
{
  // The same steps of a hanging cloth, solved directly and by the multigrid's CG to a relative
  // 1e-12: the states agree to what that tolerance leaves (and the pinned corners do not move).
  const auto direct_body = hangingCloth(20, LinearSolverType::Direct, 1e-12);
  const auto multigrid_body = hangingCloth(20, LinearSolverType::Multigrid, 1e-12);
  SpringNetworkBody& direct = *direct_body;
  SpringNetworkBody& multigrid = *multigrid_body;
  const Environment env = noGround();
  const Eigen::Matrix3Xd start = multigrid.particles().position;
  for (int step = 0; step < 20; ++step)
  {
    direct.step(1.0 / 60.0, env);
    multigrid.step(1.0 / 60.0, env);
    ASSERT_FALSE(multigrid.frozen()) << multigrid.frozenReason();
    EXPECT_TRUE(multigrid.lastSolve().converged) << "step " << step;
    EXPECT_FALSE(multigrid.lastSolve().direct);
    EXPECT_GT(multigrid.lastSolve().iterations, 0);
  }
  const Eigen::Matrix3Xd& x = multigrid.particles().position;
  EXPECT_LE((x - direct.particles().position).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_GT((x - start).cwiseAbs().maxCoeff(), 0.05) << "the cloth fell";
  for (int pinned : {0, 19})
    EXPECT_EQ((x.col(pinned) - start.col(pinned)).norm(), 0.0) << "pinned particle " << pinned;
}

TEST(MultigridSolver, ItsIterationsGrowFarSlowerWithTheClothThanBlockJacobis)
{
  // Ten steps from rest at a relative 1e-6, at 32² and 64² (where the hierarchy has four levels;
  // at 16² its coarsest level is nearly the whole system), and CG with block Jacobi beside it: block
  // Jacobi's iterations grow with the side (about twice as many for twice the side: measured 118 and
  // 234), the multigrid's by about a twentieth (11.0 and 11.6), and they are more than ten times fewer.
  const Environment env = noGround();
  auto iterationsPerStep = [&](int n, LinearSolverType solver) {
    const auto cloth = hangingCloth(n, solver, 1e-6);
    SpringNetworkBody& body = *cloth;
    long long iterations = 0;
    for (int step = 0; step < 10; ++step)
    {
      body.step(1.0 / 60.0, env);
      EXPECT_TRUE(body.lastSolve().converged) << toString(solver) << " n = " << n << ", step " << step;
      iterations += body.lastSolve().iterations;
    }
    return static_cast<double>(iterations) / 10.0;
  };
  const double jacobi32 = iterationsPerStep(32, LinearSolverType::ConjugateGradient);
  const double jacobi64 = iterationsPerStep(64, LinearSolverType::ConjugateGradient);
  const double multigrid32 = iterationsPerStep(32, LinearSolverType::Multigrid);
  const double multigrid64 = iterationsPerStep(64, LinearSolverType::Multigrid);
  EXPECT_GT(jacobi64, 1.8 * jacobi32);
  EXPECT_LT(multigrid64, 1.4 * multigrid32);
  EXPECT_LT(10.0 * multigrid64, jacobi64);
}

TEST(MultigridSolver, AutoTriesItOnceCgTakesOverAHundredIterationsAndKeepsItWhenCheaper)
{
  // A 64² cloth on `auto` (the direct solver dearer than kDirectSolverCgIterations) at a relative
  // 1e-6: CG first, and from rest a few iterations; once a CG solve takes more than
  // kMultigridTrialCgIterations, the next solve is the multigrid's, which costs less than that CG
  // solve (its iterations more than ten times fewer): from then on every solve is the multigrid's,
  // converged, never direct.
  const auto cloth = hangingCloth(64, LinearSolverType::Auto, 1e-6);
  SpringNetworkBody& body = *cloth;
  const Environment env = noGround();
  int first_multigrid = -1, trigger = 0;
  for (int step = 0; step < 8; ++step)
  {
    body.step(1.0 / 60.0, env);
    const SolverReport report = body.lastSolve();
    EXPECT_TRUE(report.converged) << "step " << step;
    EXPECT_FALSE(report.direct) << "step " << step;
    if (first_multigrid < 0 && report.multigrid) first_multigrid = step;
    if (first_multigrid < 0)
    {
      trigger = report.iterations;
      continue;
    }
    EXPECT_TRUE(report.multigrid) << "back to CG at step " << step;
    EXPECT_LT(10 * report.iterations, trigger) << "step " << step;
  }
  ASSERT_GT(first_multigrid, 0) << "auto never tried the multigrid";
  EXPECT_GT(trigger, kMultigridTrialCgIterations);
}

TEST(MultigridSolver, AutoGoesBackToCgForGoodWhenTheMultigridCostsMore)
{
  // A 40² cloth on `auto` at a relative 1e-6: its first CG solve over kMultigridTrialCgIterations
  // (about 160) brings the multigrid's trial, which converges in about a dozen iterations but costs
  // more than those CG iterations there (its setup and cycles, at kMultigridFlopWeight): CG is back
  // for good, converged, and the direct solver still dearer.
  const auto cloth = hangingCloth(40, LinearSolverType::Auto, 1e-6);
  SpringNetworkBody& body = *cloth;
  const Environment env = noGround();
  int multigrid_solves = 0, first_multigrid = -1;
  for (int step = 0; step < 8; ++step)
  {
    body.step(1.0 / 60.0, env);
    const SolverReport report = body.lastSolve();
    EXPECT_TRUE(report.converged) << "step " << step;
    EXPECT_FALSE(report.direct) << "step " << step;
    if (!report.multigrid) continue;
    ++multigrid_solves;
    first_multigrid = step;
  }
  EXPECT_EQ(multigrid_solves, 1) << "the multigrid was tried once (or not at all)";
  EXPECT_GT(first_multigrid, 0);
  EXPECT_LT(first_multigrid, 7) << "tried in the last step: no step after it tells that CG is back";
}
