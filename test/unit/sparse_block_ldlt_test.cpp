// The direct solver of the implicit methods (SparseBlockLdlt): its solutions against a dense LU of
// the same filtered matrix, its fill on a chain (none, in any labelling), its flop estimate against
// the factor it builds, the implicit step it gives against the conjugate gradient's, and the dense
// products of its supernodes.

#include "particle_sim/core/integrators/sparse_block_ldlt.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <utility>
#include <vector>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/integrators/dense_panel.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/worker_pool.h"

using namespace particle_sim::core;

namespace
{
// A block pattern (row_start, block_column) from particle pairs, each row sorted with its diagonal.
struct Pattern
{
  std::vector<int> row_start, block_column;
  int blockIndex(int i, int j) const
  {
    const auto first = block_column.begin() + row_start[i], last = block_column.begin() + row_start[i + 1];
    const auto it = std::lower_bound(first, last, j);
    return it != last && *it == j ? static_cast<int>(it - block_column.begin()) : -1;
  }
};

Pattern patternOf(int n, const std::vector<std::pair<int, int>>& pairs)
{
  std::vector<std::vector<int>> columns(n);
  for (int i = 0; i < n; ++i)
    columns[i].push_back(i);
  for (const auto& [i, j] : pairs)
  {
    columns[i].push_back(j);
    columns[j].push_back(i);
  }
  Pattern p;
  p.row_start.push_back(0);
  for (auto& c : columns)
  {
    std::sort(c.begin(), c.end());
    c.erase(std::unique(c.begin(), c.end()), c.end());
    p.block_column.insert(p.block_column.end(), c.begin(), c.end());
    p.row_start.push_back(static_cast<int>(p.block_column.size()));
  }
  return p;
}

// A random symmetric positive definite matrix on the pattern: each pair contributes a spring-like
// positive semidefinite 4-block term (K, −K; −K, K), plus a mass on the diagonal.
std::vector<Eigen::Matrix3d> randomSpdBlocks(const Pattern& p, int n, const std::vector<std::pair<int, int>>& pairs,
                                             std::mt19937_64& random)
{
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<Eigen::Matrix3d> blocks(p.block_column.size(), Eigen::Matrix3d::Zero());
  for (int i = 0; i < n; ++i)
    blocks[p.blockIndex(i, i)] += (0.1 + 0.5 * (1.0 + uniform(random))) * Eigen::Matrix3d::Identity();
  for (const auto& [i, j] : pairs)
  {
    Eigen::Matrix3d g;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        g(a, b) = uniform(random);
    const Eigen::Matrix3d k = 100.0 * g * g.transpose();
    blocks[p.blockIndex(i, i)] += k;
    blocks[p.blockIndex(j, j)] += k;
    blocks[p.blockIndex(i, j)] -= k;
    blocks[p.blockIndex(j, i)] -= k;
  }
  return blocks;
}

// The dense matrix of the filtered system: pinned rows and columns replaced by the identity.
Eigen::MatrixXd denseFiltered(const Pattern& p, int n, const std::vector<Eigen::Matrix3d>& blocks,
                              const std::vector<char>& pinned)
{
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  for (int i = 0; i < n; ++i)
  {
    for (int k = p.row_start[i]; k < p.row_start[i + 1]; ++k)
    {
      const int j = p.block_column[k];
      if (pinned[i] || pinned[j]) continue;
      a.block<3, 3>(3 * i, 3 * j) = blocks[k];
    }
    if (pinned[i]) a.block<3, 3>(3 * i, 3 * i).setIdentity();
  }
  return a;
}

// A 2-D grid of nu x nv particles joined to their right, upper and diagonal neighbours.
std::vector<std::pair<int, int>> gridPairs(int nu, int nv)
{
  std::vector<std::pair<int, int>> pairs;
  for (int b = 0; b < nv; ++b)
    for (int a = 0; a < nu; ++a)
    {
      const int i = b * nu + a;
      if (a + 1 < nu) pairs.emplace_back(i, i + 1);
      if (b + 1 < nv) pairs.emplace_back(i, i + nu);
      if (a + 1 < nu && b + 1 < nv) pairs.emplace_back(i, i + nu + 1);
      if (a > 0 && b + 1 < nv) pairs.emplace_back(i, i + nu - 1);
    }
  return pairs;
}
}  // namespace

TEST(SparseBlockLdlt, SolvesTheFilteredSystemLikeADenseLu)
{
  std::mt19937_64 random(7);
  const int nu = 9, nv = 7, n = nu * nv;
  const std::vector<std::pair<int, int>> pairs = gridPairs(nu, nv);
  const Pattern p = patternOf(n, pairs);
  const std::vector<Eigen::Matrix3d> blocks = randomSpdBlocks(p, n, pairs, random);
  std::vector<char> pinned(n, 0);
  pinned[0] = pinned[nu - 1] = pinned[n / 2] = 1;

  SparseBlockLdlt ldlt;
  ldlt.analyze(p.row_start, p.block_column);
  ASSERT_TRUE(ldlt.factorize(blocks, pinned));
  Eigen::Matrix3Xd b = Eigen::Matrix3Xd::Random(3, n), x(3, n);
  for (int i = 0; i < n; ++i)
    if (pinned[i]) b.col(i).setZero();
  ldlt.solve(b, x);

  const Eigen::MatrixXd a = denseFiltered(p, n, blocks, pinned);
  const Eigen::VectorXd expected = a.partialPivLu().solve(Eigen::Map<const Eigen::VectorXd>(b.data(), 3 * n));
  const Eigen::Map<const Eigen::VectorXd> got(x.data(), 3 * n);
  EXPECT_LT((got - expected).norm(), 1e-10 * expected.norm());
  for (int i = 0; i < n; ++i)
  {
    if (!pinned[i]) continue;
    EXPECT_EQ(x.col(i).norm(), 0.0) << "pinned particle " << i;
  }
}

