// The implicit solve's stopping rule in velocity (IntegratorDef::cg_velocity_tolerance): the bound
// it reports against the true error of a stopped conjugate gradient (a dense LU of the same system
// gives the exact answer), its normalisation where it is an equality, and what it costs on a body
// coming to rest; and that a spring's blocks added as a pair (addPairBlocks) are the system that
// four single blocks make: the same bits for the direct solver, and for the conjugate gradient's
// product by the kept pairs the same solution (with what addToDiagonal adds, too), the same bits at
// any thread count.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <tuple>
#include <utility>
#include <vector>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/integrators/implicit_euler_solver.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/worker_pool.h"

using namespace particle_sim::core;

namespace
{
// A stiff random system A = M + K on an n x n grid: masses from 0.1 to 2 kg, and for each
// neighbouring pair a symmetric positive semi-definite 3x3 term (K, −K; −K, K) of up to 1e4 N·s/m (what
// h ∂f/∂v + h² ∂f/∂x of a definite spring gives). Two particles are pinned. A random right-hand side
// in momentum units [kg·m/s].
struct RandomSystem
{
  int particles = 0;
  std::vector<std::pair<int, int>> pairs;
  std::vector<Eigen::Matrix3d> terms;  // per pair
  Eigen::VectorXd mass;
  Eigen::Matrix3Xd rhs;
  std::vector<char> pinned;
};

RandomSystem randomSystem(int n, unsigned seed, double stiffness = 1e4)
{
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  RandomSystem system;
  system.particles = n * n;
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < n; ++a)
    {
      const int i = b * n + a;
      if (a + 1 < n) system.pairs.emplace_back(i, i + 1);
      if (b + 1 < n) system.pairs.emplace_back(i, i + n);
      if (a + 1 < n && b + 1 < n) system.pairs.emplace_back(i, i + n + 1);
    }
  for (std::size_t p = 0; p < system.pairs.size(); ++p)
  {
    Eigen::Matrix3d g;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        g(r, c) = uniform(random);
    // Symmetric bit for bit, as a spring's blocks are (a 3x3 product sums its rows in different
    // orders): addPairBlocks() keeps one triangle.
    const Eigen::Matrix3d term = stiffness / 3.0 * g * g.transpose();
    system.terms.push_back(0.5 * (term + term.transpose()));
  }
  system.mass.resize(system.particles);
  system.rhs.resize(3, system.particles);
  for (int i = 0; i < system.particles; ++i)
  {
    system.mass[i] = 0.1 + 0.95 * (1.0 + uniform(random));
    system.rhs.col(i) = Eigen::Vector3d(uniform(random), uniform(random), uniform(random));
  }
  system.pinned.assign(system.particles, 0);
  system.pinned[0] = system.pinned[n - 1] = 1;
  return system;
}

// Settings for CG alone, stopping at the relative residual `relative` or the velocity error
// `velocity` [m/s] (0: that rule off), with no cap in practice.
IntegratorDef cgSettings(double relative, double velocity)
{
  IntegratorDef settings;
  settings.linear_solver = LinearSolverType::ConjugateGradient;
  settings.cg_tolerance = relative;
  settings.cg_velocity_tolerance = velocity;
  settings.cg_max_iterations = 100000;
  return settings;
}

