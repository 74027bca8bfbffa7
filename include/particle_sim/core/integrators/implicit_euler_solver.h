#pragma once

#include <Eigen/Core>
#include <array>
#include <utility>
#include <vector>

#include "particle_sim/core/constraints/resting_contact.h"
#include "particle_sim/core/integrator.h"
#include "particle_sim/core/integrators/sparse_block_ldlt.h"
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
/// preconditioner; warm start from the previous step's Δv. Particles resting on a collider are
/// held the same way along the surface's normal only (RestingContact): their normal velocity is
/// set to the surface's, and the rest of the system is solved for what remains. Or, by IntegratorDef::linear_solver,
/// directly (SparseBlockLdlt, the same filtered system), with CG iterations after it only if its
/// residual misses the tolerance; `auto` decides once per pattern from the two solvers' flop counts.
///
/// The matrix is block-sparse with 3x3 blocks. Its pattern (which particle pairs are coupled) is
/// set once per body by setPattern(); each step the force elements add their Jacobian blocks with
/// addBlock(), by the block index they looked up once with blockIndex(). Nothing allocates after
/// setPattern().
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
  /// A_ij −= h dfdv + h² dfdx and b_i += h² dfdx v0_j.
  void addBlock(int block, const Eigen::Matrix3d& dfdx, const Eigen::Matrix3d& dfdv)
  {
    blocks_[block].noalias() -= h_ * dfdv + h_ * h_ * dfdx;
    if (v0_) rhs_.col(block_row_[block]).noalias() += h_ * h_ * (dfdx * v0_->col(block_column_[block]));
  }
  /// Adds ∂f_i/∂x_i = dfdx, ∂f_i/∂v_i = dfdv to particle i's diagonal block.
  void addToDiagonal(int i, const Eigen::Matrix3d& dfdx, const Eigen::Matrix3d& dfdv)
  {
    addBlock(diagonal_block_[i], dfdx, dfdv);
  }
  /// Adds a two-particle element whose Jacobians are ∂f_i/∂x_i = ∂f_j/∂x_j = −∂f_i/∂x_j =
  /// −∂f_j/∂x_i = dfdx (alike for v), as a spring's are, at `blocks` = (i, i), (i, j), (j, i), (j, j).
  /// The same bits as addBlock() on each with ±dfdx and ±dfdv (a negation is exact), for less work:
  /// h dfdv + h² dfdx and the two products with v0 are formed once each instead of four times.
  /// Inline: called for every spring of every implicit step.
  [[gnu::always_inline]] void addPairBlocks(const std::array<int, 4>& blocks, const Eigen::Matrix3d& dfdx,
                                            const Eigen::Matrix3d& dfdv)
  {
    const Eigen::Matrix3d combined = h_ * dfdv + h_ * h_ * dfdx;
    blocks_[blocks[0]] -= combined;
    blocks_[blocks[1]] += combined;
    blocks_[blocks[2]] += combined;
    blocks_[blocks[3]] -= combined;
    if (!v0_) return;
    const int i = block_row_[blocks[0]], j = block_row_[blocks[3]];
    const Eigen::Vector3d at_i = h_ * h_ * (dfdx * v0_->col(i));
    const Eigen::Vector3d at_j = h_ * h_ * (dfdx * v0_->col(j));
    rhs_.col(i) += at_i;
    rhs_.col(i) -= at_j;
    rhs_.col(j) -= at_i;
    rhs_.col(j) += at_j;
  }
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
  /// counts: 18 a block of A and about 40 a particle for one iteration). Analyses the pattern
  /// (allocates): for decisions taken once.
  double directCostInCgIterations() const;
  /// Forgets the warm start (after a reset or a jump of the state).
  void clearWarmStart() { delta_v_.setZero(); }
  /// Threads to share the conjugate gradient's per-particle loops with (null: none). Its products,
  /// vector updates and sums are shared by rows; each sum is taken in fixed chunks of rows and then
  /// chunk after chunk, so that the result is the same bits at any thread count.
  void setWorkers(WorkerPool* workers) { workers_ = workers; }

private:
  // CG iterations from delta_v_ until the filtered residual is within cg_tolerance |b|, or the
  // velocity error it bounds within cg_velocity_tolerance, or the cap.
  void conjugateGradient(const std::vector<char>& pinned, const IntegratorDef& settings, SolverReport& report);
  struct ResidualNorms
  {
    double euclidean;  // |r|
    double velocity;   // [m/s] sqrt(Σ |r_i|² / m_i / free_mass): SolverReport::velocity_error
  };
  ResidualNorms residualNorms(const Eigen::Matrix3Xd& r, double free_mass) const;
  // The norms from the sums Σ |r_i|² and Σ |r_i|² / m_i.
  static ResidualNorms normsOf(double squared, double weighted, double free_mass);
  // One chunk's sums in an iteration: r·z, |r|² and Σ |r_i|² / m_i.
  struct ResidualSums
  {
    double preconditioned = 0.0, squared = 0.0, weighted = 0.0;
  };
  void multiply(const Eigen::Matrix3Xd& p, Eigen::Matrix3Xd& out) const;
  // out = A p on rows [begin, end).
  void multiplyRows(const Eigen::Matrix3Xd& p, Eigen::Matrix3Xd& out, int begin, int end) const;
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
  std::vector<Eigen::Matrix3d> inverse_diagonal_;
  std::vector<double> inverse_mass_;  // 1/m per particle (0 where m is 0), set by begin()
  SparseBlockLdlt direct_;
  enum class DirectChoice
  {
    Undecided,
    Cheaper,
    Dearer
  } auto_choice_ = DirectChoice::Undecided;
  double direct_in_cg_iterations_ = 0.0;  // one factorization and solve, in CG iterations (flops)
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
  Eigen::Matrix3Xd delta_v_, rhs_, residual_, direction_, product_, preconditioned_;
};

}  // namespace core
}  // namespace particle_sim
