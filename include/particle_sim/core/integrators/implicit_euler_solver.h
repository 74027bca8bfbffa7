#pragma once

#include <Eigen/Core>
#include <array>
#include <utility>
#include <vector>

#include "particle_sim/core/constraints/resting_contact.h"
#include "particle_sim/core/integrator.h"
#include "particle_sim/core/integrators/padded_vectors.h"
#include "particle_sim/core/integrators/smoothed_aggregation.h"
#include "particle_sim/core/integrators/sparse_block_ldlt.h"
#include "particle_sim/core/pair_chunks.h"
#include "particle_sim/core/worker_pool.h"

namespace particle_sim
{
namespace core
{
/// One step of linearised backward Euler (Baraff & Witkin 1998):
///
///   (M − h ∂f/∂v − h² ∂f/∂x) Δv = h (f0 + h ∂f/∂x v0),   v1 = v0 + Δv,   x1 = x0 + h v1,
///
/// solved by their modified preconditioned conjugate gradient: pinned particles' Δv is held at 0
/// by filtering every search direction and residual (no huge masses); 3x3 block-Jacobi
/// preconditioner, or under LinearSolverType::Multigrid one cycle of smoothed-aggregation multigrid
/// (SmoothedAggregation); warm start from the previous step's Δv. Particles resting on a collider are
/// held the same way along the surface's normal only (RestingContact): their normal velocity is
/// set to the surface's, and the rest of the system is solved for what remains. Or, by IntegratorDef::linear_solver,
/// directly (SparseBlockLdlt, the same filtered system), with CG iterations after it only if its
/// residual misses the tolerance; `auto` decides once per pattern from the two solvers' flop counts.
///
/// The matrix is block-sparse with 3x3 blocks. Its pattern (which particle pairs are coupled) is
/// set once per body by setPattern(); each step the force elements add their Jacobian blocks with
/// addBlock(), by the block index they looked up once with blockIndex(), and springs theirs with
/// addPairBlocks() (or addAlongPairBlocks(), from a spring's parts), which keeps one symmetric
/// block a spring for the conjugate gradient's product instead of writing four (see there).
/// Nothing allocates after the first steps.
///
/// Use per step: begin(), addBlock() for every element block, solve().
class ImplicitEulerSolver
{
public:
  /// The most linear solves one step makes while revising resting contacts' holds (1 + 2 · contacts
  /// would settle every hold; the pick_and_place demo's worst step takes 17).
  static constexpr int kMaxContactSolves = 64;

  /// Sets the pattern: every particle's diagonal block, and both (i, j) and (j, i) for each pair.
  void setPattern(int particles, const std::vector<std::pair<int, int>>& coupled_pairs);
  /// The index of block (row i, column j); -1 when the pattern has no such block.
  int blockIndex(int i, int j) const;