// Δv from ImplicitEulerSolver with `settings` (h = 1, v0 = 0, so that A = M + K and b = rhs), each
// pair added as four single blocks, or with addPairBlocks() when `as_pairs`; `kept` (if given) gets
// how many pairs the solver still kept aside after the solve.
Eigen::Matrix3Xd solveOnce(ImplicitEulerSolver& solver, const RandomSystem& system, const IntegratorDef& settings,
                           SolverReport& report, bool as_pairs = false, int* kept = nullptr)
{
  solver.begin(1.0, system.mass, system.rhs, nullptr);
  for (std::size_t p = 0; p < system.pairs.size(); ++p)
  {
    const auto [i, j] = system.pairs[p];
    const Eigen::Matrix3d& k = system.terms[p];
    const Eigen::Matrix3d zero = Eigen::Matrix3d::Zero();
    if (as_pairs)
    {
      solver.addPairBlocks(
          {solver.blockIndex(i, i), solver.blockIndex(i, j), solver.blockIndex(j, i), solver.blockIndex(j, j)}, -k,
          zero);
      continue;
    }
    solver.addBlock(solver.blockIndex(i, i), -k, zero);  // A −= h² ∂f/∂x
    solver.addBlock(solver.blockIndex(j, j), -k, zero);
    solver.addBlock(solver.blockIndex(i, j), k, zero);
    solver.addBlock(solver.blockIndex(j, i), k, zero);
  }
  std::vector<RestingContact> contacts;
  Eigen::Matrix3Xd x = Eigen::Matrix3Xd::Zero(3, system.particles);
  Eigen::Matrix3Xd v = Eigen::Matrix3Xd::Zero(3, system.particles);
  report = solver.solve(system.pinned, contacts, settings, x, v);
  if (kept) *kept = solver.keptPairs();
  return v;
}

// solveOnce() with a new solver.
Eigen::Matrix3Xd solveWith(const RandomSystem& system, const IntegratorDef& settings, SolverReport& report,
                           bool as_pairs = false, int* kept = nullptr)
{
  ImplicitEulerSolver solver;
  solver.setPattern(system.particles, system.pairs);
  return solveOnce(solver, system, settings, report, as_pairs, kept);
}

// The exact Δv: a dense LU of the free rows and columns of A = M + K (+ D_i on each particle's
// diagonal block, when given).
Eigen::Matrix3Xd solveDense(const RandomSystem& system, const std::vector<Eigen::Matrix3d>* diagonal = nullptr)
{
  const int n = system.particles;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  for (int i = 0; i < n; ++i)
  {
    a.block<3, 3>(3 * i, 3 * i) = system.mass[i] * Eigen::Matrix3d::Identity();
    if (diagonal) a.block<3, 3>(3 * i, 3 * i) += (*diagonal)[i];
  }
  for (std::size_t p = 0; p < system.pairs.size(); ++p)
  {
    const auto [i, j] = system.pairs[p];
    a.block<3, 3>(3 * i, 3 * i) += system.terms[p];
    a.block<3, 3>(3 * j, 3 * j) += system.terms[p];
    a.block<3, 3>(3 * i, 3 * j) -= system.terms[p];
    a.block<3, 3>(3 * j, 3 * i) -= system.terms[p];
  }
  Eigen::VectorXd b = Eigen::Map<const Eigen::VectorXd>(system.rhs.data(), 3 * n);
  for (int i = 0; i < n; ++i)
  {
    if (!system.pinned[i]) continue;
    a.middleRows(3 * i, 3).setZero();
    a.middleCols(3 * i, 3).setZero();
    a.block<3, 3>(3 * i, 3 * i).setIdentity();
    b.segment<3>(3 * i).setZero();
  }
  const Eigen::VectorXd solution = a.partialPivLu().solve(b);
  return Eigen::Map<const Eigen::Matrix3Xd>(solution.data(), 3, n);
}

// sqrt(Σ m_i |e_i|² / Σ m_i) over the free particles [m/s].
double massWeightedRms(const RandomSystem& system, const Eigen::Matrix3Xd& error)
{
  double weighted = 0.0, mass = 0.0;
  for (int i = 0; i < system.particles; ++i)
  {
    if (system.pinned[i]) continue;
    weighted += system.mass[i] * error.col(i).squaredNorm();
    mass += system.mass[i];
  }
  return std::sqrt(weighted / mass);
}
}  // namespace