TEST(SparseBlockLdlt, ASheetTakesSupernodesThatSolveLikeADenseLuWithTheSameBitsInEitherKernel)
{
  // A 2-D sheet's separators are wide supernodes: analyze() takes the supernodal form, whose
  // solution matches a dense LU of the filtered matrix, pins included; its dense products give the
  // same bits with the AVX-512 tiles, the AVX2 tiles and without (each where the processor has it).
  std::mt19937_64 random(5);
  const int nu = 26, nv = 21, n = nu * nv;
  const std::vector<std::pair<int, int>> pairs = gridPairs(nu, nv);
  const Pattern p = patternOf(n, pairs);
  const std::vector<Eigen::Matrix3d> blocks = randomSpdBlocks(p, n, pairs, random);
  std::vector<char> pinned(n, 0);
  pinned[0] = pinned[nu - 1] = pinned[n / 2 + 3] = 1;
  Eigen::Matrix3Xd b = Eigen::Matrix3Xd::Random(3, n);
  for (int i = 0; i < n; ++i)
    if (pinned[i]) b.col(i).setZero();

  const dense_panel::Tiles tiles = SparseBlockLdlt::tiles();
  std::vector<Eigen::Matrix3Xd> solutions;
  for (const dense_panel::Tiles form :
       {dense_panel::Tiles::Avx512, dense_panel::Tiles::Avx2, dense_panel::Tiles::Scalar})
  {
    SparseBlockLdlt::setTiles(form);
    SparseBlockLdlt ldlt;
    ldlt.analyze(p.row_start, p.block_column);
    ASSERT_TRUE(ldlt.supernodal());
    ASSERT_TRUE(ldlt.factorize(blocks, pinned));
    Eigen::Matrix3Xd x(3, n);
    ldlt.solve(b, x);
    solutions.push_back(x);
  }
  SparseBlockLdlt::setTiles(tiles);
  std::printf("[tiles] widest on this processor: %s\n",
              dense_panel::widestTiles() == dense_panel::Tiles::Avx512 ? "AVX-512"
              : dense_panel::widestTiles() == dense_panel::Tiles::Avx2 ? "AVX2"
                                                                       : "scalar");
  for (std::size_t form = 1; form < solutions.size(); ++form)
    EXPECT_EQ(std::memcmp(solutions[0].data(), solutions[form].data(), sizeof(double) * 3 * n), 0) << "form " << form;

  const Eigen::MatrixXd a = denseFiltered(p, n, blocks, pinned);
  const Eigen::VectorXd expected = a.partialPivLu().solve(Eigen::Map<const Eigen::VectorXd>(b.data(), 3 * n));
  const Eigen::Map<const Eigen::VectorXd> got(solutions[0].data(), 3 * n);
  EXPECT_LT((got - expected).norm(), 1e-10 * expected.norm());
  for (int i = 0; i < n; ++i)
  {
    if (!pinned[i]) continue;
    EXPECT_EQ(solutions[0].col(i).norm(), 0.0) << "pinned particle " << i;
  }

  // A second factorization of other numbers on the same analysis (the panels are made afresh).
  SparseBlockLdlt ldlt;
  ldlt.analyze(p.row_start, p.block_column);
  ASSERT_TRUE(ldlt.factorize(randomSpdBlocks(p, n, pairs, random), pinned));
  ASSERT_TRUE(ldlt.factorize(blocks, pinned));
  Eigen::Matrix3Xd again(3, n);
  ldlt.solve(b, again);
  EXPECT_EQ(std::memcmp(again.data(), solutions[0].data(), sizeof(double) * 3 * n), 0);
}

TEST(SparseBlockLdlt, TheSupernodalFormRefusesASingularPivot)
{
  const int nu = 26, nv = 21, n = nu * nv;
  const std::vector<std::pair<int, int>> pairs = gridPairs(nu, nv);
  const Pattern p = patternOf(n, pairs);
  std::mt19937_64 random(9);
  std::vector<Eigen::Matrix3d> blocks = randomSpdBlocks(p, n, pairs, random);
  SparseBlockLdlt ldlt;
  ldlt.analyze(p.row_start, p.block_column);
  ASSERT_TRUE(ldlt.supernodal());
  // A zero row and column: singular.
  const int singular = n / 3;
  for (int k = p.row_start[singular]; k < p.row_start[singular + 1]; ++k)
  {
    const int j = p.block_column[k];
    blocks[k].row(1).setZero();
    blocks[p.blockIndex(j, singular)].col(1).setZero();
  }
  EXPECT_FALSE(ldlt.factorize(blocks, std::vector<char>(n, 0)));
  blocks[p.blockIndex(singular, singular)](1, 1) = std::nan("");
  EXPECT_FALSE(ldlt.factorize(blocks, std::vector<char>(n, 0)));
}

