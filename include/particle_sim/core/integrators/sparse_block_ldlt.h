#pragma once

#include <Eigen/Core>
#include <array>
#include <climits>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "particle_sim/core/integrators/dense_panel.h"

namespace particle_sim
{
namespace core
{
class WorkerPool;

/// out = a b, inline, the same bits as Eigen's `out.noalias() = a * b` (Eigen 3.4, SSE2): each
/// coefficient summed in Eigen's order, rows 0 and 1 (a packet) left to right, row 2 (a scalar
/// reduction) with its last two terms first. For a loop where GCC calls Eigen's product out of line.
inline void multiplyInline(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b, Eigen::Matrix3d& out)
{
  for (int c = 0; c < 3; ++c)
  {
    const double b0 = b(0, c), b1 = b(1, c), b2 = b(2, c);
    out(0, c) = (a(0, 0) * b0 + a(0, 1) * b1) + a(0, 2) * b2;
    out(1, c) = (a(1, 0) * b0 + a(1, 1) * b1) + a(1, 2) * b2;
    out(2, c) = a(2, 0) * b0 + (a(2, 1) * b1 + a(2, 2) * b2);
  }
}

/// A direct solver for the implicit methods' symmetric block-sparse systems (3x3 blocks, one block
/// row per particle): A = L D Lᵀ with L unit lower triangular and D block diagonal, in a
/// fill-reducing order of the particles (approximate minimum degree, Amestoy, Davis & Duff 1996).
///
/// analyze() runs once per pattern: the ordering, the elimination tree (Liu 1986) and the pattern of
/// L, and for every block of A and every update of the elimination the slot it lands in. factorize()
/// and solve() then allocate nothing and visit only the blocks of L. On a chain (a rope, with or
/// without bend springs) L has no fill, so a step costs O(particles); on a 2-D sheet the fill grows
/// like n log n and the work like n^1.5, so the conjugate gradient is cheaper there for large n
/// (ImplicitEulerSolver's `auto` compares the two costs: flops()).
///
/// Where most of the work lies in wide supernodes (runs of columns of L with one pattern below
/// them: the separators of a 2-D sheet), analyze() takes the supernodal form instead: each supernode
/// is one dense column-major panel, factored as scalar L D Lᵀ by products of many columns at once
/// (dense_panel.h, on AVX-512 or AVX2 where the processor has it), and subtracts its update from the
/// panels of the supernodes above it. A chain has no wide supernodes and keeps the 3x3 blocks.
///
/// Pinned particles are solved as identity rows (their Δv is 0), which is the filtered system that
/// Baraff & Witkin's modified conjugate gradient solves.
class SparseBlockLdlt
{
public:
  /// The pattern of A by block rows: row i holds the blocks row_start[i] .. row_start[i + 1] − 1, of
  /// columns block_column[k] (sorted, the diagonal included), symmetric in pattern.
  void analyze(const std::vector<int>& row_start, const std::vector<int>& block_column);
  bool analyzed() const { return !column_start_.empty(); }

  /// Floating-point operations of one factorize() and of one solve() (from the pattern of L).
  double factorFlops() const { return factor_flops_; }
  double solveFlops() const { return solve_flops_; }
  /// Whether analyze() took the supernodal form.
  bool supernodal() const { return !supernodes_.empty(); }
  /// Whether the supernodal form's dense products take vector tiles (the same bits either way; where
  /// the processor has AVX2 and FMA, by default); setting true takes the widest the processor has,
  /// false the scalar ones.
  static bool useAvx2();
  static void setUseAvx2(bool use);
  /// The form of those products (dense_panel::Tiles, every form the same bits): the widest the
  /// processor has by default; setTiles() takes the one asked for, or the widest below it that the
  /// processor has.
  static dense_panel::Tiles tiles();
  static void setTiles(dense_panel::Tiles form);
  /// Off-diagonal blocks of L.
  std::int64_t factorBlocks() const { return static_cast<std::int64_t>(row_index_.size()); }

