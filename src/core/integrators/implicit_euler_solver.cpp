#include "particle_sim/core/integrators/implicit_euler_solver.h"

#include <Eigen/LU>
#include <algorithm>
#include <atomic>
#include <cmath>

#include "particle_sim/core/integrators/cg_avx2.h"

namespace particle_sim
{
namespace core
{
namespace
{
double dot(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b)
{
  return a.cwiseProduct(b).sum();
}

// How many times the tolerance CG's start must be from it to be moved along the last solves' change
// (ImplicitEulerSolver::extrapolateStart()).
constexpr double kExtrapolateBeyond = 100.0;

// Rows per chunk of a shared product with the block matrix (about ten blocks a row).
constexpr int kRowsPerChunk = 2048;
// Blocks of A per chunk of a shared pass that zeroes them (a memset of 576 kB).
constexpr int kBlocksPerChunk = 8192;

// out_i += C (p_j − p_i) at end i (if kAddI), out_j −= C (p_j − p_i) at end j (if kAddJ), for the
// kept pairs [first, last) in order (ImplicitEulerSolver::multiplyPairRows()). C is symmetric, given
// by its lower triangle (C00, C10, C20, C11, C21, C22).
template <bool kAddI, bool kAddJ>
[[gnu::always_inline]] inline void addPairProducts(const std::array<int, 2>* ends, const std::array<double, 6>* cs,
                                                   int first, int last, const double* p, double* out)
{
  // Consecutive pairs that share end i (a cloth's springs come two or three a particle) read p_i
  // once and add to out_i in registers, stored once when the next pair's end i differs: the same
  // additions in the same order, so the same bits (but for which NaN an add of two NaNs keeps),
  // without each sum waiting for the last one's store to come back from memory (hang64 at dt
  // 1/1000: a tenth of the step). A pair with j = i (no element makes one) would take its part from
  // the registers too.
  int held = -1;
  double h0 = 0.0, h1 = 0.0, h2 = 0.0, q0 = 0.0, q1 = 0.0, q2 = 0.0;
  auto storeHeld = [&] {
    if (!kAddI || held < 0) return;
    double* const oh = out + PaddedVectors::kStride * held;
    oh[0] = h0;
    oh[1] = h1;
    oh[2] = h2;
  };
  for (int k = first; k < last; ++k)
  {
    const int i = ends[k][0];
    const int j = ends[k][1];
    if (i != held)
    {
      storeHeld();
      held = i;
      const double* const pi = p + PaddedVectors::kStride * i;
      q0 = pi[0];
      q1 = pi[1];
      q2 = pi[2];
      if (kAddI)
      {
        const double* const oi = out + PaddedVectors::kStride * i;
        h0 = oi[0];
        h1 = oi[1];
        h2 = oi[2];
      }
    }
    const double* const pj = p + PaddedVectors::kStride * j;
    const double* const c = cs[k].data();
    const double d0 = pj[0] - q0, d1 = pj[1] - q1, d2 = pj[2] - q2;
    const double w0 = (c[0] * d0 + c[1] * d1) + c[2] * d2;
    const double w1 = (c[1] * d0 + c[3] * d1) + c[4] * d2;
    const double w2 = (c[2] * d0 + c[4] * d1) + c[5] * d2;
    if (kAddI)
    {
      h0 += w0;
      h1 += w1;
      h2 += w2;
    }
    if (kAddJ)
    {
      if (kAddI && j == i)
      {
        h0 -= w0;
        h1 -= w1;
        h2 -= w2;
      }
      else
      {
        double* const oj = out + PaddedVectors::kStride * j;
        oj[0] -= w0;
        oj[1] -= w1;
        oj[2] -= w2;
      }
    }
  }
  storeHeld();
}

// Copies between the 3-row matrices and the CG's padded vectors, particle by particle.
void copyPadded(const Eigen::Matrix3Xd& from, PaddedVectors& to)
{
  for (int i = 0; i < static_cast<int>(from.cols()); ++i)
    to.col(i) = from.col(i);
}
void copyPadded(const PaddedVectors& from, Eigen::Matrix3Xd& to)
{
  for (int i = 0; i < static_cast<int>(to.cols()); ++i)
    to.col(i) = from.col(i);
}

// Whether the conjugate gradient takes the AVX2 passes (ImplicitEulerSolver::setUseAvx2()).
std::atomic<bool>& useAvx2Flag()
{
  static std::atomic<bool> use(cg_avx2::available());
  return use;
}

}  // namespace

bool ImplicitEulerSolver::useAvx2()
{
  return useAvx2Flag().load(std::memory_order_relaxed);
}

void ImplicitEulerSolver::setUseAvx2(bool use)
{
  useAvx2Flag().store(use && cg_avx2::available(), std::memory_order_relaxed);
  SparseBlockLdlt::setUseAvx2(use);
}

void ImplicitEulerSolver::setPattern(int particles, const std::vector<std::pair<int, int>>& coupled_pairs)
{
  // Columns of each row: the particle itself and every particle it is coupled with, sorted, once.
  std::vector<std::vector<int>> columns(particles);
  for (int i = 0; i < particles; ++i)
    columns[i].push_back(i);
  for (const auto& [i, j] : coupled_pairs)
  {
    columns[i].push_back(j);
    columns[j].push_back(i);
  }
  row_start_.assign(particles + 1, 0);
  block_row_.clear();
  block_column_.clear();
  diagonal_block_.assign(particles, -1);
  for (int i = 0; i < particles; ++i)
  {
    std::sort(columns[i].begin(), columns[i].end());
    columns[i].erase(std::unique(columns[i].begin(), columns[i].end()), columns[i].end());
    for (int j : columns[i])
    {
      if (j == i) diagonal_block_[i] = static_cast<int>(block_row_.size());
      block_row_.push_back(i);
      block_column_.push_back(j);
    }
    row_start_[i + 1] = static_cast<int>(block_row_.size());
  }
  blocks_.assign(block_row_.size(), Eigen::Matrix3d::Zero());
  diagonal_.assign(particles, Eigen::Matrix3d::Zero());
  diagonal_in_blocks_ = true;
  off_diagonal_zero_ = true;
  // Room for a kept pair per coupled pair, and the pair chunks of the coupled pairs, which are the
  // kept pairs of a body of springs alone (its springs in order), so that no step allocates. A body
  // whose elements add blocks of their own gives them back at its second step (begin()).
  const int pairs = static_cast<int>(coupled_pairs.size());
  pair_ends_.resize(pairs);
  for (int k = 0; k < pairs; ++k)
    pair_ends_[k] = {coupled_pairs[k].first, coupled_pairs[k].second};
  pair_blocks_.resize(pairs);
  pair_c_.resize(pairs);
  indexPairs(pairs, particles);
  adds_blocks_ = false;
  kept_pairs_ = 0;
  pairs_in_blocks_ = true;
  own_diagonal_.assign(particles, Eigen::Matrix3d::Zero());
  own_scale_.assign(particles, 0.0);
  transpose_block_.resize(block_row_.size());
  for (std::size_t k = 0; k < block_row_.size(); ++k)
    transpose_block_[k] = blockIndex(block_column_[k], block_row_[k]);
  direct_ = SparseBlockLdlt();
  auto_choice_ = DirectChoice::Undecided;
  direct_in_cg_iterations_ = 0.0;
  multigrid_choice_ = MultigridChoice::Untried;
  inverse_diagonal_.assign(particles, Eigen::Matrix3d::Identity());
  inverse_mass_.assign(particles, 0.0);
  curvature_chunks_.assign((particles + kRowsPerChunk - 1) / kRowsPerChunk, 0.0);
  residual_chunks_.assign((particles + kParticlesPerVectorChunk - 1) / kParticlesPerVectorChunk, ResidualSums());
  for (Eigen::Matrix3Xd* m : {&delta_v_, &start_, &previous_start_, &older_start_, &rhs_, &residual_, &preconditioned_,
                              &held_change_, &original_rhs_, &multigrid_direction_, &multigrid_product_})
    m->setZero(3, particles);
  multigrid_planned_ = false;
  for (PaddedVectors* v : {&padded_delta_v_, &padded_residual_, &padded_preconditioned_, &direction_, &product_})
    v->setZero(particles);
  // Room for the resting contacts' bookkeeping (holdContacts) for every particle held, so that no
  // step allocates when contacts first appear or grow in number.
  original_blocks_.reserve(blocks_.size());
  held_rows_.reserve(blocks_.size());
  held_rhs_.reserve(particles);
}

int ImplicitEulerSolver::blockIndex(int i, int j) const
{
  const auto first = block_column_.begin() + row_start_[i], last = block_column_.begin() + row_start_[i + 1];
  const auto it = std::lower_bound(first, last, j);
  return it != last && *it == j ? static_cast<int>(it - block_column_.begin()) : -1;
}

void ImplicitEulerSolver::begin(double h, const Eigen::VectorXd& mass, const Eigen::Matrix3Xd& force,
                                const Eigen::Matrix3Xd* v0)
{
  h_ = h;
  v0_ = v0;
  mass_ = &mass;
  // Only a step that wrote off-diagonal blocks leaves them to clear (the diagonal is set below).
  // Pairs are kept aside until a solve or another element needs them in the blocks; a body whose
  // elements add blocks of their own writes them in every step.
  if (!off_diagonal_zero_)
  {
    shareLoop(workers_, static_cast<int>(blocks_.size()), kBlocksPerChunk, [&](int first, int last) {
      for (int b = first; b < last; ++b)
        blocks_[b].setZero();
    });
  }
  off_diagonal_zero_ = !adds_blocks_;
  // A body with an element that adds blocks of its own (Baraff–Witkin, bending) writes its springs'
  // blocks at once: they would be moved into the blocks in every step.
  kept_pairs_ = 0;
  pairs_in_blocks_ = adds_blocks_;
  if (adds_blocks_ && !pair_ends_.empty())
  {
    std::vector<std::array<int, 2>>().swap(pair_ends_);
    std::vector<std::array<int, 2>>().swap(pair_blocks_);
    std::vector<std::array<double, 6>>().swap(pair_c_);
    pair_chunks_ = PairChunks();
  }
  // A = M on the diagonal; and 1/m for the velocity error's Σ |r_i|² / m_i, a product in CG's
  // iterations instead of a division (0 for a massless particle, which only a pinned one can be).
  // A body whose elements add blocks of their own writes its diagonal in blocks_ at once.
  diagonal_in_blocks_ = adds_blocks_;
  for (int i = 0; i < static_cast<int>(diagonal_block_.size()); ++i)
  {
    Eigen::Matrix3d& diagonal = diagonalBlock(i);
    diagonal = mass[i] * Eigen::Matrix3d::Identity();
    own_diagonal_[i] = diagonal;
    own_scale_[i] = mass[i];
    inverse_mass_[i] = mass[i] > 0.0 ? 1.0 / mass[i] : 0.0;
  }
  own_isotropic_ = true;
  rhs_ = h * force;
}

void ImplicitEulerSolver::indexPairs(int pairs, int rows)
{
  pair_chunks_.build(
      pairs, rows, kRowsPerChunk, [this](int k) { return pair_ends_[k][0]; },
      [this](int k) { return pair_ends_[k][1]; });
  indexed_pairs_ = pairs;
  pairs_changed_ = false;
}

void ImplicitEulerSolver::growPairs()
{
  const std::size_t size = std::max<std::size_t>(64, 2 * pair_ends_.size());
  pair_ends_.resize(size, {-1, -1});
  pair_blocks_.resize(size);
  pair_c_.resize(size);
}

void ImplicitEulerSolver::moveDiagonalIntoBlocks()
{
  if (diagonal_in_blocks_) return;
  shareLoop(workers_, static_cast<int>(diagonal_block_.size()), kRowsPerChunk, [&](int first, int last) {
    for (int i = first; i < last; ++i)
      blocks_[diagonal_block_[i]] = diagonal_[i];
  });
  diagonal_in_blocks_ = true;
}

void ImplicitEulerSolver::movePairsIntoBlocks()
{
  if (pairs_in_blocks_) return;
  // Each block gets its pairs' C in the pairs' order. With threads, the blocks are cut in two at
  // the middle and each part's thread passes every pair, adding to its own blocks alone (a pair's
  // two blocks may lie in different parts).
  auto addPairs = [&](std::size_t first_block, std::size_t last_block) {
    auto mine = [&](int block) {
      return static_cast<std::size_t>(block) >= first_block && static_cast<std::size_t>(block) < last_block;
    };
    for (int k = 0; k < kept_pairs_; ++k)
    {
      const int ij = pair_blocks_[k][0], ji = pair_blocks_[k][1];
      if (!mine(ij) && !mine(ji)) continue;
      const Eigen::Matrix3d c = symmetricBlock(pair_c_[k]);
      if (mine(ij)) blocks_[ij] += c;
      if (mine(ji)) blocks_[ji] += c;
    }
  };
  if (workers_ && workers_->threads() > 1 && kept_pairs_ > kRowsPerChunk)
    byHalves(*workers_, blocks_.size(), addPairs);
  else
    addPairs(0, blocks_.size());
  pairs_in_blocks_ = true;
  off_diagonal_zero_ = false;
}

bool ImplicitEulerSolver::preparePairProduct()
{
  const int rows = static_cast<int>(diagonal_block_.size());
  if (pairs_changed_ || indexed_pairs_ != kept_pairs_) indexPairs(kept_pairs_, rows);
  if (pair_chunks_.hasLocality()) return true;
  movePairsIntoBlocks();
  return false;
}

void ImplicitEulerSolver::multiplyPairRows(const PaddedVectors& p, PaddedVectors& out, int chunk, int first,
                                           int last) const
{
  // E_i p_i, from e_i alone while E_i = e_i I: row r of E_i p_i is (e_i p_r + 0 p_s) + 0 p_t, which
  // is e_i p_r but for the sign of a zero (where p_s or p_t is not finite, the row is not finite
  // either way: a NaN there, an infinity or a NaN here).
  const bool avx2 = useAvx2();
  if (own_isotropic_ && avx2)
  {
    cg_avx2::scaleRows(own_scale_.data(), first, last, p.data(), out.data());
  }
  else if (own_isotropic_)
  {
    for (int i = first; i < last; ++i)
      out.col(i) = own_scale_[i] * p.col(i);
  }
  else
  {
    for (int i = first; i < last; ++i)
      out.col(i).noalias() = own_diagonal_[i] * p.col(i);
  }
  const std::array<int, 2>* const ends = pair_ends_.data();
  const std::array<double, 6>* const cs = pair_c_.data();
  const double* const ps = p.data();
  double* const outs = out.data();
  for (int r = pair_chunks_.runStart(chunk); r < pair_chunks_.runStart(chunk + 1); ++r)
  {
    const PairChunks::Run run = pair_chunks_.runs()[r];
    const bool add_i = (run.ends & PairChunks::kEndI) != 0, add_j = (run.ends & PairChunks::kEndJ) != 0;
    if (avx2)
      cg_avx2::addPairProducts(add_i, add_j, ends, cs, run.first, run.first + run.count, ps, outs);
    else if (add_i && add_j)
      addPairProducts<true, true>(ends, cs, run.first, run.first + run.count, ps, outs);
    else if (add_i)
      addPairProducts<true, false>(ends, cs, run.first, run.first + run.count, ps, outs);
    else if (add_j)
      addPairProducts<false, true>(ends, cs, run.first, run.first + run.count, ps, outs);
  }
}

void ImplicitEulerSolver::multiply(const PaddedVectors& p, PaddedVectors& out, bool pair_product) const
{
  if (!pair_product)
  {
    shareLoop(workers_, static_cast<int>(diagonal_block_.size()), kRowsPerChunk,
              [&](int first, int last) { multiplyRows(p, out, first, last); });
    return;
  }
  forEachFixedChunk(workers_, static_cast<int>(diagonal_block_.size()), kRowsPerChunk,
                    [&](int chunk, int first, int last) { multiplyPairRows(p, out, chunk, first, last); });
}

void ImplicitEulerSolver::multiplyRows(const PaddedVectors& p, PaddedVectors& out, int begin, int end) const
{
  for (int i = begin; i < end; ++i)
  {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int k = row_start_[i]; k < row_start_[i + 1]; ++k)
      sum.noalias() += blocks_[k] * p.col(block_column_[k]);
    out.col(i) = sum;
  }
}

void ImplicitEulerSolver::filter(const std::vector<char>& pinned, Eigen::Matrix3Xd& p)
{
  for (int i = 0; i < p.cols(); ++i)
  {
    if (pinned[i]) p.col(i).setZero();
  }
}

void ImplicitEulerSolver::precondition(const Eigen::Matrix3Xd& r, Eigen::Matrix3Xd& out) const
{
  for (int i = 0; i < r.cols(); ++i)
    out.col(i).noalias() = inverse_diagonal_[i] * r.col(i);
}

double ImplicitEulerSolver::cgIterationFlops() const
{
  // A product with A (18 flops a block) and about 40 flops a particle of vector passes (residual,
  // direction, preconditioner, dots).
  return 18.0 * static_cast<double>(blocks_.size()) + 40.0 * static_cast<double>(diagonal_block_.size());
}

double ImplicitEulerSolver::directCostInCgIterations(bool* supernodal) const
{
  const SparseBlockLdlt::Cost direct = SparseBlockLdlt::estimateCost(row_start_, block_column_);
  if (supernodal) *supernodal = direct.supernodal;
  return (direct.factor_flops + direct.solve_flops) / cgIterationFlops();
}

double ImplicitEulerSolver::multigridCostInCgIterations(int iterations) const
{
  // The hierarchy's numbers, then a cycle before the first iteration and one more with each
  // iteration's product and vector passes (the last iteration's cycle is skipped when it converges;
  // counted all the same); the hierarchy's flops weighted by kMultigridFlopWeight, but for the
  // cycle's smoothings and residuals on the finest level, which are CG's own kinds of operation.
  const double cg_iteration = cgIterationFlops();
  const double finest = multigrid_.finestCycleFlops();
  const double cycle = kMultigridFlopWeight * (multigrid_.cycleFlops() - finest) + finest;
  return (kMultigridFlopWeight * multigrid_.setupFlops() + cycle + iterations * (cycle + cg_iteration)) / cg_iteration;
}

bool ImplicitEulerSolver::usesDirect(LinearSolverType solver)
{
  if (solver == LinearSolverType::ConjugateGradient || solver == LinearSolverType::Multigrid) return false;
  if (solver == LinearSolverType::Auto && auto_choice_ == DirectChoice::Undecided)
  {
    // The direct solve's cost in CG iterations decides now (kDirectSolverCgIterations) and again
    // after each CG solve (solve()).
    direct_in_cg_iterations_ = directCostInCgIterations();
    auto_choice_ = direct_in_cg_iterations_ <= kDirectSolverCgIterations ? DirectChoice::Cheaper : DirectChoice::Dearer;
  }
  if (solver == LinearSolverType::Auto && auto_choice_ == DirectChoice::Dearer) return false;
  if (!direct_.analyzed()) direct_.analyze(row_start_, block_column_);
  return true;
}

bool ImplicitEulerSolver::holdContacts(const std::vector<char>& pinned, std::vector<RestingContact>& contacts,
                                       const Eigen::Matrix3Xd& v, bool keep_system)
{
  // Held: a contact not let go in this step whose particle is not leaving the surface; stuck as well
  // when it has friction and has not slipped in this step; a slipping one gets its friction impulse
  // in b. With P_i the held directions (n nᵀ, or I
  // when stuck), S_i = I − P_i, and the change z_i = P_i (u − v_i) that gives them the surface's
  // velocity u, the system A Δv = b becomes one for the rest y = Δv − z, in which P_i y_i = 0:
  //   (S A S + m_i P_i on the held rows) y = S (b − A z)
  // (Baraff & Witkin's filtered system, made definite on the held directions). The original rows
  // A_ij and b_i are kept first, for the impulses; the whole system too when asked, for a solve
  // with fewer held.
  bool any = false;
  held_rows_.clear();
  held_rhs_.clear();
  for (RestingContact& contact : contacts)
  {
    const int i = contact.particle;
    const Eigen::Vector3d& n = contact.normal;
    // Leaving: faster than the resting distance in one step (rounding leaves |v·n| ~ 1e-17 m/s).
    const bool leaving = n.dot(v.col(i) - contact.surface_velocity) * h_ > kRestingContactDistance;
    contact.held = !pinned[i] && !contact.let_go && !leaving;
    contact.stuck = contact.held && !contact.slipping && contact.friction > 0.0;
    contact.impulse.setZero();
    contact.normal_impulse = 0.0;
    if (!contact.held) continue;
    any = true;
    const Eigen::Vector3d change = contact.surface_velocity - v.col(i);
    held_change_.col(i) = contact.stuck ? change : Eigen::Vector3d(n * n.dot(change));
    for (int k = row_start_[i]; k < row_start_[i + 1]; ++k)
      held_rows_.push_back(blocks_[k]);
    held_rhs_.push_back(rhs_.col(i));
    if (contact.slipping) rhs_.col(i) += contact.friction_impulse;
  }
  if (!any) return false;
  if (keep_system)
  {
    original_blocks_ = blocks_;
    original_rhs_ = rhs_;
  }
  // b −= A z, column by column of the held particles (A_ji is block (j, i)).
  for (const RestingContact& contact : contacts)
  {
    if (!contact.held) continue;
    const int i = contact.particle;
    for (int k = row_start_[i]; k < row_start_[i + 1]; ++k)
      rhs_.col(block_column_[k]).noalias() -= blocks_[transpose_block_[k]] * held_change_.col(i);
  }
  // Project the held rows and columns; the diagonal block gets m P back on the held directions.
  for (const RestingContact& contact : contacts)
  {
    if (!contact.held) continue;
    const int i = contact.particle;
    const Eigen::Matrix3d held =
        contact.stuck ? Eigen::Matrix3d::Identity() : Eigen::Matrix3d(contact.normal * contact.normal.transpose());
    const Eigen::Matrix3d s = Eigen::Matrix3d::Identity() - held;
    for (int k = row_start_[i]; k < row_start_[i + 1]; ++k)
      blocks_[k] = s * blocks_[k];
    for (int k = row_start_[i]; k < row_start_[i + 1]; ++k)
      blocks_[transpose_block_[k]] = blocks_[transpose_block_[k]] * s;
    blocks_[diagonal_block_[i]].noalias() += (*mass_)[i] * held;
    rhs_.col(i) = s * rhs_.col(i);
    delta_v_.col(i) = s * delta_v_.col(i);  // the warm start, too
  }
  return true;
}

bool ImplicitEulerSolver::reviseHolds(std::vector<RestingContact>& contacts)
{
  // Δv = y + z; the impulse J_i = (A Δv − b)_i with the original row: what the surface added. A
  // surface can only push: a held particle with J_i·n < 0 is let go. A stuck one whose impulse
  // leaves the friction cone (|J_t| > μ J_n) slips: only its normal is held from now on, and
  // friction gives it μ J_n along J_t (Coulomb's sliding friction, opposing the slide that sticking
  // had to stop).
  bool revised = false;
  int row = 0, held = 0;
  for (RestingContact& contact : contacts)
  {
    if (!contact.held) continue;
    const int i = contact.particle;
    Eigen::Vector3d impulse = -held_rhs_[held++];
    for (int k = row_start_[i]; k < row_start_[i + 1]; ++k, ++row)
    {
      const int j = block_column_[k];
      impulse.noalias() += held_rows_[row] * (delta_v_.col(j) + held_change_.col(j));
    }
    contact.impulse = impulse;
    contact.normal_impulse = impulse.dot(contact.normal);
    const Eigen::Vector3d tangential = impulse - contact.normal_impulse * contact.normal;
    if (contact.normal_impulse < 0.0)
    {
      contact.let_go = revised = true;
    }
    else if (contact.stuck && tangential.norm() > contact.friction * contact.normal_impulse)
    {
      contact.slipping = revised = true;
      contact.friction_impulse = tangential * (contact.friction * contact.normal_impulse / tangential.norm());
    }
  }
  return revised;
}

SolverReport ImplicitEulerSolver::solve(const std::vector<char>& pinned, std::vector<RestingContact>& contacts,
                                        const IntegratorDef& settings, Eigen::Matrix3Xd& x, Eigen::Matrix3Xd& v)
{
  // Resting contacts are held (stuck, or along the normal). After each solve, holds that pull are
  // let go, stuck ones beyond the friction cone slip, and the system is solved again, until no hold
  // changes: every held contact then pushes, inside its friction cone. Each contact changes at most
  // twice (stuck → slipping → let go, never back), so this ends within 1 + 2 · contacts solves. A
  // rope or cloth lifted off a floor lets go particle after particle, one more each solve (up to 17
  // solves in a step of the pick_and_place demo); stopping earlier would leave the rest held while
  // they pull, a floor that glues. The collision response after the step answers what a let-go
  // particle then does. A step that would need more than kMaxContactSolves (a long rope or a sheet
  // dragged over a floor in one step) keeps the last solve and reports itself unconverged, which the
  // status and diagnostics warn of, rather than costing an unbounded number of factorizations.
  positions_ = &x;
  for (RestingContact& contact : contacts)
    contact.let_go = contact.slipping = false;
  if (!contacts.empty())  // holding contacts works on the rows of A
  {
    movePairsIntoBlocks();
    moveDiagonalIntoBlocks();
  }
  bool holding = holdContacts(pinned, contacts, v, true);
  SolverReport report = solveLinear(pinned, settings);
  int solves = 1;
  bool settled = true;
  while (holding && reviseHolds(contacts))
  {
    if (solves == kMaxContactSolves)
    {
      settled = false;
      break;
    }
    ++solves;
    blocks_ = original_blocks_;
    rhs_ = original_rhs_;
    for (const RestingContact& contact : contacts)
      held_change_.col(contact.particle).setZero();
    holding = holdContacts(pinned, contacts, v, false);
    report = solveLinear(pinned, settings);
  }
  report.contact_solves = solves;
  if (!settled) report.converged = false;

  // v1 = v0 + Δv (+ z on the held particles), x1 = x0 + h v1.
  v += delta_v_;
  for (const RestingContact& contact : contacts)
  {
    v.col(contact.particle) += held_change_.col(contact.particle);
    held_change_.col(contact.particle).setZero();
  }
  x += h_ * v;
  return report;
}

SolverReport ImplicitEulerSolver::solveLinear(const std::vector<char>& pinned, const IntegratorDef& settings)
{
  // Directly, when chosen and the factorization succeeds (a singular or non-finite pivot leaves it
  // to CG, from the last step's Δv); then CG, which stops at once when the residual is small enough.
  // The starts of this solve and the two before, for CG's extrapolated start.
  older_start_.swap(previous_start_);
  previous_start_.swap(start_);
  start_ = delta_v_;
  SolverReport report;
  if (settings.linear_solver == LinearSolverType::Multigrid)
  {
    multigridConjugateGradient(pinned, settings, report);
    return report;
  }
  report.direct = usesDirect(settings.linear_solver) && solveDirectly(pinned);
  // `auto`'s multigrid, on trial or chosen (see below); when it does not converge, CG takes over
  // from where it left Δv, and the multigrid is not tried again.
  int multigrid_iterations = 0;
  if (settings.linear_solver == LinearSolverType::Auto && !report.direct &&
      (multigrid_choice_ == MultigridChoice::Trying || multigrid_choice_ == MultigridChoice::Chosen))
  {
    if (autoMultigrid(pinned, settings, report)) return report;
    multigrid_iterations = report.iterations;
    report = SolverReport{};
  }
  // Under `auto`, CG may go on past the cap until it has spent what the direct solve costs: until
  // then, stopping for the direct solve would only add its cost to the iterations already spent.
  // So a solve costs at most about twice the cheaper of the two (the rent-or-buy bound), and a
  // body that CG solves in a few more iterations than the cap stays with CG.
  int max_iterations = settings.cg_max_iterations;
  if (settings.linear_solver == LinearSolverType::Auto && !report.direct && max_iterations > 0)
    max_iterations = static_cast<int>(
        std::min(1e9, std::max(static_cast<double>(max_iterations), std::ceil(direct_in_cg_iterations_))));
  conjugateGradient(pinned, settings, max_iterations, report);
  // `auto` measured CG: when a solve took more iterations than the direct solve costs, or stopped
  // at that many short of the tolerance (the direct solve is exact, however dear), the direct
  // solver takes over from the next solve on (for good: no switching back and forth).
  if (settings.linear_solver == LinearSolverType::Auto && !report.direct &&
      (report.iterations > direct_in_cg_iterations_ || !report.converged))
  {
    auto_choice_ = DirectChoice::Cheaper;
    // A capped solve is not kept: this solve is done again directly, from the same system (CG
    // only read it), so that `auto` never ends a step short of the tolerance it could meet.
    if (!report.converged && !report.breakdown && usesDirect(settings.linear_solver) && solveDirectly(pinned))
    {
      const int capped_iterations = report.iterations;
      report = SolverReport{};
      report.direct = true;
      conjugateGradient(pinned, settings, settings.cg_max_iterations, report);
      report.iterations += capped_iterations;  // the work done, the capped CG's included
    }
  }
  // `auto` tries the multigrid in the next solve once a converged CG solve took more than
  // kMultigridTrialCgIterations iterations and the direct solver is still dearer (autoMultigrid()).
  if (settings.linear_solver == LinearSolverType::Auto && !report.direct && report.converged &&
      auto_choice_ == DirectChoice::Dearer && multigrid_choice_ == MultigridChoice::Untried &&
      report.iterations > kMultigridTrialCgIterations)
  {
    multigrid_choice_ = MultigridChoice::Trying;
    trial_cg_iterations_ = report.iterations;
  }
  report.iterations += multigrid_iterations;  // the work done, the multigrid's included
  return report;
}

bool ImplicitEulerSolver::autoMultigrid(const std::vector<char>& pinned, const IntegratorDef& settings,
                                        SolverReport& report)
{
  // The multigrid's cost in CG iterations (flops: its setup, cycles, products and vector passes)
  // decides. On trial it is kept for good when it is below the CG solve's that led to the trial, else
  // CG is back for good. Kept, it gives way to the direct solver for good once a solve costs more
  // than the direct solve (as CG does). A solve short of the tolerance (or a hierarchy that is not
  // definite) ends the multigrid for good, and CG finishes the solve.
  multigridConjugateGradient(pinned, settings, report);
  if (!report.multigrid || !report.converged)
  {
    multigrid_choice_ = MultigridChoice::Rejected;
    return report.converged;
  }
  const double cost = multigridCostInCgIterations(report.iterations);
  if (multigrid_choice_ == MultigridChoice::Trying)
    multigrid_choice_ = cost < trial_cg_iterations_ ? MultigridChoice::Chosen : MultigridChoice::Rejected;
  if (multigrid_choice_ == MultigridChoice::Chosen && cost > direct_in_cg_iterations_)
  {
    multigrid_choice_ = MultigridChoice::Rejected;
    auto_choice_ = DirectChoice::Cheaper;
  }
  return true;
}

bool ImplicitEulerSolver::solveDirectly(const std::vector<char>& pinned)
{
  residual_ = rhs_;
  filter(pinned, residual_);
  // The supernodal form takes A straight from the diagonal and the kept pairs while neither is in
  // the blocks (the same numbers): the off-diagonal blocks are then never filled, read or cleared.
  if (keptApart() && direct_.supernodal())
  {
    const SparseBlockLdlt::PairedMatrix matrix{diagonal_.data(), diagonal_block_.data(), kept_pairs_,
                                               pair_blocks_.data(), pair_c_.data()};
    return direct_.factorizeAndSolve(matrix, pinned, residual_, delta_v_);
  }
  movePairsIntoBlocks();
  moveDiagonalIntoBlocks();
  return direct_.factorizeAndSolve(blocks_, pinned, residual_, delta_v_);
}

void ImplicitEulerSolver::conjugateGradient(const std::vector<char>& pinned, const IntegratorDef& settings,
                                            int max_iterations, SolverReport& report)
{
  // Modified preconditioned CG (Baraff & Witkin 1998, section 5.3), started from delta_v_, with
  // pinned rows filtered out of the start, every residual and every direction. It stops when the
  // residual is within cg_tolerance of |b|, or when the velocity error it bounds is within
  // cg_velocity_tolerance (residualNorms), or at the cap.
  // The product by the kept pairs when there are any to use (see addPairBlocks()), else by the blocks.
  const bool pair_product = !pairs_in_blocks_ && preparePairProduct();
  if (!pair_product) moveDiagonalIntoBlocks();  // the product by the blocks reads A whole
  filter(pinned, delta_v_);
  residual_ = rhs_;
  filter(pinned, residual_);
  const double free_mass = freeMass(pinned);
  const double rhs_norm = residualNorms(residual_, free_mass).euclidean;
  const int rows = static_cast<int>(diagonal_block_.size());
  copyPadded(delta_v_, padded_delta_v_);
  multiply(padded_delta_v_, product_, pair_product);
  for (int i = 0; i < rows; ++i)
    residual_.col(i) -= product_.col(i);
  filter(pinned, residual_);
  ResidualNorms norms = residualNorms(residual_, free_mass);
  auto within = [&](const ResidualNorms& n) { return withinTolerance(n, rhs_norm, settings); };
  // The start moved along the last solves' change only when it is far from the tolerance (a factor
  // kExtrapolateBeyond): near it, a moved start that passes the rule at once would carry the
  // last steps' errors into this one (a body at rest would keep a drift of the tolerance's size).
  const ResidualNorms far{norms.euclidean / kExtrapolateBeyond, norms.velocity / kExtrapolateBeyond};
  if (!within(far) && max_iterations > 0 && extrapolateStart(pinned, pair_product))
    norms = residualNorms(residual_, free_mass);
  if (!within(norms) && max_iterations > 0)
  {
    for (int i = 0; i < static_cast<int>(diagonal_block_.size()); ++i)
      inverse_diagonal_[i] = diagonalBlock(i).inverse();
    precondition(residual_, preconditioned_);
    filter(pinned, preconditioned_);
    copyPadded(preconditioned_, direction_);
    copyPadded(residual_, padded_residual_);
  }
  double delta_new = dot(residual_, preconditioned_);
  // Each iteration is three passes over the particles, each shared by rows (WorkerPool): the product
  // A d with the curvature d·Ad; the updates of Δv and r with the preconditioned residual z and the
  // sums r·z, |r|² and Σ |r_i|² / m_i; the new direction. Every row is computed alone, in the same
  // operations as on one thread, and every sum is taken in fixed chunks of rows and then chunk after
  // chunk (like sumByChunks()): the same bits at any thread count. The iterations' vectors are
  // padded (PaddedVectors), for the AVX2 passes where the processor has them (cg_avx2.h: the same
  // bits as the scalar passes here).
  const bool avx2 = useAvx2();
  while (!within(norms) && report.iterations < max_iterations)
  {
    forEachFixedChunk(workers_, rows, kRowsPerChunk, [&](int index, int first, int last) {
      if (pair_product)
        multiplyPairRows(direction_, product_, index, first, last);
      else
        multiplyRows(direction_, product_, first, last);
      if (avx2)
      {
        curvature_chunks_[index] = cg_avx2::curvature(pinned.data(), first, last, direction_.data(), product_.data());
        return;
      }
      // Three running sums, one per coordinate, so that each add need not wait for the last.
      Eigen::Vector3d curvature = Eigen::Vector3d::Zero();
      for (int i = first; i < last; ++i)
      {
        if (pinned[i]) product_.col(i).setZero();
        curvature += direction_.col(i).cwiseProduct(product_.col(i));
      }
      curvature_chunks_[index] = curvature.sum();
    });
    double curvature = 0.0;
    for (const double chunk : curvature_chunks_)
      curvature += chunk;
    if (!(curvature > 0.0))
    {
      report.breakdown = true;  // not positive definite (or NaN): the solve failed
      break;
    }
    const double alpha = delta_new / curvature;
    forEachFixedChunk(workers_, rows, kParticlesPerVectorChunk, [&](int index, int first, int last) {
      // Through raw pointers held in registers: Eigen's packet stores may alias anything, so what the
      // loop reads through members (or through the lambda's references) would be read again after
      // every store.
      const double* const inverse_mass = inverse_mass_.data();
      double* const delta_v = padded_delta_v_.data();
      double* const residual = padded_residual_.data();
      double* const preconditioned_out = padded_preconditioned_.data();
      const double* const direction = direction_.data();
      const double* const product = product_.data();
      const Eigen::Matrix3d* const inverse_diagonal = inverse_diagonal_.data();
      const double step = alpha;
      if (avx2)
      {
        const cg_avx2::UpdateSums sums =
            cg_avx2::updateIterate(first, last, step, inverse_mass, inverse_diagonal, direction, product, delta_v,
                                   residual, preconditioned_out);
        residual_chunks_[index] = {sums.preconditioned, sums.squared, sums.weighted};
        return;
      }
      constexpr int kStride = PaddedVectors::kStride;
      using Column = Eigen::Map<Eigen::Vector3d>;
      using ConstColumn = Eigen::Map<const Eigen::Vector3d>;
      Eigen::Vector3d preconditioned = Eigen::Vector3d::Zero(), squared = Eigen::Vector3d::Zero(),
                      weighted = Eigen::Vector3d::Zero();  // per coordinate, as above
      for (int i = first; i < last; ++i)
      {
        Column(delta_v + kStride * i) += step * ConstColumn(direction + kStride * i);
        const Eigen::Vector3d r = Column(residual + kStride * i) - step * ConstColumn(product + kStride * i);
        Column(residual + kStride * i) = r;
        const Eigen::Vector3d z = inverse_diagonal[i] * r;
        Column(preconditioned_out + kStride * i) = z;
        preconditioned += r.cwiseProduct(z);
        const Eigen::Vector3d r2 = r.cwiseAbs2();
        squared += r2;
        weighted += inverse_mass[i] * r2;
      }
      residual_chunks_[index] = {preconditioned.sum(), squared.sum(), weighted.sum()};
    });
    ResidualSums total;
    for (const ResidualSums& chunk : residual_chunks_)
    {
      total.preconditioned += chunk.preconditioned;
      total.squared += chunk.squared;
      total.weighted += chunk.weighted;
    }
    const double delta_old = delta_new;
    delta_new = total.preconditioned;
    const double beta = delta_new / delta_old;
    shareLoop(workers_, rows, kParticlesPerVectorChunk, [&](int begin, int end) {
      if (avx2)
      {
        cg_avx2::updateDirection(pinned.data(), begin, end, beta, padded_preconditioned_.data(), direction_.data());
        return;
      }
      for (int i = begin; i < end; ++i)
      {
        direction_.col(i) = padded_preconditioned_.col(i) + beta * direction_.col(i);
        if (pinned[i]) direction_.col(i).setZero();
      }
    });
    norms = normsOf(total.squared, total.weighted, free_mass);
    ++report.iterations;
  }
  copyPadded(padded_delta_v_, delta_v_);
  report.relative_residual = rhs_norm > 0.0 ? norms.euclidean / rhs_norm : 0.0;
  report.velocity_error = norms.velocity;
  report.converged = within(norms) && std::isfinite(norms.euclidean);
}

bool ImplicitEulerSolver::extrapolateStart(const std::vector<char>& pinned, bool pair_product)
{
  // d = (s1 − s2) + ((s1 − s2) − (s2 − s3)) of the starts s1, s2, s3, latest first: the last change
  // and the change of the change (zero on pinned rows), into direction_, and A d into product_,
  // which CG overwrites next; then dᵀAd and dᵀr in one pass, and Δv += β d, r −= β A d in another.
  // Serial passes (a few per step), so the sums do not depend on the threads.
  constexpr int kStride = PaddedVectors::kStride;
  const int rows = static_cast<int>(diagonal_block_.size());
  const double* const start = start_.data();
  const double* const previous = previous_start_.data();
  const double* const older = older_start_.data();
  double* const direction = direction_.data();
  bool moved = false;
  for (int i = 0; i < rows; ++i)
  {
    for (int k = 0; k < 3; ++k)
    {
      const double last_change = start[3 * i + k] - previous[3 * i + k];
      const double change_before = previous[3 * i + k] - older[3 * i + k];
      const double change = pinned[i] ? 0.0 : last_change + (last_change - change_before);
      direction[kStride * i + k] = change;
      moved = moved || change != 0.0;
    }
  }
  if (!moved) return false;
  multiply(direction_, product_, pair_product);
  const double* const product = product_.data();
  double* const residual = residual_.data();
  double curvature = 0.0, along = 0.0;
  for (int i = 0; i < rows; ++i)
  {
    for (int k = 0; k < 3; ++k)
    {
      curvature += direction[kStride * i + k] * product[kStride * i + k];
      along += direction[kStride * i + k] * residual[3 * i + k];
    }
  }
  if (!(curvature > 0.0) || !std::isfinite(along)) return false;
  const double beta = along / curvature;
  double* const delta_v = padded_delta_v_.data();
  for (int i = 0; i < rows; ++i)
  {
    if (pinned[i]) continue;
    for (int k = 0; k < 3; ++k)
    {
      delta_v[kStride * i + k] += beta * direction[kStride * i + k];
      residual[3 * i + k] -= beta * product[kStride * i + k];
    }
  }
  return true;
}

void ImplicitEulerSolver::multigridConjugateGradient(const std::vector<char>& pinned, const IntegratorDef& settings,
                                                     SolverReport& report)
{
  // The hierarchy reads A whole: the kept pairs go into its copy of the blocks (not into blocks_,
  // whose off-diagonal blocks then stay zero and need no clearing in the next step). Its aggregates
  // and plans are laid out at the first solve of a pattern; its numbers every solve. The products
  // with A on the finest level (CG's, and the cycles' residuals there) take the kept pairs while
  // there are any (multiplyFilteredPairs(): a third of the bytes of the blocks, which the products
  // would read three times an iteration), else the hierarchy's blocks.
  const bool pair_product = !pairs_in_blocks_ && preparePairProduct();
  FinestPairs pairs;
  if (pair_product)
    pairs = {kept_pairs_, pair_ends_.data(), pair_blocks_.data(), pair_c_.data()};
  else
    movePairsIntoBlocks();
  moveDiagonalIntoBlocks();  // the hierarchy reads the diagonal blocks in blocks_
  // Given again every solve: it holds this solver and this solve's pins.
  multigrid_.setFinestProduct([this, &pinned](const double* x, double* y) { multiplyFilteredPairs(pinned, x, y); });
  multigrid_.useFinestProduct(pair_product);
  if (!multigrid_planned_)
  {
    multigrid_.setPattern(static_cast<int>(diagonal_block_.size()), row_start_, block_column_);
    multigrid_planned_ = true;
  }
  // A new hierarchy every solve: kept over later solves, its rigid-body modes turn away from a
  // swinging cloth's within a few steps at h = 1/60 (hang64: 24 iterations a step with a new one
  // each solve, 36 with one every second solve, 136 every tenth; README, "Or by multigrid").
  if (!multigrid_.setup(blocks_, *positions_, pinned, pairs))
  {
    // Not definite (or not finite): block Jacobi's CG meets it as it would and reports it.
    conjugateGradient(pinned, settings, settings.cg_max_iterations, report);
    return;
  }
  report.multigrid = true;
  // Preconditioned CG from the warm start on the filtered system, which the hierarchy's finest level
  // holds (pinned rows and columns cleared): its product is zero on pinned rows of a filtered
  // direction, and so is a cycle of a filtered residual (filtered again all the same).
  filter(pinned, delta_v_);
  residual_ = rhs_;
  filter(pinned, residual_);
  const double free_mass = freeMass(pinned);
  const double rhs_norm = residualNorms(residual_, free_mass).euclidean;
  multigrid_.multiplyFinest(delta_v_, multigrid_product_);
  residual_ -= multigrid_product_;
  filter(pinned, residual_);
  ResidualNorms norms = residualNorms(residual_, free_mass);
  double rz = 0.0;
  auto precondition = [&] {
    multigrid_.apply(residual_, preconditioned_);
    filter(pinned, preconditioned_);
    return dot(residual_, preconditioned_);
  };
  if (!withinTolerance(norms, rhs_norm, settings))
  {
    rz = precondition();
    multigrid_direction_ = preconditioned_;
  }
  while (!withinTolerance(norms, rhs_norm, settings) && report.iterations < settings.cg_max_iterations)
  {
    multigrid_.multiplyFinest(multigrid_direction_, multigrid_product_);
    const double curvature = dot(multigrid_direction_, multigrid_product_);
    // Non-positive (or NaN) curvature, or r·z: A or the cycle is not positive definite.
    if (!(curvature > 0.0) || !(rz > 0.0))
    {
      report.breakdown = true;
      break;
    }
    const double alpha = rz / curvature;
    delta_v_ += alpha * multigrid_direction_;
    residual_ -= alpha * multigrid_product_;
    norms = residualNorms(residual_, free_mass);
    ++report.iterations;
    if (withinTolerance(norms, rhs_norm, settings)) break;
    const double rz_new = precondition();
    const double beta = rz_new / rz;
    rz = rz_new;
    multigrid_direction_ = preconditioned_ + beta * multigrid_direction_;
  }
  report.relative_residual = rhs_norm > 0.0 ? norms.euclidean / rhs_norm : 0.0;
  report.velocity_error = norms.velocity;
  report.converged = withinTolerance(norms, rhs_norm, settings) && std::isfinite(norms.euclidean);
}

void ImplicitEulerSolver::multiplyFilteredPairs(const std::vector<char>& pinned, const double* x, double* y)
{
  // Through the padded vectors of the pair product (which the multigrid's CG does not use otherwise).
  const int rows = static_cast<int>(diagonal_block_.size());
  shareLoop(workers_, rows, kParticlesPerVectorChunk, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
      direction_.col(i) = Eigen::Vector3d::Map(x + 3 * i);
  });
  multiply(direction_, product_, true);
  shareLoop(workers_, rows, kParticlesPerVectorChunk, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
    {
      if (pinned[i])
        Eigen::Vector3d::Map(y + 3 * i).setZero();
      else
        Eigen::Vector3d::Map(y + 3 * i) = product_.col(i);
    }
  });
}