  /// Starts a step: A = M, b = h f0; remembers h and v0 (null: no h² ∂f/∂x v0 term in b, as in
  /// the Newton iterations, whose right-hand side is given whole in `force`).
  void begin(double h, const Eigen::VectorXd& mass, const Eigen::Matrix3Xd& force, const Eigen::Matrix3Xd* v0);
  /// Adds the block ∂f_i/∂x_j = dfdx, ∂f_i/∂v_j = dfdv at `block` (row i, column j):
  /// A_ij −= h dfdv + h² dfdx and b_i += h² dfdx v0_j. The pairs kept so far are written into their
  /// blocks first, so that every block gets its terms in the order they were added.
  void addBlock(int block, const Eigen::Matrix3d& dfdx, const Eigen::Matrix3d& dfdv)
  {
    if (!pairs_in_blocks_) movePairsIntoBlocks();
    moveDiagonalIntoBlocks();
    adds_blocks_ = true;
    addToBlock(block, dfdx, dfdv);
  }
  /// Adds ∂f_i/∂x_i = dfdx, ∂f_i/∂v_i = dfdv to particle i's diagonal block (and to its diagonal
  /// without the pairs' part, for the pair product).
  void addToDiagonal(int i, const Eigen::Matrix3d& dfdx, const Eigen::Matrix3d& dfdv)
  {
    diagonalBlock(i).noalias() -= h_ * dfdv + h_ * h_ * dfdx;
    if (v0_) rhs_.col(i).noalias() += h_ * h_ * (dfdx * v0_->col(i));
    Eigen::Matrix3d& own = own_diagonal_[i];
    own.noalias() -= h_ * dfdv + h_ * h_ * dfdx;
    // Still a multiple of the identity (a global damping's term is): the product keeps its number.
    own_scale_[i] = own(0, 0);
    own_isotropic_ = own_isotropic_ && own(1, 1) == own(0, 0) && own(2, 2) == own(0, 0) && own(1, 0) == 0.0 &&
                     own(2, 0) == 0.0 && own(2, 1) == 0.0 && own(0, 1) == 0.0 && own(0, 2) == 0.0 && own(1, 2) == 0.0;
  }
  /// Adds a two-particle element whose Jacobians are ∂f_i/∂x_i = ∂f_j/∂x_j = −∂f_i/∂x_j =
  /// −∂f_j/∂x_i = dfdx (alike for v), both symmetric bit for bit as a spring's are, at `blocks` =
  /// (i, i), (i, j), (j, i), (j, j). C = h dfdv + h² dfdx goes into the diagonal blocks at once
  /// (A_ii −= C, A_jj −= C); for A_ij = A_ji += C the pair is kept, as (i, j) and the six numbers
  /// of C's lower triangle, in the order of the calls. The conjugate gradient multiplies by the
  /// pairs themselves: C (p_j − p_i) at i and its negative at j, one symmetric block read and one
  /// 3x3 product a spring, where A's blocks cost two full blocks and two products. The pairs go into
  /// the off-diagonal blocks, in their order, only when a solve needs A whole (the direct solver,
  /// resting contacts) or an element adds a block with addBlock(): A is then the same bits as if
  /// they had been added at once. Inline: called for every spring of every implicit step.
  [[gnu::always_inline]] void addPairBlocks(const std::array<int, 4>& blocks, const Eigen::Matrix3d& dfdx,
                                            const Eigen::Matrix3d& dfdv)
  {
    const Eigen::Matrix3d c = h_ * dfdv + h_ * h_ * dfdx;
    addPairC(blocks, c.data());
    if (!v0_) return;
    const int i = block_row_[blocks[0]], j = block_row_[blocks[3]];
    const Eigen::Vector3d at_i = h_ * h_ * (dfdx * v0_->col(i));
    const Eigen::Vector3d at_j = h_ * h_ * (dfdx * v0_->col(j));
    rhs_.col(i) += at_i;
    rhs_.col(i) -= at_j;
    rhs_.col(j) -= at_i;
    rhs_.col(j) += at_j;
  }
  /// addPairBlocks() for Jacobians of a spring's form along the unit vector d: dfdx = along_x d dᵀ +
  /// isotropic_x I, dfdv = along_v d dᵀ (springJacobianParts()). Then C = (h along_v + h² along_x)
  /// d dᵀ + h² isotropic_x I, and b's term h² dfdx (v0_i − v0_j) = h² (along_x (d·u) d +
  /// isotropic_x u) with u = v0_i − v0_j: about half the arithmetic of the full blocks, the same
  /// system but for rounding (C: alongPairC()).
  [[gnu::always_inline]] void addAlongPairBlocks(const std::array<int, 4>& blocks, const Eigen::Vector3d& d,
                                                 double along_x, double isotropic_x, double along_v)
  {
    double c[9];
    alongPairC(d, along_x, isotropic_x, along_v, c);
    addPairC(blocks, c);
    if (!v0_) return;
    const int i = block_row_[blocks[0]], j = block_row_[blocks[3]];
    const Eigen::Vector3d change = alongRhsChange(i, j, d, along_x, isotropic_x);
    rhs_.col(i) += change;
    rhs_.col(j) -= change;
  }
  /// Whether addAlongPairEnds() may be used now: the diagonal blocks and the pairs are still kept
  /// apart from A's blocks in this step.
  bool pairEndsShareable() const { return keptApart(); }
  /// Room for `count` more kept pairs, numbered from the index returned on (addAlongPairEnds()).
  int reservePairs(int count)
  {
    while (kept_pairs_ + count > static_cast<int>(pair_ends_.size()))
      growPairs();
    const int first = kept_pairs_;
    kept_pairs_ += count;
    return first;
  }
  /// addAlongPairBlocks() of the pair numbered `pair` (reservePairs()) by its ends, for a loop shared
  /// by chunks of particles in which each chunk's thread visits the springs that touch the chunk, in
  /// order, and adds only to their ends inside it (PairChunks): A_ii −= C and b_i's term at end i
  /// (kAddI), likewise at end j (kAddJ), each particle's terms in the order of the one-thread loop.
  /// The call with end i keeps the pair; it returns whether the pair's particles differ from the
  /// last step's pair at that place (the caller then calls notePairsChanged()). Only while
  /// pairEndsShareable().
  template <bool kAddI, bool kAddJ>
  [[gnu::always_inline]] bool addAlongPairEnds(int pair, const std::array<int, 4>& blocks, const Eigen::Vector3d& d,
                                               double along_x, double isotropic_x, double along_v)
  {
    double c[9];
    alongPairC(d, along_x, isotropic_x, along_v, c);
    const int i = block_row_[blocks[0]], j = block_row_[blocks[3]];
    bool changed = false;
    if (kAddI)
    {
      subtractC(diagonal_[i], c);
      changed = storePair(pair, blocks, c);
    }
    if (kAddJ) subtractC(diagonal_[j], c);
    if (!v0_) return changed;
    const Eigen::Vector3d change = alongRhsChange(i, j, d, along_x, isotropic_x);
    if (kAddI) rhs_.col(i) += change;
    if (kAddJ) rhs_.col(j) -= change;
    return changed;
  }
  /// After addAlongPairEnds() calls of which one returned true.
  void notePairsChanged() { pairs_changed_ = true; }
  /// Solves for Δv with pinned rows filtered and resting contacts held, then v += Δv, x += h v.
  /// Pinned particles keep the velocity in v (the one that carries them to their target). Each
  /// contact whose particle is not leaving its surface is held (RestingContact: stuck, sliding or let
  /// go, decided by the impulses of solves repeated until no hold changes); what was decided and the
  /// impulses are written back.
  SolverReport solve(const std::vector<char>& pinned, std::vector<RestingContact>& contacts,
                     const IntegratorDef& settings, Eigen::Matrix3Xd& x, Eigen::Matrix3Xd& v);
  /// Whether `solver` means the direct solver for this pattern. `auto` compares the flop count of one
  /// factorization and solve with kDirectSolverCgIterations CG iterations (analysed once), and
  /// switches to the direct solver for good once a CG solve took more iterations than that count.
  bool usesDirect(LinearSolverType solver);
  /// One factorization and solve of the direct solver for this pattern, in CG iterations (their flop
  /// counts: 18 a block of A and about 40 a particle for one iteration), and whether the direct
  /// solver takes its supernodal form there (`supernodal`, if not null). Analyses the pattern
  /// (allocates): for decisions taken once.
  double directCostInCgIterations(bool* supernodal = nullptr) const;
  /// A multigrid solve of `iterations` iterations for this pattern, in CG iterations (flops:
  /// SmoothedAggregation::setupFlops() and cycleFlops(), the part of them that is not
  /// finestCycleFlops() weighted by kMultigridFlopWeight, and per iteration a CG iteration's product
  /// and vector passes), from the hierarchy of the last multigrid solve.
  double multigridCostInCgIterations(int iterations) const;
  /// The pairs kept by addPairBlocks() in this step, not yet in the blocks of A (for tests).
  int keptPairs() const { return pairs_in_blocks_ ? 0 : kept_pairs_; }
  /// Forgets the warm start (after a reset or a jump of the state).
  void clearWarmStart()
  {
    delta_v_.setZero();
    start_.setZero();
    previous_start_.setZero();
    older_start_.setZero();
    multigrid_.forgetHistory();
  }
  /// Threads to share the conjugate gradient's per-particle loops with (null: none). Its products,
  /// vector updates and sums are shared by rows; each sum is taken in fixed chunks of rows and then
  /// chunk after chunk, so that the result is the same bits at any thread count.
  /// The multigrid's passes over nodes are shared with them too (SmoothedAggregation::setWorkers()).
  void setWorkers(WorkerPool* workers)
  {
    workers_ = workers;
    multigrid_.setWorkers(workers);
    direct_.setWorkers(workers);
  }
  /// Whether the conjugate gradient's passes run a particle's three coordinates in one 256-bit
  /// register (cg_avx2.h), which they do where the processor has AVX2, with the same bits as the
  /// scalar passes. Off forces the scalar passes (for the test that compares the two, and for
  /// benchmarks); on takes effect only where the processor has AVX2. For every solver at once, and
  /// for the direct solver's supernodal products too (SparseBlockLdlt::setUseAvx2()), and the
  /// springs' force pass and Jacobian parts (addSpringForcesOf(), springJacobianPartsOf()).
  static bool useAvx2();
  static void setUseAvx2(bool use);

private:
  // A_ij −= h dfdv + h² dfdx at `block` (row i, column j) and b_i += h² dfdx v0_j.
  void addToBlock(int block, const Eigen::Matrix3d& dfdx, const Eigen::Matrix3d& dfdv)
  {
    blocks_[block].noalias() -= h_ * dfdv + h_ * h_ * dfdx;
    if (v0_) rhs_.col(block_row_[block]).noalias() += h_ * h_ * (dfdx * v0_->col(block_column_[block]));
  }
  // C of addAlongPairBlocks(), entry by entry as Eigen evaluates (a d dᵀ + b I): (a d_r) d_c +
  // b I_rc with a = h along_v + h² along_x and b = h² isotropic_x (so C_rc and C_cr may differ in
  // the last bit; a kept pair is the lower triangle), column-major, into numbers the compiler keeps
  // in registers: a 3x3 matrix written to the stack and read back in halves stalled the assembly on
  // every spring.
  [[gnu::always_inline]] void alongPairC(const Eigen::Vector3d& d, double along_x, double isotropic_x, double along_v,
                                         double* c) const
  {
    const double h2 = h_ * h_;
    const double a = h_ * along_v + h2 * along_x, b = h2 * isotropic_x, b_off = b * 0.0;
    const double ad[3] = {a * d[0], a * d[1], a * d[2]};
#pragma GCC unroll 3
    for (int column = 0; column < 3; ++column)
#pragma GCC unroll 3
      for (int row = 0; row < 3; ++row)
        c[row + 3 * column] = ad[row] * d[column] + (row == column ? b : b_off);
  }
  // b's term of addAlongPairBlocks() at end i (its negative at j).
  [[gnu::always_inline]] Eigen::Vector3d alongRhsChange(int i, int j, const Eigen::Vector3d& d, double along_x,
                                                        double isotropic_x) const
  {
    const Eigen::Vector3d u = v0_->col(i) - v0_->col(j);
    return h_ * h_ * (along_x * d.dot(u) * d + isotropic_x * u);
  }
  // block −= C and block += C, C's nine numbers column-major.
  [[gnu::always_inline]] static void subtractC(Eigen::Matrix3d& block, const double* c)
  {
#pragma GCC unroll 9
    for (int k = 0; k < 9; ++k)
      block.data()[k] -= c[k];
  }
  [[gnu::always_inline]] static void addC(Eigen::Matrix3d& block, const double* c)
  {
#pragma GCC unroll 9
    for (int k = 0; k < 9; ++k)
      block.data()[k] += c[k];
  }
  // A_ii −= C, A_jj −= C, and A_ij = A_ji += C, kept as a pair until the blocks are needed
  // (addPairBlocks()); C's nine numbers column-major.
  [[gnu::always_inline]] void addPairC(const std::array<int, 4>& blocks, const double* c)
  {
    if (diagonal_in_blocks_)
    {
      subtractC(blocks_[blocks[0]], c);
      subtractC(blocks_[blocks[3]], c);
    }
    else
    {
      subtractC(diagonal_[block_row_[blocks[0]]], c);
      subtractC(diagonal_[block_row_[blocks[3]]], c);
    }
    if (pairs_in_blocks_)
    {
      addC(blocks_[blocks[1]], c);
      addC(blocks_[blocks[2]], c);
    }
    else
    {
      keepPair(blocks, c);
    }
  }
  // Keeps pair C (addPairBlocks()); notes when its particles differ from the last step's pair at
  // this place in the list (the pair chunks are then indexed again).
  [[gnu::always_inline]] void keepPair(const std::array<int, 4>& blocks, const double* c)
  {
    if (kept_pairs_ == static_cast<int>(pair_ends_.size())) growPairs();
    if (storePair(kept_pairs_++, blocks, c)) pairs_changed_ = true;
  }
  // Whether the diagonal blocks and the pairs are both still kept apart from A's blocks this step.
  bool keptApart() const
  {
    return !diagonal_in_blocks_ && !pairs_in_blocks_;
  }
  // Pair C as number k of the kept list; whether its particles differ from the last step's there.
  [[gnu::always_inline]] bool storePair(int k, const std::array<int, 4>& blocks, const double* c)
  {
    const int i = block_row_[blocks[0]], j = block_row_[blocks[3]];
    const bool changed = pair_ends_[k][0] != i || pair_ends_[k][1] != j;
    pair_ends_[k] = {i, j};
    pair_blocks_[k] = {blocks[1], blocks[2]};
    pair_c_[k] = {c[0], c[1], c[2], c[4], c[5], c[8]};
    return changed;
  }
  // Writes the diagonal blocks A_ii from diagonal_ into their places in blocks_, once a step, for
  // what reads A whole (the direct solver, the multigrid's setup, resting contacts, the product by
  // the blocks, elements that add blocks of their own); later terms then go to blocks_ (the same
  // sums in the same order: the same bits).
  void moveDiagonalIntoBlocks();
  // A_ii, wherever it is this step.
  const Eigen::Matrix3d& diagonalBlock(int i) const
  {
    return diagonal_in_blocks_ ? blocks_[diagonal_block_[i]] : diagonal_[i];
  }
  Eigen::Matrix3d& diagonalBlock(int i) { return diagonal_in_blocks_ ? blocks_[diagonal_block_[i]] : diagonal_[i]; }
  // Indexes the first `pairs` pairs of pair_ends_ by chunks of `rows` rows (pair_chunks_).
  void indexPairs(int pairs, int rows);
  // More room for kept pairs (setPattern() makes room for one a coupled pair, so only a body with
  // more pair elements than coupled pairs gets here).
  void growPairs();
  // Adds every kept pair's C to its off-diagonal blocks (i, j) and (j, i), in the pairs' order; from
  // now on in this step addPairBlocks() writes them there at once.
  void movePairsIntoBlocks();
  // Makes the pair product ready for this step's kept pairs: the pair chunks, indexed again when
  // the list changed. False when it is not worth it (pairs without locality, more
  // than a quarter of them across two chunks of rows): the pairs are then moved into the blocks.
  bool preparePairProduct();
  // out = A p on the rows [first, last) of chunk `chunk` of kRowsPerChunk rows, from the kept pairs:
  // (A p)_i = E_i p_i + Σ over the pairs at i, in list order, of ±C (p_j − p_i) (+ at end i, − at j),
  // with E_i = A_ii + Σ C its diagonal block without the pairs' part (own_diagonal_).
  void multiplyPairRows(const PaddedVectors& p, PaddedVectors& out, int chunk, int first, int last) const;
  // CG iterations from delta_v_ until the filtered residual is within cg_tolerance |b|, or the
  // velocity error it bounds within cg_velocity_tolerance, or `max_iterations`. When the start is
  // far from them, it first moves the start along the last solves' change, by the step that
  // minimises the error's A-norm (extrapolateStart()).
  void conjugateGradient(const std::vector<char>& pinned, const IntegratorDef& settings, int max_iterations,
                         SolverReport& report);
  // The start Δv + β d, with d the change from the last start that a quadratic through the last three
  // starts gives (Δv_n ≈ 3 Δv_{n−1} − 3 Δv_{n−2} + Δv_{n−3}, so d = 2 start_ − 3 previous_start_ +
  // older_start_, filtered) and β = dᵀr / dᵀAd, the minimum of the error's A-norm along d (so never
  // further from the solution in that norm than Δv). Updates Δv (the padded copy) and the residual
  // r = b − A Δv; one product by A. False when d is zero or dᵀAd is not positive (nothing changed).
  bool extrapolateStart(const std::vector<char>& pinned, bool pair_product);
  // Flops of one CG iteration (directCostInCgIterations()).
  double cgIterationFlops() const;
  // `auto`'s multigrid solve (solveLinear()): false, with the multigrid rejected for good, when it
  // did not converge (CG then finishes the solve).
  bool autoMultigrid(const std::vector<char>& pinned, const IntegratorDef& settings, SolverReport& report);
  // The same conjugate gradient and stopping rule, preconditioned by a cycle of multigrid_ (set up
  // for this system first) instead of block Jacobi; block Jacobi's when the hierarchy is not definite.
  void multigridConjugateGradient(const std::vector<char>& pinned, const IntegratorDef& settings, SolverReport& report);
  // y = Ã x for the multigrid (SmoothedAggregation::setFinestProduct()), on 3 x particles numbers,
  // from the kept pairs: A x with the rows of the pinned particles zero (x is zero there, so A's
  // pinned columns do not count).
  void multiplyFilteredPairs(const std::vector<char>& pinned, const double* x, double* y);
  struct ResidualNorms
  {
    double euclidean;  // |r|
    double velocity;   // [m/s] sqrt(Σ |r_i|² / m_i / free_mass): SolverReport::velocity_error
  };
  // Whether CG may stop: |r| within cg_tolerance |b|, or the velocity error within cg_velocity_tolerance.
  static bool withinTolerance(const ResidualNorms& norms, double rhs_norm, const IntegratorDef& settings)
  {
    return norms.euclidean <= settings.cg_tolerance * rhs_norm || norms.velocity <= settings.cg_velocity_tolerance;
  }
  // [kg] the mass of the particles that are not pinned.
  double freeMass(const std::vector<char>& pinned) const;
  ResidualNorms residualNorms(const Eigen::Matrix3Xd& r, double free_mass) const;
  // The norms from the sums Σ |r_i|² and Σ |r_i|² / m_i.
  static ResidualNorms normsOf(double squared, double weighted, double free_mass);
  // One chunk's sums in an iteration: r·z, |r|² and Σ |r_i|² / m_i.
  struct ResidualSums
  {
    double preconditioned = 0.0, squared = 0.0, weighted = 0.0;
  };
  // out = A p, all rows: from the kept pairs when `pair_product`, else from the blocks.
  void multiply(const PaddedVectors& p, PaddedVectors& out, bool pair_product) const;
  // out = A p on rows [begin, end).
  void multiplyRows(const PaddedVectors& p, PaddedVectors& out, int begin, int end) const;
  static void filter(const std::vector<char>& pinned, Eigen::Matrix3Xd& p);
  void precondition(const Eigen::Matrix3Xd& r, Eigen::Matrix3Xd& out) const;
  // Decides which contacts are held and turns the system into one for the rest (keeping the
  // original first when `keep_system`): true when any is.
  bool holdContacts(const std::vector<char>& pinned, std::vector<RestingContact>& contacts, const Eigen::Matrix3Xd& v,
                    bool keep_system);
  // After a solve: each held contact's impulse; those that pull are let go, stuck ones outside the
  // friction cone slip (true if any was).
  bool reviseHolds(std::vector<RestingContact>& contacts);
  // The linear solve of the (filtered) system in blocks_ and rhs_ for delta_v_.
  SolverReport solveLinear(const std::vector<char>& pinned, const IntegratorDef& settings);
  // Δv by the direct solver (factorize and solve the filtered system); false, Δv untouched, when a
  // pivot block is singular or not finite.
  bool solveDirectly(const std::vector<char>& pinned);