TEST(ImplicitEulerSolver, CgStartsWhereTheLastThreeSolvesPoint)
{
  // One solver, four solves of the same matrix with right-hand sides b0 + k c + k² e (k = 0..3):
  // their solutions are a quadratic in k, so the fourth starts (the quadratic through the last three
  // starts, at the minimum along it) at its own solution and takes no iteration, where the third,
  // whose history is one solve short, takes many. Each Δv is the dense solve's. Then a right-hand
  // side unrelated to the last ones: the start moved along a useless change still ends at the dense
  // solution.
  for (const bool as_pairs : {false, true})
  {
    RandomSystem system = randomSystem(10, 7u);
    const Eigen::Matrix3Xd first = system.rhs;
    const Eigen::Matrix3Xd change = randomSystem(10, 8u).rhs;
    const Eigen::Matrix3Xd curve = randomSystem(10, 9u).rhs;
    ImplicitEulerSolver solver;
    solver.setPattern(system.particles, system.pairs);
    std::vector<int> iterations;
    for (int k = 0; k < 4; ++k)
    {
      system.rhs = first + k * change + (k * k) * curve;
      const Eigen::Matrix3Xd exact = solveDense(system);
      SolverReport report;
      const Eigen::Matrix3Xd dv = solveOnce(solver, system, cgSettings(k < 3 ? 1e-13 : 1e-8, 0.0), report, as_pairs);
      ASSERT_TRUE(report.converged) << "solve " << k;
      EXPECT_LT((dv - exact).norm(), 1e-6 * exact.norm()) << "solve " << k;
      iterations.push_back(report.iterations);
    }
    EXPECT_GT(iterations[2], 10) << "pairs " << as_pairs;
    EXPECT_EQ(iterations[3], 0) << "pairs " << as_pairs;

    system.rhs = randomSystem(10, 10u).rhs;
    const Eigen::Matrix3Xd exact = solveDense(system);
    SolverReport report;
    const Eigen::Matrix3Xd dv = solveOnce(solver, system, cgSettings(1e-10, 0.0), report, as_pairs);
    ASSERT_TRUE(report.converged);
    EXPECT_LT((dv - exact).norm(), 1e-8 * exact.norm());
    std::printf("pairs %d: iterations %d, %d, %d, %d; after an unrelated right-hand side %d\n", as_pairs, iterations[0],
                iterations[1], iterations[2], iterations[3], report.iterations);
  }
}

TEST(CgStoppingRule, VelocityErrorBoundsTheTrueErrorOfAStoppedSolve)
{
  // CG stopped by the velocity rule alone (a relative tolerance it cannot reach first): at each
  // tolerance the reported bound is within it, and the true mass-weighted RMS error against the
  // dense solve is within the bound; and the solve stopped early, in fewer iterations than a solve
  // to round-off takes.
  for (unsigned seed : {1u, 2u, 3u})
  {
    const RandomSystem system = randomSystem(10, seed);
    const Eigen::Matrix3Xd exact = solveDense(system);
    SolverReport full;
    solveWith(system, cgSettings(1e-14, 0.0), full);
    ASSERT_TRUE(full.converged);
    int previous_iterations = -1;
    for (double tolerance : {1e-2, 1e-3, 1e-4, 1e-5})
    {
      SolverReport report;
      const Eigen::Matrix3Xd cg = solveWith(system, cgSettings(1e-300, tolerance), report);
      const double true_error = massWeightedRms(system, cg - exact);
      EXPECT_TRUE(report.converged) << "seed " << seed << ", tolerance " << tolerance;
      EXPECT_LE(report.velocity_error, tolerance) << "seed " << seed;
      EXPECT_LE(true_error, report.velocity_error) << "seed " << seed << ", tolerance " << tolerance;
      EXPECT_LT(report.iterations, full.iterations) << "seed " << seed << ", tolerance " << tolerance;
      EXPECT_GT(report.iterations, previous_iterations) << "a tighter tolerance takes more iterations";
      previous_iterations = report.iterations;
      std::printf("seed %u, tolerance %.0e m/s: %3d iterations, bound %.3e m/s, true error %.3e m/s\n", seed, tolerance,
                  report.iterations, report.velocity_error, true_error);
    }
  }
}