  /// Threads for factorize() and solve() (null: the caller's alone). With two or more, the
  /// supernodal form's tree of supernodes is cut, once per pattern, into two sets of whole subtrees
  /// of about equal work, each factored by one thread, and the supernodes above them, factored after
  /// both (see planSubtrees()). Every entry of L and of the solution gets the same terms in the same
  /// order as on one thread: the same bits.
  void setWorkers(WorkerPool* workers) { workers_ = workers; }
  /// The factorization's flops in the two sets of subtrees that two threads share, over all of
  /// them (0 when none are planned: no supernodal form, or no cut worth it).
  double sharedShare() const { return shared_share_; }

  /// What analyze() would find, from the pattern alone (L is not built): whether the direct solver
  /// is worth analysing at all.
  struct Cost
  {
    std::int64_t factor_blocks = 0;  ///< off-diagonal blocks of L
    double factor_flops = 0.0;       ///< of one factorize()
    double solve_flops = 0.0;        ///< of one solve()
    bool supernodal = false;         ///< whether analyze() would take the supernodal form
  };
  static Cost estimateCost(const std::vector<int>& row_start, const std::vector<int>& block_column);

  /// L D Lᵀ of the matrix whose blocks (in analyze()'s block order) are `blocks`, with the rows and
  /// columns of pinned particles replaced by the identity. False when a pivot block is singular or
  /// not finite (then the factors are not usable).
  bool factorize(const std::vector<Eigen::Matrix3d>& blocks, const std::vector<char>& pinned);
  /// x = A⁻¹ b for the last factorization; pinned columns of b must be 0 (x's are then 0).
  void solve(const Eigen::Matrix3Xd& b, Eigen::Matrix3Xd& x);
  /// factorize(), then solve() (false, and x untouched, where factorize() is false): the same
  /// numbers, but with two threads the shares' forward passes of the solve run beside the
  /// factorization of the last panel above them, which one thread does alone.
  bool factorizeAndSolve(const std::vector<Eigen::Matrix3d>& blocks, const std::vector<char>& pinned,
                         const Eigen::Matrix3Xd& b, Eigen::Matrix3Xd& x);

  /// A matrix by its diagonal blocks and its pairs of off-diagonal blocks (ImplicitEulerSolver's
  /// kept pairs): block (i, i), at diagonal_block[i] in analyze()'s block order, is diagonal[i]; pair
  /// k adds its symmetric C (lower triangle C00, C10, C20, C11, C21, C22: c[k]) to blocks
  /// blocks[k] = ((i, j), (j, i)), pair after pair, onto zero; every other block is zero.
  struct PairedMatrix
  {
    const Eigen::Matrix3d* diagonal = nullptr;
    const int* diagonal_block = nullptr;
    int pairs = 0;
    const std::array<int, 2>* blocks = nullptr;
    const std::array<double, 6>* c = nullptr;
  };
  /// factorizeAndSolve() of that matrix, taken into the supernodes' panels straight from its
  /// diagonal and pairs (its blocks are never built): the same numbers as from its blocks. For the
  /// supernodal form (supernodal()); false without it.
  bool factorizeAndSolve(const PairedMatrix& matrix, const std::vector<char>& pinned, const Eigen::Matrix3Xd& b,
                         Eigen::Matrix3Xd& x);

private:
  // The order: new_of_[old] and old_of_[new] particle indices.
  std::vector<int> new_of_, old_of_;
  // L by columns (new indices): column j holds rows row_index_[column_start_[j] ..
  // column_start_[j + 1] − 1], ascending, all > j, with blocks lower_[...].
  std::vector<int> column_start_, row_index_;
  std::vector<Eigen::Matrix3d> lower_;
  std::vector<Eigen::Matrix3d> pivot_, pivot_inverse_;  // D_j and D_j⁻¹
  // Where each block k of A goes: a slot of lower_ (>= 0), or −1 − j for pivot j, or kUnused for
  // the upper triangle (A is symmetric; the lower block is used).
  static constexpr int kUnused = INT32_MIN;
  std::vector<int> block_slot_;
  std::vector<int> block_row_new_, block_column_new_;  // each block's (row, column) in the new order
  // The elimination's updates: for column j, for each pair (k ≤ i) of its rows, the slot of (i, k)
  // in L (or −1 − i for the pivot i when i == k), in the order factorize() visits them.
  std::vector<int> update_slot_;
  std::vector<char> pinned_new_;