TEST(SparseBlockLdlt, TwoThreadsFactorASheetToTheSameBitsAsOne)
{
  // A sheet large enough for the two threads' plan: its tree of supernodes cut into two shares of
  // whole subtrees and the supernodes above them. The solution with two threads is the one thread's
  // (which the test above holds against a dense LU), bit for bit, in every form of the dense
  // products, and over a second factorization on the same analysis; a singular pivot is refused
  // either way, in a share or above them, and by factorizeAndSolve(), which then leaves x alone.
  std::mt19937_64 random(13);
  WorkerPool two(2);
  const dense_panel::Tiles tiles = SparseBlockLdlt::tiles();
  // A near-square sheet (one supernode above the shares, its root) and a long one (some twenty
  // above, whose updates of each other are split between the threads between the held-back ones).
  for (const auto& [nu, nv] : {std::pair<int, int>{40, 36}, std::pair<int, int>{17, 123}})
  {
    const int n = nu * nv;
    const std::vector<std::pair<int, int>> pairs = gridPairs(nu, nv);
    const Pattern p = patternOf(n, pairs);
    std::vector<char> pinned(n, 0);
    pinned[0] = pinned[nu - 1] = pinned[n / 2 + 7] = 1;
    Eigen::Matrix3Xd b = Eigen::Matrix3Xd::Random(3, n);
    for (int i = 0; i < n; ++i)
      if (pinned[i]) b.col(i).setZero();
    for (const dense_panel::Tiles form :
         {dense_panel::Tiles::Avx512, dense_panel::Tiles::Avx2, dense_panel::Tiles::Scalar})
    {
      SparseBlockLdlt::setTiles(form);
      SparseBlockLdlt one_thread, two_threads;
      one_thread.analyze(p.row_start, p.block_column);
      two_threads.analyze(p.row_start, p.block_column);
      two_threads.setWorkers(&two);
      ASSERT_TRUE(two_threads.supernodal());
      ASSERT_GT(two_threads.sharedShare(), 0.5) << nu << " x " << nv;
      for (int round = 0; round < 2; ++round)
      {
        const std::vector<Eigen::Matrix3d> blocks = randomSpdBlocks(p, n, pairs, random);
        ASSERT_TRUE(one_thread.factorize(blocks, pinned));
        ASSERT_TRUE(two_threads.factorize(blocks, pinned));
        Eigen::Matrix3Xd x1(3, n), x2(3, n), x3(3, n);
        one_thread.solve(b, x1);
        two_threads.solve(b, x2);
        EXPECT_EQ(std::memcmp(x1.data(), x2.data(), sizeof(double) * 3 * n), 0)
            << nu << " x " << nv << ", round " << round;
        // Both at once, the shares' forward passes beside the last panel above them.
        ASSERT_TRUE(two_threads.factorizeAndSolve(blocks, pinned, b, x3));
        EXPECT_EQ(std::memcmp(x1.data(), x3.data(), sizeof(double) * 3 * n), 0)
            << nu << " x " << nv << ", round " << round << ", factorized and solved at once";
      }
    }
  }
  SparseBlockLdlt::setTiles(tiles);
  EXPECT_GT(two.sharedLoops(), 0);

  // A zero row and column, singular, at every 11th particle in turn: such particles lie in both
  // shares and above them (the supernodes above hold some 9 % of the columns here).
  const int nu = 40, nv = 36, n = nu * nv;
  const std::vector<std::pair<int, int>> pairs = gridPairs(nu, nv);
  const Pattern p = patternOf(n, pairs);
  SparseBlockLdlt ldlt;
  ldlt.analyze(p.row_start, p.block_column);
  ldlt.setWorkers(&two);
  for (int singular = 0; singular < n; singular += 11)
  {
    std::vector<Eigen::Matrix3d> blocks = randomSpdBlocks(p, n, pairs, random);
    for (int k = p.row_start[singular]; k < p.row_start[singular + 1]; ++k)
    {
      const int j = p.block_column[k];
      blocks[k].row(1).setZero();
      blocks[p.blockIndex(j, singular)].col(1).setZero();
    }
    EXPECT_FALSE(ldlt.factorize(blocks, std::vector<char>(n, 0))) << "singular particle " << singular;
    Eigen::Matrix3Xd x = Eigen::Matrix3Xd::Constant(3, n, 7.0);
    EXPECT_FALSE(ldlt.factorizeAndSolve(blocks, std::vector<char>(n, 0), Eigen::Matrix3Xd::Ones(3, n), x))
        << "singular particle " << singular;
    EXPECT_TRUE((x.array() == 7.0).all()) << "x written after a singular pivot, particle " << singular;
  }
}