TEST(CgStoppingRule, TheBoundIsTheTrueErrorWhenTheSystemIsTheMassMatrix)
{
  // With no stiffness (A = M) and a tolerance the start already meets, CG stops at Δv = 0: its error
  // is the whole answer M⁻¹ b, and |M⁻¹ b|_M = |b|_M⁻¹, so the reported bound is the true error
  // itself. This pins the bound's normalisation (by the free particles' mass) that the loose
  // inequality of the stiff systems cannot.
  RandomSystem system = randomSystem(6, 5, 0.0);
  system.rhs *= 0.1;  // [kg·m/s]: an answer of about 0.1 m/s, within the tolerance of 1 m/s
  SolverReport report;
  const Eigen::Matrix3Xd stopped = solveWith(system, cgSettings(1e-300, 1.0), report);
  ASSERT_EQ(report.iterations, 0);
  EXPECT_EQ(stopped.cwiseAbs().maxCoeff(), 0.0);
  const double true_error = massWeightedRms(system, stopped - solveDense(system));
  EXPECT_GT(true_error, 0.01);  // [m/s]
  EXPECT_NEAR(report.velocity_error, true_error, 1e-12 * true_error);
}

TEST(CgStoppingRule, OnlyTheRelativeRuleWhenTheVelocityToleranceIsZero)
{
  // cg_velocity_tolerance 0: the solve goes on to the relative residual, far past the velocity
  // error the default would have stopped at.
  const RandomSystem system = randomSystem(10, 4);
  SolverReport report;
  const Eigen::Matrix3Xd cg = solveWith(system, cgSettings(1e-12, 0.0), report);
  EXPECT_TRUE(report.converged);
  EXPECT_LE(report.relative_residual, 1e-12);
  EXPECT_LT(report.velocity_error, IntegratorDef().cg_velocity_tolerance * 1e-3);
  EXPECT_LT(massWeightedRms(system, cg - solveDense(system)), 1e-9);
}

namespace
{
// Δv and x of one step at h = 1/60 from v0 of the system whose pairs are elements with
// ∂f/∂x = −terms[p] and ∂f/∂v = damping[p], added with addPairBlocks() (as_pairs) or with addBlock()
// on (i, i), (i, j), (j, i) and (j, j) with ±dfdx and ±dfdv, solved by `settings` with `threads`
// threads. `kept` is how many pairs the solver still kept aside after the solve. With `parts`, the
// pairs are a spring's instead (addAlongPairBlocks(); terms and damping are not read).
struct PairSolve
{
  Eigen::Matrix3Xd v, x;
  SolverReport report;
  int kept = 0;
};
// A spring's Jacobians by their parts: ∂f/∂x = along_x d dᵀ + isotropic_x I, ∂f/∂v = along_v d dᵀ.
struct SpringParts
{
  Eigen::Vector3d d;
  double along_x, isotropic_x, along_v;
};
PairSolve solvePairs(const RandomSystem& system, const std::vector<Eigen::Matrix3d>& damping,
                     const Eigen::Matrix3Xd& v0, bool as_pairs, const IntegratorDef& settings, int threads = 1,
                     const std::vector<SpringParts>* parts = nullptr)
{
  const double h = 1.0 / 60.0;
  WorkerPool workers(threads);
  ImplicitEulerSolver solver;
  solver.setWorkers(&workers);
  solver.setPattern(system.particles, system.pairs);
  solver.begin(h, system.mass, system.rhs, &v0);
  for (std::size_t p = 0; p < system.pairs.size(); ++p)
  {
    const auto [i, j] = system.pairs[p];
    const std::array<int, 4> blocks = {solver.blockIndex(i, i), solver.blockIndex(i, j), solver.blockIndex(j, i),
                                       solver.blockIndex(j, j)};
    if (parts)
    {
      const SpringParts& q = (*parts)[p];
      solver.addAlongPairBlocks(blocks, q.d, q.along_x, q.isotropic_x, q.along_v);
      continue;
    }
    const Eigen::Matrix3d dfdx = -system.terms[p];
    const Eigen::Matrix3d& dfdv = damping[p];
    if (as_pairs)
    {
      solver.addPairBlocks(blocks, dfdx, dfdv);
      continue;
    }
    solver.addBlock(blocks[0], dfdx, dfdv);
    solver.addBlock(blocks[1], -dfdx, -dfdv);
    solver.addBlock(blocks[2], -dfdx, -dfdv);
    solver.addBlock(blocks[3], dfdx, dfdv);
  }
  std::vector<RestingContact> contacts;
  PairSolve out;
  out.x = Eigen::Matrix3Xd::Zero(3, system.particles);
  out.v = v0;
  out.report = solver.solve(system.pinned, contacts, settings, out.x, out.v);
  out.kept = solver.keptPairs();
  return out;
}

// Random velocities v0 [m/s] and damping blocks −c d dᵀ (c up to 5 N·s/m) for a system's pairs.
void randomDampingAndVelocity(const RandomSystem& system, unsigned seed, std::vector<Eigen::Matrix3d>& damping,
                              Eigen::Matrix3Xd& v0)
{
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  v0.resize(3, system.particles);
  for (int i = 0; i < system.particles; ++i)
    v0.col(i) = Eigen::Vector3d(uniform(random), uniform(random), uniform(random));
  damping.clear();
  for (std::size_t p = 0; p < system.pairs.size(); ++p)
  {
    const Eigen::Vector3d d = Eigen::Vector3d(uniform(random), uniform(random), uniform(random)).normalized();
    const Eigen::Matrix3d along = d * d.transpose();  // symmetric bit for bit (scaled afterwards)
    damping.push_back(-2.5 * (1.0 + uniform(random)) * along);
  }
}

bool sameBits(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b)
{
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}
}  // namespace