  // The supernodal form (empty when analyze() keeps the 3x3 blocks). Supernode s holds the block
  // columns first .. first + width − 1 of L, whose rows below it are the same: super_rows_[rows ..
  // rows + below − 1]. Its panel, at panels_[panel], is (3 width + 3 below) × 3 width scalars,
  // column-major: its own columns' rows first, then those below.
  struct Supernode
  {
    int first = 0, width = 0, rows = 0, below = 0;
    std::size_t panel = 0;
  };
  std::vector<Supernode> supernodes_;
  std::vector<int> super_rows_;
  std::vector<double> panels_;
  // Per block of A: the offset of its (0, 0) entry in panels_ and its panel's leading dimension
  // ({−1, 0} for the upper triangle).
  std::vector<std::array<long, 2>> block_place_;
  // A supernode's update passes to the supernodes that hold its rows below, one run of consecutive
  // rows (below's [begin, end)) per target: the update's entries in the run's columns, on and below
  // the diagonal, are subtracted where they belong in panels_, entry (i, j) of the run's rows and
  // columns (both counted from its first scalar row, 3 begin) at update_column_offset_[columns +
  // j] + update_row_offset_[rows + i].
  struct UpdateRun
  {
    int target = 0, begin = 0, end = 0;
    std::size_t rows = 0, columns = 0;
  };
  std::vector<UpdateRun> runs_;
  std::vector<int> run_start_, update_row_offset_;
  std::vector<long> update_column_offset_;
  std::vector<double> scalar_pivot_;                // D, one number a scalar column
  std::vector<double> scaled_, gathered_;           // T = L D of a panel, R's x
  std::vector<int> ascending_;                      // 0, 1, 2, ...: a panel's own rows as row offsets
  // b into work_ in the new order, work_ into x in the old order, and the pinned flags in the new
  // order (pinned_new_).
  void toNewOrder(const Eigen::Matrix3Xd& b);
  void fromNewOrder(Eigen::Matrix3Xd& x) const;
  void pinnedInNewOrder(const std::vector<char>& pinned);
  // analyze()'s rest for the supernodal form (supernodes_ holds each one's columns): the panels,
  // where A's blocks go in them and the update runs.
  void analyzeSupernodes(const std::vector<int>& row_start, const std::vector<int>& block_column,
                         const std::vector<int>& supernode_of);
  // factorize() (of the panels once scattered) and solve() in the supernodal form (solve() on work_,
  // in the new order; both with two threads where planSubtrees() planned them and there are
  // workers). `forward_beside`: work_ holds b, and the shares' forward passes run beside the last
  // panel above them (forwardShares()); `shares_forwarded`: they have.
  bool factorizeSupernodes(bool forward_beside);
  // A's lower triangle into the zeroed panels, from its blocks or from its diagonal and pairs; a
  // pinned particle's row and column left 0, its diagonal I; each scalar column's diagonal entry in
  // A kept as the scale its pivot is judged by. With two threads planned, shared by halves.
  void scatterBlocks(const std::vector<Eigen::Matrix3d>& blocks);
  void scatterPairs(const PairedMatrix& matrix);
  void zeroPanels();
  // Both factorizeAndSolve()s once A is in the panels (pinned_new_ set): the supernodal
  // factorization and solve, x untouched where a pivot is singular.
  bool factorizeAndSolveScattered(const Eigen::Matrix3Xd& b, Eigen::Matrix3Xd& x);
  // Block (i, k) of A's lower triangle (new order) at `place` in the panels (block_place_): its
  // entries, or none but the identity's ones on a pinned particle's diagonal block and nothing off
  // it; a diagonal block's entries also as its columns' pivot scales.
  void putBlock(const std::array<long, 2>& place, int i, int k, const Eigen::Matrix3d& value);
  void solveSupernodes(bool shares_forwarded = false);
  // The forward passes of the two shares' supernodes (L y = b on work_ for their rows, their sums
  // for the rows above the shares kept): on two threads at once, or on this one.
  void forwardShares(bool two_threads);
  // One supernode's panel factored (factorPanel()), false at a singular pivot; then its update
  // subtracted from the panels above it: all of its runs, or (`shared_only`) only those into
  // supernodes of its own share, the others left for subtractRuns().
  bool factorSupernode(std::size_t s, double* scaled, bool shared_only, dense_panel::Tiles tiles);
  // Supernode s's panel factored, T = L D into `scaled` (a panel's size); false at a singular pivot.
  bool factorPanel(std::size_t s, double* scaled, dense_panel::Tiles tiles);
  // The update runs of supernode s into the supernodes of share `share` (0 or 1, kAboveShares or
  // kEveryShare), from its T in `scaled`, each run whole.
  void subtractRuns(std::size_t s, const double* scaled, int share, dense_panel::Tiles tiles);
  static constexpr int kAboveShares = -1, kEveryShare = 2;
  // Update run q of supernode s (T in `scaled`), its columns [from, to) alone.
  void subtractRun(std::size_t s, const double* scaled, int q, int from, int to, dense_panel::Tiles tiles);
  // One supernode of the solve forwards (L y = b; its sums for the rows above the shares into
  // `kept` when that is not null) and backwards (Lᵀ x = y), `gathered` its scratch.
  void forwardSupernode(std::size_t s, double* y, double* gathered, bool avx2, double* kept);
  void backwardSupernode(std::size_t s, double* y, double* gathered, bool avx2);