TEST(SparseBlockLdlt, APairedMatrixFactorsToTheSameBitsAsItsBlocks)
{
  // The implicit solver hands a sheet's matrix over as its diagonal blocks and its pairs (a spring's
  // C on blocks (i, j) and (j, i)), which go straight into the panels: the solution is the one from
  // the blocks the pairs add up to, bit for bit, at one thread and two, pins included. Some particle
  // pairs carry three pairs, whose sum depends on their order; a pair's blocks come either way round.
  std::mt19937_64 random(23);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  WorkerPool two(2);
  const int nu = 40, nv = 36, n = nu * nv;
  const std::vector<std::pair<int, int>> grid = gridPairs(nu, nv);
  const Pattern p = patternOf(n, grid);
  std::vector<std::array<int, 2>> pair_blocks;
  std::vector<std::array<double, 6>> pair_c;
  std::vector<Eigen::Matrix3d> diagonal(n), blocks(p.block_column.size(), Eigen::Matrix3d::Zero());
  std::vector<int> diagonal_block(n);
  for (int i = 0; i < n; ++i)
  {
    diagonal_block[i] = p.blockIndex(i, i);
    diagonal[i] = (0.1 + 0.5 * (1.0 + uniform(random))) * Eigen::Matrix3d::Identity();
  }
  for (std::size_t e = 0; e < grid.size(); ++e)
  {
    const auto [i, j] = grid[e];
    for (int repeat = 0; repeat < (e % 5 == 0 ? 3 : 1); ++repeat)
    {
      Eigen::Matrix3d g;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          g(a, b) = uniform(random);
      const Eigen::Matrix3d k = 100.0 * g * g.transpose();
      diagonal[i] += k;
      diagonal[j] += k;
      const std::array<double, 6> c{-k(0, 0), -k(1, 0), -k(2, 0), -k(1, 1), -k(2, 1), -k(2, 2)};
      const int ij = p.blockIndex(i, j), ji = p.blockIndex(j, i);
      pair_blocks.push_back(uniform(random) < 0.0 ? std::array<int, 2>{ij, ji} : std::array<int, 2>{ji, ij});
      pair_c.push_back(c);
      Eigen::Matrix3d symmetric;
      symmetric << c[0], c[1], c[2], c[1], c[3], c[4], c[2], c[4], c[5];
      blocks[ij] += symmetric;
      blocks[ji] += symmetric;
    }
  }
  for (int i = 0; i < n; ++i)
    blocks[diagonal_block[i]] = diagonal[i];
  const SparseBlockLdlt::PairedMatrix paired{diagonal.data(), diagonal_block.data(), static_cast<int>(pair_c.size()),
                                             pair_blocks.data(), pair_c.data()};
  std::vector<char> pinned(n, 0);
  pinned[0] = pinned[nu - 1] = pinned[n / 2 + 7] = 1;
  Eigen::Matrix3Xd b = Eigen::Matrix3Xd::Random(3, n);
  for (int i = 0; i < n; ++i)
    if (pinned[i]) b.col(i).setZero();

  for (const bool two_threads : {false, true})
  {
    SparseBlockLdlt from_blocks, from_pairs;
    from_blocks.analyze(p.row_start, p.block_column);
    from_pairs.analyze(p.row_start, p.block_column);
    if (two_threads)
    {
      from_blocks.setWorkers(&two);
      from_pairs.setWorkers(&two);
    }
    ASSERT_TRUE(from_pairs.supernodal());
    Eigen::Matrix3Xd x_blocks(3, n), x_pairs(3, n);
    ASSERT_TRUE(from_blocks.factorizeAndSolve(blocks, pinned, b, x_blocks));
    for (int round = 0; round < 2; ++round)  // and again on the same analysis
    {
      x_pairs.setConstant(7.0);
      ASSERT_TRUE(from_pairs.factorizeAndSolve(paired, pinned, b, x_pairs));
      EXPECT_EQ(std::memcmp(x_blocks.data(), x_pairs.data(), sizeof(double) * 3 * n), 0)
          << (two_threads ? "two threads" : "one thread") << ", round " << round;
    }
  }
  EXPECT_GT(two.sharedLoops(), 0);

  // A chain keeps its 3x3 blocks (no supernodes): the pairs are refused, x left alone.
  std::vector<std::pair<int, int>> chain;
  for (int i = 0; i + 1 < 10; ++i)
    chain.emplace_back(i, i + 1);
  const Pattern q = patternOf(10, chain);
  SparseBlockLdlt rope;
  rope.analyze(q.row_start, q.block_column);
  ASSERT_FALSE(rope.supernodal());
  Eigen::Matrix3Xd x = Eigen::Matrix3Xd::Constant(3, 10, 7.0);
  EXPECT_FALSE(rope.factorizeAndSolve(SparseBlockLdlt::PairedMatrix{}, std::vector<char>(10, 0),
                                      Eigen::Matrix3Xd::Ones(3, 10), x));
  EXPECT_TRUE((x.array() == 7.0).all());
}