TEST(ImplicitEulerSolver, PairBlocksAreTheSameBitsAsFourSingleBlocksForTheDirectSolver)
{
  // The direct solver needs A whole: the kept pairs go into their blocks in their order, so the
  // factorized system, and the step, are the same bits as four single blocks a pair make (with the
  // h² ∂f/∂x v0 terms of the right-hand side, and damping blocks).
  const RandomSystem system = randomSystem(8, 6);
  std::vector<Eigen::Matrix3d> damping;
  Eigen::Matrix3Xd v0;
  randomDampingAndVelocity(system, 7, damping, v0);
  IntegratorDef settings = cgSettings(1e-10, 0.0);
  settings.linear_solver = LinearSolverType::Direct;
  const PairSolve pairs = solvePairs(system, damping, v0, true, settings);
  const PairSolve singles = solvePairs(system, damping, v0, false, settings);
  ASSERT_TRUE(pairs.report.direct && pairs.report.converged);
  EXPECT_EQ(pairs.kept, 0);
  EXPECT_GT((pairs.v - v0).cwiseAbs().maxCoeff(), 1e-3);  // [m/s]: the step changed the velocities
  EXPECT_TRUE(sameBits(pairs.v, singles.v));
  EXPECT_TRUE(sameBits(pairs.x, singles.x));
}

TEST(ImplicitEulerSolver, SpringPartsMakeTheSystemOfTheFullBlocks)
{
  // addAlongPairBlocks() builds C and b's v0 term from a spring's parts (dfdx = a_x d dᵀ + b_x I,
  // dfdv = a_v d dᵀ) instead of the full blocks: the same step as addPairBlocks() with those blocks,
  // to rounding, through the direct solver (the pairs moved into A) and through the conjugate
  // gradient's pair product.
  const RandomSystem system = randomSystem(8, 9);
  std::mt19937_64 random(10);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<SpringParts> parts;
  RandomSystem full = system;  // the same springs by their full blocks
  std::vector<Eigen::Matrix3d> damping;
  for (std::size_t p = 0; p < system.pairs.size(); ++p)
  {
    const Eigen::Vector3d d = Eigen::Vector3d(uniform(random), uniform(random), uniform(random)).normalized();
    // A spring of up to 1e4 N/m with its transverse factor in [0, 0.5], damping up to 5 N·s/m.
    const double stiffness = 1e4 * (1.0 + uniform(random)) / 2.0, transverse = 0.25 * (1.0 + uniform(random));
    parts.push_back({d, -stiffness * (1.0 - transverse), -stiffness * transverse, -2.5 * (1.0 + uniform(random))});
    const SpringParts& q = parts.back();
    const Eigen::Matrix3d along = q.d * q.d.transpose();
    full.terms[p] = -(q.along_x * along + q.isotropic_x * Eigen::Matrix3d::Identity());
    damping.push_back(q.along_v * along);
  }
  Eigen::Matrix3Xd v0(3, system.particles);
  for (int i = 0; i < system.particles; ++i)
    v0.col(i) = Eigen::Vector3d(uniform(random), uniform(random), uniform(random));
  for (LinearSolverType linear_solver : {LinearSolverType::Direct, LinearSolverType::ConjugateGradient})
  {
    IntegratorDef settings = cgSettings(1e-13, 0.0);
    settings.linear_solver = linear_solver;
    const PairSolve from_parts = solvePairs(system, {}, v0, true, settings, 1, &parts);
    const PairSolve from_blocks = solvePairs(full, damping, v0, true, settings);
    EXPECT_TRUE(from_parts.report.converged);
    EXPECT_TRUE(from_blocks.report.converged);
    const double change = massWeightedRms(system, from_blocks.v - v0);
    EXPECT_GT(change, 1e-3);  // [m/s]: the step changed the velocities
    EXPECT_LT(massWeightedRms(system, from_parts.v - from_blocks.v), 1e-10 * change);
  }
}