  // Two threads' plan (planSubtrees(); forgetSubtrees() empties it): share_of_[s] is 0 or 1 for a
  // supernode in one of the two sets of subtrees, kAboveShares for one above them; shared_order_[k]
  // lists share k's supernodes in order; a shared supernode with runs into those above keeps its T
  // at kept_scaled_at_[s] in kept_scaled_ (else kNotKept) for those runs, subtracted after both
  // shares are done. twoThreads(): there is a plan and there are threads for it.
  void planSubtrees(const std::vector<int>& supernode_of);
  void forgetSubtrees();
  bool twoThreads() const;
  static constexpr std::size_t kNotKept = SIZE_MAX;
  std::vector<signed char> share_of_;
  std::vector<int> shared_order_[2];
  std::vector<std::size_t> kept_scaled_at_;
  std::vector<double> kept_scaled_, second_scaled_;  // the kept T's; the second thread's T
  // The columns of each supernode above the shares cut into blocks of about equal entries (on and
  // below the diagonal), which two threads take from each other as they come (WorkerPool): the
  // updates into a block are subtracted by one thread, in supernode order, so every entry gets its
  // terms in the order of one thread. A block's pieces, in the order of their sources: the part of
  // a source's update run (runs_[run]) whose columns [from, to) land in the block. A supernode's
  // blocks are block_start_[s] .. block_start_[s + 1] − 1 (none for a shared supernode).
  struct BlockPiece
  {
    int source = 0, run = 0, from = 0, to = 0;
  };
  std::vector<int> block_start_, piece_start_;  // block b's pieces: piece_start_[b] .. piece_start_[b + 1] − 1
  std::vector<BlockPiece> pieces_;
  // Block b's pieces from the sources in [first_source, last_source): a shared source's from its
  // kept T, an above one's from `scaled`.
  void subtractBlock(int b, int first_source, int last_source, const double* scaled, dense_panel::Tiles tiles);
  // Blocks [first, last) on the threads, each whole on one, sources as for subtractBlock().
  void subtractBlocks(int first, int last, int first_source, int last_source, const double* scaled,
                      dense_panel::Tiles tiles);
  // The solve's (solveSupernodes()): a shared supernode's first row below that lies above the
  // shares, where its sums for those rows wait (kept_sums_at_[s] in kept_sums_, else kNotKept), and
  // the second thread's sums.
  std::vector<int> first_row_above_;
  std::vector<std::size_t> kept_sums_at_;
  std::vector<double> kept_sums_, second_gathered_;
  double shared_share_ = 0.0;
  int last_above_ = -1;  // the last supernode above the shares (−1: none planned)
  WorkerPool* workers_ = nullptr;
  Eigen::Matrix3Xd work_;
  double factor_flops_ = 0.0, solve_flops_ = 0.0;
};

}  // namespace core
}  // namespace particle_sim