double ImplicitEulerSolver::freeMass(const std::vector<char>& pinned) const
{
  double free_mass = 0.0;
  for (int i = 0; i < static_cast<int>(pinned.size()); ++i)
    free_mass += pinned[i] ? 0.0 : (*mass_)[i];
  return free_mass;
}

ImplicitEulerSolver::ResidualNorms ImplicitEulerSolver::residualNorms(const Eigen::Matrix3Xd& r, double free_mass) const
{
  // |r| and |r|_M⁻¹ / sqrt(Σ m) in one pass, with begin()'s 1/m (pinned rows are zero after
  // filtering; a massless particle, which only a pinned one can be, adds nothing).
  double squared = 0.0, weighted = 0.0;
  for (int i = 0; i < static_cast<int>(r.cols()); ++i)
  {
    const double s = r.col(i).squaredNorm();
    squared += s;
    weighted += inverse_mass_[i] * s;
  }
  return normsOf(squared, weighted, free_mass);
}

ImplicitEulerSolver::ResidualNorms ImplicitEulerSolver::normsOf(double squared, double weighted, double free_mass)
{
  return {std::sqrt(squared), free_mass > 0.0 ? std::sqrt(weighted / free_mass) : 0.0};
}

}  // namespace core
}  // namespace particle_sim