TEST(ImplicitEulerSolver, ThePairProductSolvesTheSystemOfTheBlocks)
{
  // The conjugate gradient multiplies by the kept pairs (C (p_j − p_i) at i, its negative at j)
  // instead of the blocks: the same system, so both solves, to a relative residual of 1e-12, agree
  // with the dense LU of A = M + K (h = 1, v0 = 0 as in solveWith) to 1e-9 m/s, in about the same
  // iterations; the pairs were kept aside through the solve.
  for (unsigned seed : {11u, 12u})
  {
    const RandomSystem system = randomSystem(10, seed);
    const Eigen::Matrix3Xd exact = solveDense(system);
    int kept_pairs = 0, kept_singles = 0;
    SolverReport pairs, singles;
    const Eigen::Matrix3Xd v_pairs = solveWith(system, cgSettings(1e-12, 0.0), pairs, true, &kept_pairs);
    const Eigen::Matrix3Xd v_singles = solveWith(system, cgSettings(1e-12, 0.0), singles, false, &kept_singles);
    ASSERT_TRUE(pairs.converged && singles.converged);
    EXPECT_EQ(kept_pairs, static_cast<int>(system.pairs.size()));
    EXPECT_EQ(kept_singles, 0);
    EXPECT_GT(pairs.iterations, 20);
    EXPECT_LE(std::abs(pairs.iterations - singles.iterations), 2) << "seed " << seed;
    EXPECT_LT(massWeightedRms(system, v_pairs - exact), 1e-9) << "seed " << seed;
    EXPECT_LT(massWeightedRms(system, v_singles - exact), 1e-9) << "seed " << seed;
    EXPECT_GT(massWeightedRms(system, exact), 1e-3);  // [m/s]: an answer far from zero
  }
}