TEST(SparseBlockLdlt, SolvesAnIndefiniteButRegularSystem)
{
  // Compressed springs make ∂f/∂x positive in places, and A = M − h² ∂f/∂x may then be indefinite;
  // L D Lᵀ with 3x3 pivots still solves it while no pivot is singular.
  std::mt19937_64 random(11);
  const int n = 12;
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i + 1 < n; ++i)
    pairs.emplace_back(i, i + 1);
  const Pattern p = patternOf(n, pairs);
  std::vector<Eigen::Matrix3d> blocks = randomSpdBlocks(p, n, pairs, random);
  blocks[p.blockIndex(5, 5)] -= 400.0 * Eigen::Matrix3d::Identity();
  const std::vector<char> pinned(n, 0);
  const Eigen::MatrixXd a = denseFiltered(p, n, blocks, pinned);
  ASSERT_LT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(a).eigenvalues().minCoeff(), 0.0);

  SparseBlockLdlt ldlt;
  ldlt.analyze(p.row_start, p.block_column);
  ASSERT_TRUE(ldlt.factorize(blocks, pinned));
  const Eigen::Matrix3Xd b = Eigen::Matrix3Xd::Random(3, n);
  Eigen::Matrix3Xd x(3, n);
  ldlt.solve(b, x);
  const Eigen::VectorXd expected = a.partialPivLu().solve(Eigen::Map<const Eigen::VectorXd>(b.data(), 3 * n));
  EXPECT_LT((Eigen::Map<const Eigen::VectorXd>(x.data(), 3 * n) - expected).norm(), 1e-9 * expected.norm());
}

TEST(SparseBlockLdlt, RefusesASingularPivot)
{
  const int n = 4;
  const std::vector<std::pair<int, int>> pairs = {{0, 1}, {1, 2}, {2, 3}};
  const Pattern p = patternOf(n, pairs);
  std::vector<Eigen::Matrix3d> blocks(p.block_column.size(), Eigen::Matrix3d::Zero());
  for (int i = 0; i < n; ++i)
    blocks[p.blockIndex(i, i)].setIdentity();
  blocks[p.blockIndex(2, 2)](1, 1) = 0.0;  // a zero row and column: singular
  SparseBlockLdlt ldlt;
  ldlt.analyze(p.row_start, p.block_column);
  EXPECT_FALSE(ldlt.factorize(blocks, std::vector<char>(n, 0)));
  blocks[p.blockIndex(2, 2)](1, 1) = std::nan("");
  EXPECT_FALSE(ldlt.factorize(blocks, std::vector<char>(n, 0)));
}

TEST(SparseBlockLdlt, AChainHasNoFillInAnyLabelling)
{
  // A rope with bend springs (i, i+1) and (i, i+2): a band of two blocks. Its fill-reducing order
  // eliminates it with no fill whatever order its particles are numbered in, so L has exactly the
  // pattern's 2n − 3 lower blocks, and the work is O(n).
  const int n = 200;
  std::vector<int> label(n);
  for (int i = 0; i < n; ++i)
    label[i] = i;
  std::shuffle(label.begin(), label.end(), std::mt19937_64(3));
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i + 1 < n; ++i)
    pairs.emplace_back(label[i], label[i + 1]);
  for (int i = 0; i + 2 < n; ++i)
    pairs.emplace_back(label[i], label[i + 2]);
  const Pattern p = patternOf(n, pairs);
  SparseBlockLdlt ldlt;
  ldlt.analyze(p.row_start, p.block_column);
  EXPECT_EQ(ldlt.factorBlocks(), 2 * n - 3);
  EXPECT_FALSE(ldlt.supernodal());
  EXPECT_FALSE(SparseBlockLdlt::estimateCost(p.row_start, p.block_column).supernodal);
}

TEST(SparseBlockLdlt, CostEstimateMatchesTheFactorItBuilds)
{
  const int nu = 20, nv = 15;
  const Pattern p = patternOf(nu * nv, gridPairs(nu, nv));
  SparseBlockLdlt ldlt;
  ldlt.analyze(p.row_start, p.block_column);
  const SparseBlockLdlt::Cost cost = SparseBlockLdlt::estimateCost(p.row_start, p.block_column);
  EXPECT_EQ(cost.factor_blocks, ldlt.factorBlocks());
  EXPECT_EQ(cost.factor_flops, ldlt.factorFlops());
  EXPECT_EQ(cost.solve_flops, ldlt.solveFlops());
  EXPECT_EQ(cost.supernodal, ldlt.supernodal());
  // A 2-D sheet fills in: more blocks than the pattern's lower triangle.
  EXPECT_GT(cost.factor_blocks, static_cast<std::int64_t>(gridPairs(nu, nv).size()));
}