  // Block-sparse rows: row i has blocks row_start_[i] .. row_start_[i + 1] − 1.
  std::vector<int> row_start_, block_row_, block_column_, diagonal_block_;
  std::vector<int> transpose_block_;  // the index of block (j, i) for block (i, j)
  std::vector<Eigen::Matrix3d> blocks_;
  // The diagonal blocks A_ii, one a particle in particle order, while diagonal_in_blocks_ is false
  // (from begin() on): the springs' assembly adds two of them a spring and CG's preconditioner reads
  // them all, and in blocks_ they lie one a row of the pattern, a few hundred bytes apart.
  std::vector<Eigen::Matrix3d> diagonal_;
  bool diagonal_in_blocks_ = true;
  // The pairs of addPairBlocks() (struct of arrays, kept_pairs_ of them in this step): their
  // particles (i, j), their off-diagonal blocks (i, j) and (j, i), and C's lower triangle by columns
  // (C00, C10, C20, C11, C21, C22).
  std::vector<std::array<int, 2>> pair_ends_, pair_blocks_;
  std::vector<std::array<double, 6>> pair_c_;
  int kept_pairs_ = 0;
  bool pairs_in_blocks_ = true;     // the kept pairs are in blocks_ (and addPairBlocks() writes there)
  bool adds_blocks_ = false;        // addBlock() was called since setPattern(): pairs are not kept
  bool pairs_changed_ = true;       // the list differs from the one pair_chunks_ indexes
  int indexed_pairs_ = -1;          // how many pairs pair_chunks_ indexes
  bool off_diagonal_zero_ = false;  // every off-diagonal block of blocks_ is zero
  PairChunks pair_chunks_;          // the pairs by chunks of kRowsPerChunk rows
  // E_i = A_ii + Σ C over the pairs at i: M_i and what addToDiagonal() added, in this step (an
  // element that adds blocks with addBlock() moves the pairs into the blocks, so E is not used).
  std::vector<Eigen::Matrix3d> own_diagonal_;
  // While every E_i is e_i I (the masses, and any global damping), the product reads e_i alone
  // (multiplyPairRows()): a ninth of E's numbers, the same result.
  std::vector<double> own_scale_;
  bool own_isotropic_ = true;
  std::vector<Eigen::Matrix3d> inverse_diagonal_;
  std::vector<double> inverse_mass_;  // 1/m per particle (0 where m is 0), set by begin()
  SparseBlockLdlt direct_;
  SmoothedAggregation multigrid_;                // LinearSolverType::Multigrid's preconditioner
  bool multigrid_planned_ = false;               // multigrid_ has this pattern
  const Eigen::Matrix3Xd* positions_ = nullptr;  // x of the step being solved (the multigrid's modes)
  enum class DirectChoice
  {
    Undecided,
    Cheaper,
    Dearer
  } auto_choice_ = DirectChoice::Undecided;
  double direct_in_cg_iterations_ = 0.0;  // one factorization and solve, in CG iterations (flops)
  // `auto`'s multigrid: not tried yet; on trial in the next solve; chosen; or not (for good).
  enum class MultigridChoice
  {
    Untried,
    Trying,
    Chosen,
    Rejected
  } multigrid_choice_ = MultigridChoice::Untried;
  int trial_cg_iterations_ = 0;  // the CG solve's iterations that led to the multigrid's trial
  double h_ = 0.0;
  const Eigen::Matrix3Xd* v0_ = nullptr;
  const Eigen::VectorXd* mass_ = nullptr;
  WorkerPool* workers_ = nullptr;
  // Held contacts: the velocity change z each is given (0 elsewhere), and the original rows A_ij of
  // their particles and b_i (for the impulse), contact after contact.
  Eigen::Matrix3Xd held_change_;
  std::vector<Eigen::Matrix3d> held_rows_;
  std::vector<Eigen::Vector3d> held_rhs_;
  std::vector<Eigen::Matrix3d> original_blocks_;  // the system before holding, for a solve again
  Eigen::Matrix3Xd original_rhs_;
  // Per chunk of rows, an iteration's sums (conjugateGradient()).
  std::vector<double> curvature_chunks_;
  std::vector<ResidualSums> residual_chunks_;
  Eigen::Matrix3Xd delta_v_, rhs_, residual_, preconditioned_;
  // The Δv each of the last three linear solves started from (the solution of the solve before it),
  // the latest first: conjugateGradient() moves its start along their extrapolation first.
  Eigen::Matrix3Xd start_, previous_start_, older_start_;
  Eigen::Matrix3Xd multigrid_direction_, multigrid_product_;  // multigridConjugateGradient()'s d and A d
  // CG's iterations: Δv, the residual r, the preconditioned residual z, the direction d and the
  // product A d, padded for the AVX2 passes (PaddedVectors).
  PaddedVectors padded_delta_v_, padded_residual_, padded_preconditioned_, direction_, product_;
};

}  // namespace core
}  // namespace particle_sim