TEST(ImplicitEulerSolver, ThePairProductTakesWhatIsAddedToTheDiagonal)
{
  // addToDiagonal() beside kept pairs: a global damping's c m I keeps every particle's own diagonal
  // a multiple of the identity, which the product reads as one number a particle; any other block
  // (a general one, or equal diagonal entries with off-diagonal ones) makes it read the whole 3x3.
  // Either way the conjugate gradient, multiplying by the kept pairs, solves A = M + K + D: it agrees
  // with the dense LU of that system to 1e-9 m/s. One solver takes the three in turn, step after
  // step, so a step whose diagonal is a multiple of the identity follows one whose diagonal is not.
  const RandomSystem system = randomSystem(10, 41);
  std::mt19937_64 random(42);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  ImplicitEulerSolver solver;
  solver.setPattern(system.particles, system.pairs);
  enum class Kind
  {
    General,
    EqualDiagonal,
    Isotropic
  };
  for (const Kind kind : {Kind::General, Kind::EqualDiagonal, Kind::Isotropic})
  {
    const int label = static_cast<int>(kind);
    std::vector<Eigen::Matrix3d> diagonal(system.particles);  // D_i = −h ∂f_i/∂v_i, h = 1
    for (int i = 0; i < system.particles; ++i)
    {
      Eigen::Matrix3d g;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          g(r, c) = uniform(random);
      const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
      if (kind == Kind::General)
        diagonal[i] = 50.0 * g * g.transpose() + identity;
      else if (kind == Kind::EqualDiagonal)  // 30 I plus a symmetric part of zero diagonal, |entries| ≤ 10
        diagonal[i] = 30.0 * identity + 5.0 * (g + g.transpose() - Eigen::Matrix3d(g.diagonal().asDiagonal()) * 2.0);
      else
        diagonal[i] = 3.0 * system.mass[i] * identity;
    }
    solver.begin(1.0, system.mass, system.rhs, nullptr);
    for (std::size_t p = 0; p < system.pairs.size(); ++p)
    {
      const auto [i, j] = system.pairs[p];
      solver.addPairBlocks(
          {solver.blockIndex(i, i), solver.blockIndex(i, j), solver.blockIndex(j, i), solver.blockIndex(j, j)},
          -system.terms[p], Eigen::Matrix3d::Zero());
    }
    for (int i = 0; i < system.particles; ++i)
      solver.addToDiagonal(i, Eigen::Matrix3d::Zero(), -diagonal[i]);
    std::vector<RestingContact> contacts;
    Eigen::Matrix3Xd x = Eigen::Matrix3Xd::Zero(3, system.particles);
    Eigen::Matrix3Xd v = Eigen::Matrix3Xd::Zero(3, system.particles);
    const SolverReport report = solver.solve(system.pinned, contacts, cgSettings(1e-12, 0.0), x, v);
    ASSERT_TRUE(report.converged) << "kind " << label;
    EXPECT_EQ(solver.keptPairs(), static_cast<int>(system.pairs.size()));
    const Eigen::Matrix3Xd exact = solveDense(system, &diagonal);
    EXPECT_LT(massWeightedRms(system, v - exact), 1e-9) << "kind " << label;
    EXPECT_GT(massWeightedRms(system, exact), 1e-4);  // [m/s]: an answer far above that error
  }
}

TEST(ImplicitEulerSolver, ThePairProductIsTheSameBitsAtAnyThreadCount)
{
  // A 48 x 48 system is two chunks of rows: the pairs across them are visited by both chunks'
  // threads, each adding to its own rows only, in the pairs' order. One and two threads end in the
  // same bits, with the pairs kept; and the step agrees with the one of single blocks (a solve of the
  // same system) to far below the tolerance's error.
  const RandomSystem system = randomSystem(48, 21);
  std::vector<Eigen::Matrix3d> damping;
  Eigen::Matrix3Xd v0;
  randomDampingAndVelocity(system, 22, damping, v0);
  const IntegratorDef settings = cgSettings(1e-10, 0.0);
  const PairSolve one = solvePairs(system, damping, v0, true, settings, 1);
  const PairSolve two = solvePairs(system, damping, v0, true, settings, 2);
  const PairSolve singles = solvePairs(system, damping, v0, false, settings, 1);
  ASSERT_TRUE(one.report.converged && two.report.converged && singles.report.converged);
  EXPECT_EQ(one.kept, static_cast<int>(system.pairs.size()));
  EXPECT_EQ(one.report.iterations, two.report.iterations);
  EXPECT_TRUE(sameBits(one.v, two.v));
  EXPECT_TRUE(sameBits(one.x, two.x));
  const double change = (one.v - v0).cwiseAbs().maxCoeff();
  EXPECT_GT(change, 1e-3);  // [m/s]
  EXPECT_LT((one.v - singles.v).cwiseAbs().maxCoeff(), 1e-6 * change);
}