TEST(SparseBlockLdlt, ImplicitEulerStepMatchesTheConjugateGradient)
{
  // A hanging rope (pinned at one end), one implicit step from a swinging state: the direct solve
  // and a tightly converged CG give the same state to the CG's tolerance.
  auto run = [](LinearSolverType solver) {
    RopeDef def;
    def.particles = 40;
    def.start = {0.0, 0.0, 2.0};
    def.end = {2.0, 0.0, 2.0};
    def.pins = {0};
    def.stretch_stiffness = 5000.0;
    def.stretch_damping = 1.0;
    def.bend_stiffness = 50.0;
    def.bend_damping = 0.1;
    def.integrator.type = kImplicitEulerIntegrator;
    def.integrator.linear_solver = solver;
    def.integrator.cg_tolerance = 1e-13;
    def.integrator.cg_velocity_tolerance = 0.0;  // the relative rule alone
    def.integrator.cg_max_iterations = 100000;
    SpringNetworkBody body(buildRope(def));
    Environment env;
    env.ground.enabled = false;
    for (int step = 0; step < 20; ++step)
      body.step(1.0 / 60.0, env);
    return std::make_pair(Eigen::Matrix3Xd(body.particles().position.leftCols(body.particles().size())),
                          body.lastSolve());
  };
  const auto [direct, direct_report] = run(LinearSolverType::Direct);
  const auto [cg, cg_report] = run(LinearSolverType::ConjugateGradient);
  EXPECT_TRUE(direct_report.direct);
  EXPECT_FALSE(cg_report.direct);
  EXPECT_TRUE(direct_report.converged);
  EXPECT_EQ(direct_report.iterations, 0) << "the direct solve alone met the tolerance";
  EXPECT_GT(cg_report.iterations, 0);
  EXPECT_LT((direct - cg).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(SparseBlockLdlt, AutoPicksDirectForARopeAndCgForALargeSheet)
{
  ImplicitEulerSolver rope, sheet;
  std::vector<std::pair<int, int>> chain;
  for (int i = 0; i + 1 < 1000; ++i)
    chain.emplace_back(i, i + 1);
  rope.setPattern(1000, chain);
  sheet.setPattern(64 * 64, gridPairs(64, 64));
  EXPECT_TRUE(rope.usesDirect(LinearSolverType::Auto));
  EXPECT_FALSE(sheet.usesDirect(LinearSolverType::Auto));
  EXPECT_TRUE(sheet.usesDirect(LinearSolverType::Direct));
  EXPECT_FALSE(rope.usesDirect(LinearSolverType::ConjugateGradient));
}

namespace
{
// A stiff 48 x 48 spring cloth hanging from two corners, implicit Euler with `auto`.
ClothGridDef stiffSheetOnAuto()
{
  ClothGridDef def(ClothModel::Springs);
  def.name = "sheet";
  def.nu = def.nv = 48;
  def.mass = 1.0;
  def.stretch.stiffness = 1000.0;
  def.shear.stiffness = 1000.0;
  def.named_pins = {"corner_00", "corner_10"};
  def.integrator.type = kImplicitEulerIntegrator;
  def.integrator.linear_solver = LinearSolverType::Auto;
  return def;
}
}  // namespace

TEST(SparseBlockLdlt, AutoTurnsDirectWhenCgTakesMoreIterationsThanTheFactorizationCosts)
{
  // A stiff 48 x 48 spring cloth at dt = 1/60: too large for `auto` to start directly, but CG needs
  // hundreds of iterations to a relative residual of 1e-8 (the velocity rule alone would stop it
  // sooner), more than one factorization costs; from the next step on it is direct. On the way, its
  // first CG solve over kMultigridTrialCgIterations brings one solve by the multigrid, whose cost
  // here is within a few per cent of that CG solve's (since 2026-12-07 a little below it, so it is
  // kept): then the multigrid's solves, not CG's, are the ones that turn it direct.
  ClothGridDef def = stiffSheetOnAuto();
  def.integrator.cg_velocity_tolerance = 0.0;
  SpringNetworkBody body(buildClothGrid(def));
  Environment env;
  env.ground.enabled = false;
  // CG first; the step after the first solve that costs more than the factorization is direct, and
  // so is every step after it. When that solve is CG's, its iterations are the most so far (the
  // count to beat is fixed for the pattern), and far above the first step's (from rest, a few).
  std::vector<int> iterations;
  int first_direct = -1;
  bool last_by_multigrid = false;
  for (int step = 0; step < 60; ++step)
  {
    body.step(1.0 / 60.0, env);
    if (body.lastSolve().direct)
    {
      if (first_direct < 0) first_direct = step;
    }
    else
    {
      EXPECT_LT(first_direct, 0) << "back to CG at step " << step;
      last_by_multigrid = body.lastSolve().multigrid;
      if (!last_by_multigrid) iterations.push_back(body.lastSolve().iterations);
    }
  }
  ASSERT_GT(first_direct, 0) << "auto never turned direct in 60 steps";
  ASSERT_GE(iterations.size(), 2u);
  const int most = *std::max_element(iterations.begin(), iterations.end());
  if (!last_by_multigrid)
  {
    EXPECT_EQ(iterations.back(), most);
  }
  EXPECT_GT(most, kMultigridTrialCgIterations) << "no CG solve brought the multigrid's trial";
  EXPECT_GT(most, 10 * iterations.front());
  EXPECT_TRUE(body.lastSolve().converged);
  // A forced CG stays CG.
  def.integrator.linear_solver = LinearSolverType::ConjugateGradient;
  def.integrator.cg_max_iterations = 5;
  SpringNetworkBody cg(buildClothGrid(def));
  for (int step = 0; step < 3; ++step)
    cg.step(1.0 / 60.0, env);
  EXPECT_FALSE(cg.lastSolve().direct);
  EXPECT_FALSE(cg.lastSolve().converged) << "5 iterations were enough: the forced CG was not tested";
}

TEST(SparseBlockLdlt, AutoGoesOnPastTheCapUntilCgHasSpentWhatTheDirectSolveCosts)
{
  // The same stiff 48 x 48 cloth, the relative rule alone (1e-8), CG capped at 5 iterations: far
  // fewer than the factorization costs. A twin with CG forced at the same cap stops short of the
  // tolerance. `auto` goes on past the cap while CG has spent less than the direct solve would
  // cost, and meets the tolerance by CG; once CG needs more (the sheet stretches, its iterations
  // grow), it turns direct for good, that step solved again directly. No step of `auto` ends
  // unconverged.
  ClothGridDef def = stiffSheetOnAuto();
  def.integrator.cg_velocity_tolerance = 0.0;
  def.integrator.cg_max_iterations = 5;
  SpringNetworkBody body(buildClothGrid(def));
  def.integrator.linear_solver = LinearSolverType::ConjugateGradient;
  SpringNetworkBody twin(buildClothGrid(def));
  Environment env;
  env.ground.enabled = false;
  int first_direct = -1, twin_short = 0, past_the_cap = 0;
  for (int step = 0; step < 60; ++step)
  {
    twin.step(1.0 / 60.0, env);
    twin_short += twin.lastSolve().converged ? 0 : 1;
    body.step(1.0 / 60.0, env);
    const SolverReport report = body.lastSolve();
    EXPECT_TRUE(report.converged) << "step " << step;
    if (report.direct)
    {
      if (first_direct < 0) first_direct = step;
    }
    else
    {
      EXPECT_LT(first_direct, 0) << "back to CG at step " << step;
      past_the_cap += report.iterations > 5 ? 1 : 0;
    }
  }
  EXPECT_GT(twin_short, 0) << "CG met the tolerance in 5 iterations: the cap did not bind";
  EXPECT_GT(past_the_cap, 0) << "auto stopped CG at the cap";
  ASSERT_GE(first_direct, 0) << "auto never turned direct in 60 steps: CG never cost more than the direct solve";
}

// factorize() forms L_ij = W_i D_j⁻¹ with multiplyInline(), whose sums must round as Eigen's product
// does (the golden hashes of every direct solve depend on it): over random blocks of mixed scales
// every coefficient is the same bits. Summed in another order, about half of them differ.
TEST(SparseBlockLdlt, InlineProductIsTheBitsOfEigensProduct)
{
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), exponent(-8.0, 8.0);
  auto randomBlock = [&] {
    Eigen::Matrix3d m;
    for (int k = 0; k < 9; ++k)
      m(k % 3, k / 3) = unit(random) * std::pow(10.0, exponent(random));
    return m;
  };
  int differing_in_another_order = 0;
  for (int t = 0; t < 2000; ++t)
  {
    const Eigen::Matrix3d a = randomBlock(), b = randomBlock();
    Eigen::Matrix3d eigen, inline_product;
    eigen.noalias() = a * b;
    multiplyInline(a, b, inline_product);
    for (int k = 0; k < 9; ++k)
    {
      const int r = k % 3, c = k / 3;
      EXPECT_EQ(std::memcmp(&eigen(r, c), &inline_product(r, c), sizeof(double)), 0)
          << "block " << t << " (" << r << ", " << c << ")";
      const double left_to_right = (a(r, 0) * b(0, c) + a(r, 1) * b(1, c)) + a(r, 2) * b(2, c);
      const double right_pair_first = a(r, 0) * b(0, c) + (a(r, 1) * b(1, c) + a(r, 2) * b(2, c));
      if (left_to_right != right_pair_first) ++differing_in_another_order;
    }
  }
  EXPECT_GT(differing_in_another_order, 1000);  // the order matters: the test can see it
}

// The supernodes' update goes straight into the panels that hold its rows
// (dense_panel::subtractLowerProducts): every entry on or below the diagonal lands where
// its row and column offsets say, as C(i, j) − Σ_p T(i, p) L(j, p) (against a sum in long double),
// nothing else is written, and the AVX2 and AVX-512 tiles give the scalar entries' bits. The row
// offsets either mix rows that follow each other in C with gaps (none eight long) or are all
// consecutive (a panel's own rows: written four or eight at a time), and the sizes are not whole
// tiles.
namespace
{
void scatteredProductsLandWhereTheyBelong(bool consecutive)
{
  std::mt19937 random(17);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const int rows = 23, columns = 10, k = 7, ldt = rows + 2, ldl = rows + 1;
  std::vector<double> t(static_cast<std::size_t>(ldt) * k), l(static_cast<std::size_t>(ldl) * k);
  for (double& x : t)
    x = unit(random);
  for (double& x : l)
    x = unit(random);
  // Row offsets in a column of C: runs of consecutive rows with gaps between them (or one run);
  // columns 61 apart.
  std::vector<int> row_offset(rows);
  std::vector<long> column_offset(columns);
  int at = 0;
  for (int i = 0; i < rows; ++i)
  {
    row_offset[i] = at;
    at += (!consecutive && (i % 7 == 6 || i % 11 == 3)) ? 3 : 1;
  }
  for (int j = 0; j < columns; ++j)
    column_offset[j] = 61L * j + 2;
  const std::size_t size = 61 * columns + 64;
  std::vector<double> start(size);
  for (double& x : start)
    x = unit(random);

  using particle_sim::core::dense_panel::Tiles;
  std::vector<std::vector<double>> results;
  for (const Tiles tiles : {Tiles::Scalar, Tiles::Avx2, Tiles::Avx512})
  {
    std::vector<double> c = start;
    const Tiles ran = particle_sim::core::dense_panel::subtractLowerProducts(
        tiles, rows, columns, k, t.data(), ldt, l.data(), ldl, row_offset.data(), column_offset.data(), c.data());
    EXPECT_EQ(ran, std::min(tiles, particle_sim::core::dense_panel::widestTiles()));
    results.push_back(c);
  }
  for (std::size_t form = 1; form < results.size(); ++form)
    EXPECT_EQ(std::memcmp(results[0].data(), results[form].data(), sizeof(double) * size), 0) << "form " << form;

  std::vector<char> written(size, 0);
  for (int j = 0; j < columns; ++j)
    for (int i = j; i < rows; ++i)
    {
      const long place = column_offset[j] + row_offset[i];
      written[place] = 1;
      long double sum = 0.0L;
      for (int p = 0; p < k; ++p)
        sum += static_cast<long double>(t[i + p * ldt]) * l[j + p * ldl];
      EXPECT_NEAR(results[0][place], static_cast<double>(start[place] - sum), 1e-14) << "(" << i << ", " << j << ")";
    }
  for (std::size_t e = 0; e < size; ++e)
  {
    if (written[e]) continue;
    EXPECT_EQ(results[0][e], start[e]) << "entry " << e << " is written but holds no product";
  }
}
}  // namespace

TEST(DensePanel, ScatteredProductsLandWhereTheyBelong)
{
  for (const bool consecutive : {false, true})
  {
    SCOPED_TRACE(consecutive ? "consecutive rows" : "rows with gaps");
    scatteredProductsLandWhereTheyBelong(consecutive);
  }
}

// The passes over a panel's columns (factorPanel(), forwardSupernode(), backwardSupernode()): the
// rows' −Σ of the columns taken row by row (subtractScaledColumns, also with T's column kept and L's
// scaled) and four columns' dots at once (dotColumns) give the bits of the column-by-column passes
// they replace, in either form (AVX2 or scalar), with sizes that leave rows past the last eight and
// four and columns past the last four; and they are the sums (against long double).
TEST(DensePanel, ColumnsAtOnceGiveTheBitsOfColumnAfterColumn)
{
  std::mt19937 random(29);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), exponent(-3.0, 3.0);
  const int n = 23, count = 19;
  const long ld = n + 5;
  namespace dense_panel = particle_sim::core::dense_panel;
  for (int trial = 0; trial < 20; ++trial)
  {
    SCOPED_TRACE("trial " + std::to_string(trial));
    std::vector<double> columns(static_cast<std::size_t>(ld) * count), factors(count), x(n), start(n);
    for (std::vector<double>* numbers : {&columns, &factors, &x, &start})
      for (double& v : *numbers)
        v = unit(random) * std::pow(10.0, exponent(random));
    for (const bool avx2 : {false, true})
    {
      SCOPED_TRACE(avx2 ? "avx2" : "scalar");
      std::vector<double> one_by_one = start, at_once = start;
      for (int c = 0; c < count; ++c)
        dense_panel::subtractScaled(avx2, n, columns.data() + c * ld, factors[c], one_by_one.data());
      dense_panel::subtractScaledColumns(avx2, n, count, columns.data(), ld, factors.data(), at_once.data());
      EXPECT_EQ(std::memcmp(one_by_one.data(), at_once.data(), sizeof(double) * n), 0);
      // With T's column kept and L's scaled in the same pass: the kept entries are those bits, the
      // scaled ones each of them times the scale.
      const double scale = 1.0 / factors[0];
      std::vector<double> scaled = start, kept(n);
      dense_panel::subtractScaledColumnsKeepAndScale(avx2, n, count, columns.data(), ld, factors.data(), scale,
                                                     scaled.data(), kept.data());
      EXPECT_EQ(std::memcmp(one_by_one.data(), kept.data(), sizeof(double) * n), 0);
      for (int r = 0; r < n; ++r)
      {
        const double expected = one_by_one[r] * scale;
        EXPECT_EQ(std::memcmp(&expected, &scaled[r], sizeof(double)), 0) << "row " << r;
      }
      std::vector<double> dots(count, 0.0);
      dense_panel::dotColumns(avx2, n, count, columns.data(), ld, x.data(), dots.data());
      for (int c = 0; c < count; ++c)
      {
        const double alone = dense_panel::dot(avx2, n, columns.data() + c * ld, x.data());
        EXPECT_EQ(std::memcmp(&alone, &dots[c], sizeof(double)), 0) << "column " << c;
        long double sum = 0.0L, magnitude = 0.0L;
        for (int r = 0; r < n; ++r)
        {
          sum += static_cast<long double>(columns[c * ld + r]) * x[r];
          magnitude += std::abs(static_cast<long double>(columns[c * ld + r]) * x[r]);
        }
        EXPECT_NEAR(dots[c], static_cast<double>(sum), 1e-14 * static_cast<double>(magnitude)) << "column " << c;
      }
      for (int r = 0; r < n; ++r)
      {
        long double entry = start[r], magnitude = std::abs(start[r]);
        for (int c = 0; c < count; ++c)
        {
          entry -= static_cast<long double>(columns[c * ld + r]) * factors[c];
          magnitude += std::abs(static_cast<long double>(columns[c * ld + r]) * factors[c]);
        }
        EXPECT_NEAR(at_once[r], static_cast<double>(entry), 1e-14 * static_cast<double>(magnitude)) << "row " << r;
      }
    }
  }
}