TEST(ImplicitEulerSolver, PairsWithoutLocalityAreMultipliedAsBlocks)
{
  // Pairs whose particles are numbered at random cross the five chunks of rows of a 96 x 96 system
  // (most of them would be visited twice): the solver moves them into the blocks and multiplies by
  // those, the same bits as four single blocks a pair.
  RandomSystem system = randomSystem(96, 31);
  std::vector<int> shuffled(system.particles);
  for (int i = 0; i < system.particles; ++i)
    shuffled[i] = i;
  std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937_64(32));
  for (auto& [i, j] : system.pairs)
    std::tie(i, j) = std::make_pair(shuffled[i], shuffled[j]);
  std::vector<Eigen::Matrix3d> damping;
  Eigen::Matrix3Xd v0;
  randomDampingAndVelocity(system, 33, damping, v0);
  const PairSolve pairs = solvePairs(system, damping, v0, true, cgSettings(1e-6, 0.0));
  const PairSolve singles = solvePairs(system, damping, v0, false, cgSettings(1e-6, 0.0));
  ASSERT_TRUE(pairs.report.converged);
  EXPECT_EQ(pairs.kept, 0);
  EXPECT_TRUE(sameBits(pairs.v, singles.v));
}

namespace
{
// A 16 x 16 spring cloth hanging from two corners, implicit Euler with CG.
ClothGridDef dampedHangingCloth()
{
  ClothGridDef def(ClothModel::Springs);
  def.name = "cloth";
  def.nu = def.nv = 16;
  def.mass = 0.5;
  def.stretch.stiffness = 500.0;
  def.shear.stiffness = 500.0;
  def.bend.stiffness = 20.0;
  def.named_pins = {"corner_00", "corner_10"};
  def.integrator.type = kImplicitEulerIntegrator;
  def.integrator.linear_solver = LinearSolverType::ConjugateGradient;
  def.integrator.cg_max_iterations = 100000;
  return def;
}
}  // namespace

TEST(CgStoppingRule, ABodyComingToRestCostsLittleUnderTheVelocityRule)
{
  // A damped cloth settling for 20 s. The relative rule asks for |r| <= 1e-8 |b| however small b
  // becomes, so it costs as many iterations at rest as in motion. The velocity rule (1e-5 m/s) stops
  // once the warm start (the last step's Δv) is that close: in the last second it costs under a
  // quarter as much, and the cloth is at rest to within 5 times its tolerance.
  ClothGridDef relative_def = dampedHangingCloth();
  relative_def.integrator.cg_velocity_tolerance = 0.0;
  ClothGridDef velocity_def = dampedHangingCloth();  // the defaults: 1e-8 relative or 1e-5 m/s
  SpringNetworkBody relative(buildClothGrid(relative_def)), velocity(buildClothGrid(velocity_def));
  const double tolerance = velocity.integrator().cg_velocity_tolerance;
  Environment env;
  env.ground.enabled = false;
  env.damping = 2.0;  // [1/s]: every speed falls by e^-40 in 20 s
  auto largestSpeed = [](const SpringNetworkBody& body) {
    const ParticlePool& p = body.particles();
    return p.velocity.leftCols(p.size()).colwise().norm().maxCoeff();
  };
  int relative_late = 0, velocity_late = 0;
  for (int step = 0; step < 1200; ++step)  // 20 s at 60 Hz
  {
    relative.step(1.0 / 60.0, env);
    velocity.step(1.0 / 60.0, env);
    ASSERT_TRUE(relative.lastSolve().converged) << "step " << step;
    ASSERT_TRUE(velocity.lastSolve().converged) << "step " << step;
    EXPECT_LE(velocity.lastSolve().velocity_error, tolerance) << "step " << step;
    if (step >= 1140)  // the last second
    {
      relative_late += relative.lastSolve().iterations;
      velocity_late += velocity.lastSolve().iterations;
    }
  }
  std::printf("last second: relative rule %d iterations (largest speed %.2e m/s), velocity rule %d (%.2e m/s)\n",
              relative_late, largestSpeed(relative), velocity_late, largestSpeed(velocity));
  EXPECT_LT(largestSpeed(velocity), 5.0 * tolerance);
  EXPECT_LT(4 * velocity_late, relative_late);
}
