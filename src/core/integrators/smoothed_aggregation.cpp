#include "particle_sim/core/integrators/smoothed_aggregation.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <type_traits>

namespace particle_sim
{
namespace core
{
namespace
{
constexpr int kModes = SmoothedAggregation::kModes;

template <int R, int C>
using BlockMap = Eigen::Map<Eigen::Matrix<double, R, C, Eigen::RowMajor>>;
template <int R, int C>
using ConstBlockMap = Eigen::Map<const Eigen::Matrix<double, R, C, Eigen::RowMajor>>;
template <int N>
using SegmentMap = Eigen::Map<Eigen::Matrix<double, N, 1>>;
template <int N>
using ConstSegmentMap = Eigen::Map<const Eigen::Matrix<double, N, 1>>;

// Power iterations for the largest eigenvalue of D⁻¹ A, and the margin its estimate is raised by
// (the iterations approach it from below): the smoother's ω ρ then stays below 2 with room to spare.
constexpr int kPowerIterations = 12;
// From the last setup's vector (SmoothedAggregation::setupLevel()).
constexpr int kWarmPowerIterations = 3;
// θ of the strength of a coupling (SmoothedAggregation::planNextLevel()): Vaněk, Mandel & Brezina's
// 0.08 for elasticity.
constexpr double kStrongCoupling = 0.08;
constexpr double kSpectralMargin = 1.1;
// A mode whose part orthogonal to the ones before is below this fraction of its norm (or that is zero:
// every particle of the aggregate pinned, a rotation about a straight rope's axis) is dropped.
constexpr double kDroppedMode = 1e-10;
// The coarsest level is factored densely up to this many unknowns (else smoothed by block Jacobi
// alone: a body whose graph does not coarsen, such as particles without couplings).
constexpr int kMaxDenseUnknowns = 1200;

// Position of `value` in the sorted range [first, last) (it must be there).
int positionIn(const std::vector<int>& sorted, int first, int last, int value)
{
  return static_cast<int>(std::lower_bound(sorted.begin() + first, sorted.begin() + last, value) - sorted.begin());
}

// Sorted rows of unique columns, as block-sparse rows (start, column).
void compressRows(std::vector<std::vector<int>>& rows, std::vector<int>& start, std::vector<int>& column)
{
  start.assign(rows.size() + 1, 0);
  column.clear();
  for (std::size_t i = 0; i < rows.size(); ++i)
  {
    std::sort(rows[i].begin(), rows[i].end());
    rows[i].erase(std::unique(rows[i].begin(), rows[i].end()), rows[i].end());
    column.insert(column.end(), rows[i].begin(), rows[i].end());
    start[i + 1] = static_cast<int>(column.size());
  }
}

// Nodes per chunk of a loop over a level's nodes that `workers` share: some 2048 3x3 block rows of
// a cloth (13 blocks each with its bend springs), about 50 µs of work, and 128 6x6 rows, some 10 µs,
// so that the second coarse level of a 128² cloth (about 200 nodes) is shared too and the first
// (about 1800) splits evenly (its step at two threads, side by side: 6 % slower with 512 6x6 rows a
// chunk, the same with 64, or with 1024 3x3 rows); a loop's handover, a few microseconds, is a few per
// cent of a chunk; a level smaller than one chunk runs on the calling thread.
template <int B>
constexpr int kNodesPerChunk = B == 3 ? 2048 : 128;

// y = A x for a matrix of B x B row-major blocks in block-sparse rows (start, column), x and y B
// numbers a node: each row's blocks summed in their order, the rows shared with `workers` (each row
// alone: the same bits at any thread count). Block k of row i multiplies the node sourceOf(k, i) of
// x (its column, or another node for a matrix with blocks moved). With `rhs` not null, y = rhs − A x
// instead (the residual, in the same operations as the product and then the difference: its bits).
template <int B, typename Source>
void blockSparseProduct(WorkerPool* workers, int nodes, const std::vector<int>& start, const std::vector<double>& a,
                        const double* x, const double* rhs, double* y, const Source& sourceOf)
{
  shareLoop(workers, nodes, kNodesPerChunk<B>, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
    {
      Eigen::Matrix<double, B, 1> sum = Eigen::Matrix<double, B, 1>::Zero();
      for (int k = start[i]; k < start[i + 1]; ++k)
        sum.noalias() += ConstBlockMap<B, B>(a.data() + B * B * k) * ConstSegmentMap<B>(x + B * sourceOf(k, i));
      if (rhs)
        SegmentMap<B>(y + B * i) = ConstSegmentMap<B>(rhs + B * i) - sum;
      else
        SegmentMap<B>(y + B * i) = sum;
    }
  });
}

template <int B>
void blockSparseProduct(WorkerPool* workers, int nodes, const std::vector<int>& start, const std::vector<int>& column,
                        const std::vector<double>& a, const double* x, double* y, const double* rhs = nullptr)
{
  blockSparseProduct<B>(workers, nodes, start, a, x, rhs, y, [&](int k, int) { return column[k]; });
}
}  // namespace

void SmoothedAggregation::setPattern(int particles, const std::vector<int>& row_start, const std::vector<int>& column)
{
  levels_.clear();
  levels_.emplace_back();
  Level& finest = levels_.back();
  finest.nodes = particles;
  finest.block = 3;
  finest.start = row_start;
  finest.column = column;
  layOut(finest);
  planned_ = false;
}

void SmoothedAggregation::layOut(Level& level)
{
  level.diagonal.resize(level.nodes);
  for (int i = 0; i < level.nodes; ++i)
    level.diagonal[i] = positionIn(level.column, level.start[i], level.start[i + 1], i);
  const int b = level.block;
  level.a.assign(level.column.size() * b * b, 0.0);
  level.inverse_diagonal.assign(static_cast<std::size_t>(level.nodes) * b * b, 0.0);
  level.modes.assign(static_cast<std::size_t>(level.nodes) * b * kModes, 0.0);
  for (Eigen::VectorXd* v : {&level.rhs, &level.x, &level.residual, &level.chebyshev_step, &level.first_visit_x,
                             &level.first_visit_rhs, &level.power, &level.power_product})
    v->setZero(static_cast<Eigen::Index>(level.nodes) * b);
}

bool SmoothedAggregation::planAndSetUp(const Eigen::Matrix3Xd& x, const std::vector<char>& pinned)
{
  // Each level is aggregated by the strength of its couplings in this first system, and its numbers
  // made, before the next level is aggregated from those; until a level is small enough to factor,
  // or stops shrinking.
  for (int index = 0; levels_[index].nodes > kCoarsestNodes; ++index)
  {
    const int nodes = levels_[index].nodes;
    planNextLevel(index);
    // Aggregation that leaves three quarters of the nodes does not pay for a level.
    if (4 * levels_.back().nodes > 3 * nodes)
    {
      levels_.pop_back();
      levels_[index].aggregate.clear();
      levels_[index].members.clear();
      break;
    }
    if (index == 0) finestModes(x, pinned);
    if (levels_[index].block == 3)
      setupLevel<3>(index);
    else
      setupLevel<kModes>(index);
  }
  const Level& coarsest = levels_.back();
  const int unknowns = coarsest.nodes * coarsest.block;
  const int dense = unknowns <= kMaxDenseUnknowns ? unknowns : 0;
  coarsest_.setZero(dense, dense);  // its factor takes its room at its first compute(), below
  return setUpCoarsest();
}

void SmoothedAggregation::planNextLevel(int index)
{
  // Aggregation (Vaněk, Mandel & Brezina's three passes over the graph of strong couplings: j is a
  // strong neighbour of i when |A_ij| >= θ sqrt(|A_ii| |A_jj|) in Frobenius norms, so that a cloth's
  // bend springs, ten times weaker than its stretch springs and two particles long, do not make
  // aggregates of five particles across):
  // 1. a node whose strong neighbours are all free makes an aggregate with them;
  // 2. every node left joins the aggregate of pass 1 that most of its strong neighbours belong to
  //    (the first such in column order on a tie);
  // 3. a node still left (no strong neighbour aggregated) makes an aggregate with its free ones.
  Level& level = levels_[index];
  const int n = level.nodes;
  const int bb = level.block * level.block;
  auto blockNorm = [&](int k) {
    return Eigen::Map<const Eigen::VectorXd>(level.a.data() + static_cast<std::size_t>(bb) * k, bb).norm();
  };
  std::vector<char>& strong = level.strong;
  strong.assign(level.column.size(), 0);
  level.has_weak = false;
  for (int i = 0; i < n; ++i)
    for (int k = level.start[i]; k < level.start[i + 1]; ++k)
    {
      const int j = level.column[k];
      const double coupling = blockNorm(k);
      strong[k] = j == i || coupling * coupling >= kStrongCoupling * kStrongCoupling * blockNorm(level.diagonal[i]) *
                                                       blockNorm(level.diagonal[j]);
      if (!strong[k] && coupling > 0.0) level.has_weak = true;
    }
  std::vector<int>& aggregate = level.aggregate;
  aggregate.assign(n, -1);
  int aggregates = 0;
  for (int i = 0; i < n; ++i)
  {
    bool free = aggregate[i] < 0;
    for (int k = level.start[i]; free && k < level.start[i + 1]; ++k)
      free = !strong[k] || aggregate[level.column[k]] < 0;
    if (!free) continue;
    for (int k = level.start[i]; k < level.start[i + 1]; ++k)
      if (strong[k]) aggregate[level.column[k]] = aggregates;
    ++aggregates;
  }
  const std::vector<int> first_pass = aggregate;
  for (int i = 0; i < n; ++i)
  {
    if (aggregate[i] >= 0) continue;
    int best = -1, best_count = 0;
    for (int k = level.start[i]; k < level.start[i + 1]; ++k)
    {
      const int candidate = strong[k] ? first_pass[level.column[k]] : -1;
      if (candidate < 0) continue;
      int count = 0;
      for (int l = level.start[i]; l < level.start[i + 1]; ++l)
        count += strong[l] && first_pass[level.column[l]] == candidate;
      if (count > best_count)
      {
        best = candidate;
        best_count = count;
      }
    }
    aggregate[i] = best;
  }
  for (int i = 0; i < n; ++i)
  {
    if (aggregate[i] >= 0) continue;
    for (int k = level.start[i]; k < level.start[i + 1]; ++k)
      if (strong[k] && aggregate[level.column[k]] < 0) aggregate[level.column[k]] = aggregates;
    ++aggregates;
  }
  level.members.assign(aggregates, {});
  for (int i = 0; i < n; ++i)
    level.members[aggregate[i]].push_back(i);

  // P has a block (i, J) where a strong neighbour of i (or i) is in aggregate J (it is smoothed by the
  // lumped matrix A_L); A P a block (i, J) where P has one in a neighbour's row; A_c = Pᵀ (A P) a
  // block (I, J) where a row has P's (·, I) and A P's (·, J).
  std::vector<std::vector<int>> rows(n);
  for (int i = 0; i < n; ++i)
    for (int k = level.start[i]; k < level.start[i + 1]; ++k)
      if (strong[k]) rows[i].push_back(aggregate[level.column[k]]);
  compressRows(rows, level.p_start, level.p_column);
  // Pᵀ's rows: for each aggregate, the blocks of P in its column, by ascending row (the restriction's
  // gather, in the order in which the rows of P would add into it).
  level.pt_start.assign(aggregates + 1, 0);
  for (const int column : level.p_column)
    ++level.pt_start[column + 1];
  for (int a = 0; a < aggregates; ++a)
    level.pt_start[a + 1] += level.pt_start[a];
  level.pt_block.resize(level.p_column.size());
  level.pt_row.resize(level.p_column.size());
  {
    std::vector<int> filled(level.pt_start.begin(), level.pt_start.end() - 1);
    for (int i = 0; i < n; ++i)
      for (int q = level.p_start[i]; q < level.p_start[i + 1]; ++q)
      {
        const int slot = filled[level.p_column[q]]++;
        level.pt_block[slot] = q;
        level.pt_row[slot] = i;
      }
  }
  for (int i = 0; i < n; ++i)
  {
    rows[i].clear();
    for (int k = level.start[i]; k < level.start[i + 1]; ++k)
    {
      const int j = level.column[k];
      rows[i].insert(rows[i].end(), level.p_column.begin() + level.p_start[j],
                     level.p_column.begin() + level.p_start[j + 1]);
    }
  }
  compressRows(rows, level.ap_start, level.ap_column);
  std::vector<std::vector<int>> coarse_rows(aggregates);
  for (int i = 0; i < n; ++i)
    for (int q = level.p_start[i]; q < level.p_start[i + 1]; ++q)
    {
      std::vector<int>& row = coarse_rows[level.p_column[q]];
      row.insert(row.end(), level.ap_column.begin() + level.ap_start[i],
                 level.ap_column.begin() + level.ap_start[i + 1]);
    }
  Level next;
  next.nodes = aggregates;
  next.block = kModes;
  compressRows(coarse_rows, next.start, next.column);

  // The plans: every block product of A P, row after row, and of Pᵀ (A P), by the row of A_c it adds
  // into (a column of P) and within that by ascending row of A P (Pᵀ's rows, pt_block and pt_row,
  // are in that order). Each row of A P and each row of A_c is so made by one plan range alone, which
  // the workers share; of A_c only the blocks on and above the diagonal are summed (A_c is symmetric),
  // the ones below copied from them after.
  level.ap_plan.clear();
  level.ap_plan_start.assign(n + 1, 0);
  for (int i = 0; i < n; ++i)
  {
    const int first = level.ap_start[i], last = level.ap_start[i + 1];
    for (int k = level.start[i]; k < level.start[i + 1]; ++k)
    {
      const int j = level.column[k];
      for (int q = level.p_start[j]; q < level.p_start[j + 1]; ++q)
        level.ap_plan.push_back({k, q, positionIn(level.ap_column, first, last, level.p_column[q])});
    }
    level.ap_plan_start[i + 1] = static_cast<int>(level.ap_plan.size());
  }
  level.galerkin_plan.clear();
  level.galerkin_plan_start.assign(aggregates + 1, 0);
  for (int coarse_row = 0; coarse_row < aggregates; ++coarse_row)
  {
    for (int slot = level.pt_start[coarse_row]; slot < level.pt_start[coarse_row + 1]; ++slot)
    {
      const int i = level.pt_row[slot];
      for (int t = level.ap_start[i]; t < level.ap_start[i + 1]; ++t)
      {
        if (level.ap_column[t] < coarse_row) continue;
        level.galerkin_plan.push_back(
            {slot, t, positionIn(next.column, next.start[coarse_row], next.start[coarse_row + 1], level.ap_column[t])});
      }
    }
    level.galerkin_plan_start[coarse_row + 1] = static_cast<int>(level.galerkin_plan.size());
  }
  for (int row = 0; row < next.nodes; ++row)
    for (int k = next.start[row]; k < next.start[row + 1]; ++k)
    {
      const int column = next.column[k];
      if (column < row)
        next.mirrored.push_back({k, positionIn(next.column, next.start[column], next.start[column + 1], row)});
    }
  const int b = level.block;
  if (level.has_weak)
  {
    level.lumped_inverse_diagonal.assign(static_cast<std::size_t>(n) * b * b, 0.0);
    level.lumped_power.setZero(static_cast<Eigen::Index>(n) * b);
    level.lumped_power_product.setZero(static_cast<Eigen::Index>(n) * b);
  }
  level.tentative.assign(static_cast<std::size_t>(n) * b * kModes, 0.0);
  level.p.assign(level.p_column.size() * b * kModes, 0.0);
  level.pt_p.assign(level.p.size(), 0.0);
  level.ap.assign(level.ap_column.size() * b * kModes, 0.0);
  levels_.push_back(std::move(next));
  layOut(levels_.back());
}

void SmoothedAggregation::copyFinest(const std::vector<Eigen::Matrix3d>& blocks, const std::vector<char>& pinned,
                                     const FinestPairs& pairs)
{
  // The finest matrix, filtered: a pinned particle's row and column cleared but for an identity on
  // the diagonal (it decouples; the residual is zero there).
  Level& finest = levels_[0];
  shareLoop(workers_, finest.nodes, kNodesPerChunk<3>, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
    {
      for (int k = finest.start[i]; k < finest.start[i + 1]; ++k)
      {
        const int j = finest.column[k];
        BlockMap<3, 3> a(finest.a.data() + 9 * k);
        if (!pinned[i] && !pinned[j])
          a = blocks[k];
        else if (j == i)
          a.setIdentity();
        else
          a.setZero();
      }
    }
  });
  // The pairs, in their order, into the blocks of particles that are not pinned (the others are
  // filtered above): 0 + C, then any later pair's C, as the solver's own blocks would sum them.
  for (int k = 0; k < pairs.count; ++k)
  {
    if (pinned[pairs.ends[k][0]] || pinned[pairs.ends[k][1]]) continue;
    const Eigen::Matrix3d block = symmetricBlock(pairs.c[k]);
    for (const int b : pairs.blocks[k])
      BlockMap<3, 3>(finest.a.data() + 9 * b) += block;
  }
}

bool SmoothedAggregation::setup(const std::vector<Eigen::Matrix3d>& blocks, const Eigen::Matrix3Xd& x,
                                const std::vector<char>& pinned)
{
  return setup(blocks, x, pinned, FinestPairs());
}

bool SmoothedAggregation::setup(const std::vector<Eigen::Matrix3d>& blocks, const Eigen::Matrix3Xd& x,
                                const std::vector<char>& pinned, const FinestPairs& pairs)
{
  copyFinest(blocks, pinned, pairs);
  if (!planned_)
  {
    planned_ = true;
    return planAndSetUp(x, pinned);
  }
  if (levels_.size() > 1) finestModes(x, pinned);
  for (int l = 0; l + 1 < static_cast<int>(levels_.size()); ++l)
  {
    if (levels_[l].block == 3)
      setupLevel<3>(l);
    else
      setupLevel<kModes>(l);
  }
  return setUpCoarsest();
}

void SmoothedAggregation::finestModes(const Eigen::Matrix3Xd& x, const std::vector<char>& pinned)
{
  // The rigid-body modes (zero for a pinned particle) of each particle about its aggregate's centroid:
  // the translations, and the rotations e_k × (x_i − c) about the three axes.
  Level& finest = levels_[0];
  for (const std::vector<int>& members : finest.members)
  {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const int i : members)
      centroid += x.col(i);
    centroid /= static_cast<double>(members.size());
    for (const int i : members)
    {
      BlockMap<3, kModes> mode(finest.modes.data() + 3 * kModes * i);
      if (pinned[i])
      {
        mode.setZero();
        continue;
      }
      const Eigen::Vector3d p = x.col(i) - centroid;
      mode << 1, 0, 0, 0, p.z(), -p.y(),  //
          0, 1, 0, -p.z(), 0, p.x(),      //
          0, 0, 1, p.y(), -p.x(), 0;
    }
  }
}

bool SmoothedAggregation::setUpCoarsest()
{
  // The inverse diagonal of the coarsest level (for a coarsest level too large to factor), then its
  // factorization.
  if (levels_.back().block == 3)
    setupLevel<3>(static_cast<int>(levels_.size()) - 1);
  else
    setupLevel<kModes>(static_cast<int>(levels_.size()) - 1);
  return factorCoarsest();
}

template <int B>
void SmoothedAggregation::tentativeOfAggregate(Level& level, Level& next, int a)
{
  // Aggregate a's modes, orthonormalised by modified Gram–Schmidt (twice, for orthogonality to
  // rounding), as its members' rows of Q; R is the next level's modes of its node.
  const std::vector<int>& members = level.members[a];
  BlockMap<kModes, kModes> r(next.modes.data() + kModes * kModes * a);
  r.setZero();
  for (const int i : members)
    BlockMap<B, kModes>(level.tentative.data() + B * kModes * i) =
        ConstBlockMap<B, kModes>(level.modes.data() + B * kModes * i);
  for (int c = 0; c < kModes; ++c)
  {
    double before = 0.0;
    for (const int i : members)
      before += BlockMap<B, kModes>(level.tentative.data() + B * kModes * i).col(c).squaredNorm();
    for (int pass = 0; pass < 2; ++pass)
      for (int e = 0; e < c; ++e)
      {
        double projection = 0.0;
        for (const int i : members)
        {
          const BlockMap<B, kModes> q(level.tentative.data() + B * kModes * i);
          projection += q.col(e).dot(q.col(c));
        }
        for (const int i : members)
        {
          BlockMap<B, kModes> q(level.tentative.data() + B * kModes * i);
          q.col(c) -= projection * q.col(e);
        }
        r(e, c) += projection;
      }
    double after = 0.0;
    for (const int i : members)
      after += BlockMap<B, kModes>(level.tentative.data() + B * kModes * i).col(c).squaredNorm();
    const bool dropped = !(after > kDroppedMode * kDroppedMode * before) || !(before > 0.0);
    const double norm = std::sqrt(after);
    r(c, c) = dropped ? 0.0 : norm;
    for (const int i : members)
    {
      BlockMap<B, kModes> q(level.tentative.data() + B * kModes * i);
      if (dropped)
        q.col(c).setZero();
      else
        q.col(c) /= norm;
    }
  }
}

template <int B>
void SmoothedAggregation::setupLevel(int index)
{
  Level& level = levels_[index];
  const int n = level.nodes;
  // The inverse of each diagonal block. A mode dropped on the level above left its row and column
  // empty: its diagonal is set to one, so that it decouples.
  shareLoop(workers_, n, kNodesPerChunk<B>, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
    {
      BlockMap<B, B> diagonal(level.a.data() + B * B * level.diagonal[i]);
      for (int d = 0; d < B; ++d)
        if (diagonal(d, d) == 0.0) diagonal(d, d) = 1.0;
      BlockMap<B, B>(level.inverse_diagonal.data() + B * B * i) = diagonal.inverse();
    }
  });
  if (static_cast<std::size_t>(index) + 1 == levels_.size()) return;

  // The smoother's damping; and the lumped matrix's inverse diagonal blocks D_L,i = A_ii + Σ of the
  // row's weak blocks (where one is not invertible, A_ii's inverse stands in) and its damping.
  level.omega = smootherDamping<B>(
      workers_, n, level.inverse_diagonal,
      [&](const Eigen::VectorXd& x, Eigen::VectorXd& y) { multiply<B>(level, x, y); }, level.power, level.power_product,
      level.power_started);
  // The smoother's Chebyshev polynomial (chebyshevSteps()) on [u / α, u] stops contracting where
  // t > u (1 + 1 / α); u is set so that this is 2 / ω, where damped Jacobi with the damping ω (the
  // cycle's smoother until 2026-12-07; P's below where the level has no weak couplings) would stop:
  // a true ρ up to 1.5 kSpectralMargin times the power iterations' estimate breaks neither (u is
  // 1.5 times the estimate, the interval reaching past it). A ρ of zero (no coupling left) leaves the
  // smoothing out, as Jacobi's ω = 0 would.
  level.smoother =
      level.omega > 0.0 ? chebyshevSteps(2.0 / (level.omega * (1.0 + 1.0 / kChebyshevRange))) : ChebyshevSteps{};
  if (level.has_weak)
  {
    shareLoop(workers_, n, kNodesPerChunk<B>, [&](int begin, int end) {
      for (int i = begin; i < end; ++i)
      {
        Eigen::Matrix<double, B, B> diagonal = ConstBlockMap<B, B>(level.a.data() + B * B * level.diagonal[i]);
        for (int k = level.start[i]; k < level.start[i + 1]; ++k)
          if (!level.strong[k]) diagonal += ConstBlockMap<B, B>(level.a.data() + B * B * k);
        const Eigen::Matrix<double, B, B> inverse = diagonal.inverse();
        BlockMap<B, B>(level.lumped_inverse_diagonal.data() + B * B * i) =
            inverse.allFinite() ? inverse : ConstBlockMap<B, B>(level.inverse_diagonal.data() + B * B * i);
      }
    });
    level.lumped_omega = smootherDamping<B>(
        workers_, n, level.lumped_inverse_diagonal,
        [&](const Eigen::VectorXd& x, Eigen::VectorXd& y) { multiplyLumped<B>(level, x, y); }, level.lumped_power,
        level.lumped_power_product, level.lumped_power_started);
  }

  // The tentative prolongator, aggregate by aggregate (tentativeOfAggregate()): each aggregate alone
  // (its members' rows of P̂, its node's modes), so the aggregates are shared.
  Level& next = levels_[index + 1];
  shareLoop(workers_, next.nodes, kNodesPerChunk<kModes>, [&](int begin, int end) {
    for (int a = begin; a < end; ++a)
      tentativeOfAggregate<B>(level, next, a);
  });

  // P = (I − ω_L D_L⁻¹ A_L) P̂: row i's blocks first collect Σ_j A_L,ij P̂_j by the aggregate of j
  // (the strong blocks of A; the weak ones' part, A_ij P̂_i, is in i's own aggregate), then become
  // −ω_L D_L,i⁻¹ times that, plus P̂_i in i's own aggregate.
  const std::vector<double>& smoothing_inverse =
      level.has_weak ? level.lumped_inverse_diagonal : level.inverse_diagonal;
  const double smoothing_omega = level.has_weak ? level.lumped_omega : level.omega;
  // Each row of P alone (its own blocks), so the rows are shared with the workers.
  shareLoop(workers_, n, kNodesPerChunk<B>, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
    {
      const int first = level.p_start[i], last = level.p_start[i + 1];
      std::fill(level.p.begin() + B * kModes * first, level.p.begin() + B * kModes * last, 0.0);
      for (int k = level.start[i]; k < level.start[i + 1]; ++k)
      {
        const int j = level.strong[k] ? level.column[k] : i;
        if (!level.strong[k] && !level.has_weak) continue;  // a zero block
        const int q = positionIn(level.p_column, first, last, level.aggregate[j]);
        BlockMap<B, kModes>(level.p.data() + B * kModes * q).noalias() +=
            ConstBlockMap<B, B>(level.a.data() + B * B * k) *
            ConstBlockMap<B, kModes>(level.tentative.data() + B * kModes * j);
      }
      const ConstBlockMap<B, B> inverse(smoothing_inverse.data() + B * B * i);
      for (int q = first; q < last; ++q)
      {
        BlockMap<B, kModes> block(level.p.data() + B * kModes * q);
        const Eigen::Matrix<double, B, kModes> smoothed = -smoothing_omega * (inverse * block);
        block = smoothed;
      }
      const int own = positionIn(level.p_column, first, last, level.aggregate[i]);
      BlockMap<B, kModes>(level.p.data() + B * kModes * own) +=
          ConstBlockMap<B, kModes>(level.tentative.data() + B * kModes * i);
    }
  });

  // P's blocks copied in Pᵀ's order, aggregate by aggregate.
  shareLoop(workers_, next.nodes, kNodesPerChunk<kModes>, [&](int begin, int end) {
    for (int slot = level.pt_start[begin]; slot < level.pt_start[end]; ++slot)
      std::copy_n(level.p.data() + B * kModes * level.pt_block[slot], B * kModes,
                  level.pt_p.data() + B * kModes * slot);
  });

  // A P by its plan, each row alone; then A_c = Pᵀ (A P) by its plan, each row of A_c alone (its
  // blocks on and above the diagonal); then its lower blocks from the upper ones.
  shareLoop(workers_, n, kNodesPerChunk<B>, [&](int begin, int end) {
    std::fill(level.ap.begin() + B * kModes * level.ap_start[begin],
              level.ap.begin() + B * kModes * level.ap_start[end], 0.0);
    for (int e = level.ap_plan_start[begin]; e < level.ap_plan_start[end]; ++e)
    {
      const auto& [k, q, t] = level.ap_plan[e];
      BlockMap<B, kModes>(level.ap.data() + B * kModes * t).noalias() +=
          ConstBlockMap<B, B>(level.a.data() + B * B * k) * ConstBlockMap<B, kModes>(level.p.data() + B * kModes * q);
    }
  });
  shareLoop(workers_, next.nodes, kNodesPerChunk<kModes>, [&](int begin, int end) {
    std::fill(next.a.begin() + kModes * kModes * next.start[begin], next.a.begin() + kModes * kModes * next.start[end],
              0.0);
    for (int e = level.galerkin_plan_start[begin]; e < level.galerkin_plan_start[end]; ++e)
    {
      const auto& [slot, t, c] = level.galerkin_plan[e];
      BlockMap<kModes, kModes>(next.a.data() + kModes * kModes * c).noalias() +=
          ConstBlockMap<B, kModes>(level.pt_p.data() + B * kModes * slot).transpose() *
          ConstBlockMap<B, kModes>(level.ap.data() + B * kModes * t);
    }
  });
  for (const auto& [lower, upper] : next.mirrored)
    BlockMap<kModes, kModes>(next.a.data() + kModes * kModes * lower) =
        ConstBlockMap<kModes, kModes>(next.a.data() + kModes * kModes * upper).transpose();
}

double SmoothedAggregation::cycleFlops() const
{
  if (!planned_) return 0.0;
  // Each level's visits in one cycle: the first coarse level once, each one below it kCoarseVisits
  // times as often as the level above (cycle(), visitNext()), the coarsest as often as the one
  // above it.
  const double unknowns = static_cast<double>(coarsest_.rows());
  double flops = 0.0, visits = 1.0;
  for (std::size_t l = 0; l + 1 < levels_.size(); ++l)
  {
    const Level& level = levels_[l];
    const double b = level.block, p_blocks = level.p_start.back();
    double visit = smoothingFlops(level);
    visit += 2.0 * 2.0 * b * kModes * p_blocks;  // restriction and prolongation
    // The further visits of the next level (visitNext()): its residual and sum each.
    const Level& next = levels_[l + 1];
    const int next_visits = visitsOfNext(static_cast<int>(l));
    visit += (next_visits - 1) * (2.0 * kModes * kModes * next.start.back() + kModes * next.nodes);
    flops += visits * visit;
    visits *= next_visits;
  }
  const Level& coarsest = levels_.back();
  // The coarsest level's solve: with its dense factor (two triangular solves), else its block Jacobi.
  flops += visits * (unknowns > 0.0 ? 2.0 * unknowns * unknowns
                                    : 2.0 * coarsest.block * coarsest.block * static_cast<double>(coarsest.nodes));
  return flops;
}

double SmoothedAggregation::finestCycleFlops() const
{
  if (!planned_ || levels_.size() < 2) return 0.0;
  return smoothingFlops(levels_[0]);
}

double SmoothedAggregation::smoothingFlops(const Level& level)
{
  // 2 kSmoothingSweeps smoothings D⁻¹ r and as many residuals r − A x.
  const double b = level.block;
  return 2.0 * kSmoothingSweeps * 2.0 * b * b * (static_cast<double>(level.nodes) + level.start.back());
}

int SmoothedAggregation::visitsOfNext(int index) const
{
  // The finest level visits the first coarse level once. A second visit makes the correction
  // (2 B − B A_c B) r_c, positive definite while the cycle below is a contraction (‖I − B A_c‖ < 1
  // in A_c's norm), which the damped smoothers and the coarsest's exact solve make it; the
  // coarsest's undamped block Jacobi (a level too large to factor) does not promise that, so then
  // one visit only. One also when the next level is the coarsest: its exact solve leaves nothing for
  // a second visit.
  const bool last_above_coarsest = static_cast<std::size_t>(index) + 2 == levels_.size();
  return index == 0 || last_above_coarsest || coarsest_.rows() == 0 ? 1 : kCoarseVisits;
}

double SmoothedAggregation::setupFlops() const
{
  if (!planned_) return 0.0;
  double flops = 0.0;
  for (std::size_t l = 0; l < levels_.size(); ++l)
  {
    const Level& level = levels_[l];
    const double b = level.block, nodes = level.nodes, blocks = level.start.back();
    flops += 2.0 * b * b * b * nodes;  // the inverse diagonal blocks
    if (l + 1 == levels_.size()) break;
    // The power iterations (warm: from the last setup's vector), of A and of the lumped matrix.
    const double power = kWarmPowerIterations * (2.0 * b * b * (blocks + nodes) + 3.0 * b * nodes);
    flops += level.has_weak ? 2.0 * power + b * b * blocks + 2.0 * b * b * b * nodes : power;
    // P̂ by Gram–Schmidt (two passes over the modes' pairs, a dot and an update each), then P's
    // smoothing: A_L P̂ by blocks of A, and D_L⁻¹ times each block of P.
    flops += 2.0 * 15.0 * 2.0 * 2.0 * b * nodes;
    flops += 2.0 * b * b * kModes * (blocks + static_cast<double>(level.p_start.back()));
    // A P and Pᵀ (A P), by their plans.
    flops += 2.0 * b * b * kModes * static_cast<double>(level.ap_plan.size());
    flops += 2.0 * kModes * b * kModes * static_cast<double>(level.galerkin_plan.size());
  }
  const double unknowns = static_cast<double>(coarsest_.rows());
  flops += unknowns * unknowns * unknowns / 3.0;  // the coarsest L D Lᵀ
  return flops;
}

void SmoothedAggregation::forgetHistory()
{
  for (Level& level : levels_)
    level.power_started = level.lumped_power_started = false;
}

bool SmoothedAggregation::factorCoarsest()
{
  const Level& coarsest = levels_.back();
  if (coarsest_.rows() == 0) return true;  // block Jacobi there
  const int b = coarsest.block;
  coarsest_.setZero();
  for (int i = 0; i < coarsest.nodes; ++i)
    for (int k = coarsest.start[i]; k < coarsest.start[i + 1]; ++k)
      for (int r = 0; r < b; ++r)
        for (int c = 0; c < b; ++c)
          coarsest_(b * i + r, b * coarsest.column[k] + c) = coarsest.a[b * b * k + b * r + c];
  coarsest_factor_.compute(coarsest_);
  // Positive definite: every pivot positive and finite.
  if (coarsest_factor_.info() != Eigen::Success) return false;
  const auto pivots = coarsest_factor_.vectorD();
  for (Eigen::Index k = 0; k < pivots.size(); ++k)
    if (!(pivots[k] > 0.0) || !std::isfinite(pivots[k])) return false;
  return true;
}

template <int B>
void SmoothedAggregation::multiply(const Level& level, const Eigen::VectorXd& x, Eigen::VectorXd& y) const
{
  blockSparseProduct<B>(workers_, level.nodes, level.start, level.column, level.a, x.data(), y.data());
}

template <int B>
void SmoothedAggregation::residualOf(const Level& level, const Eigen::VectorXd& x, Eigen::VectorXd& residual) const
{
  blockSparseProduct<B>(workers_, level.nodes, level.start, level.column, level.a, x.data(), residual.data(),
                        level.rhs.data());
}

template <int B>
void SmoothedAggregation::multiplyLumped(const Level& level, const Eigen::VectorXd& x, Eigen::VectorXd& y) const
{
  blockSparseProduct<B>(workers_, level.nodes, level.start, level.a, x.data(), nullptr, y.data(),
                        [&](int k, int i) { return level.strong[k] ? level.column[k] : i; });
}

template <int B, typename Product>
double SmoothedAggregation::smootherDamping(WorkerPool* workers, int nodes, const std::vector<double>& inverse_diagonal,
                                            const Product& product, Eigen::VectorXd& power,
                                            Eigen::VectorXd& power_product, bool& power_started)
{
  // ρ(D⁻¹ A) by power iterations: at the first setup (or after forgetHistory()) from a fixed start,
  // later from the last setup's vector, which the system of a step later hardly turns (the same
  // setups in the same order: the same bits).
  int iterations = kWarmPowerIterations;
  if (!power_started)
  {
    for (int k = 0; k < power.size(); ++k)
      power[k] = 1.0 + 0.5 * std::sin(0.7 * k);
    power_started = true;
    iterations = kPowerIterations;
  }
  double rho = 0.0;
  for (int iteration = 0; iteration < iterations; ++iteration)
  {
    product(power, power_product);
    shareLoop(workers, nodes, kNodesPerChunk<B>, [&](int begin, int end) {
      for (int i = begin; i < end; ++i)
        SegmentMap<B>(power.data() + B * i).noalias() =
            ConstBlockMap<B, B>(inverse_diagonal.data() + B * B * i) * ConstSegmentMap<B>(power_product.data() + B * i);
    });
    const double norm = power.norm();
    if (!(norm > 0.0) || !std::isfinite(norm))
    {
      power_started = false;  // start afresh next time
      break;
    }
    rho = norm;  // |D⁻¹ A v| for |v| = 1
    power /= norm;
  }
  return rho > 0.0 ? 4.0 / (3.0 * kSpectralMargin * rho) : 0.0;
}

SmoothedAggregation::ChebyshevSteps SmoothedAggregation::chebyshevSteps(double upper)
{
  // The three-term recurrence of the Chebyshev polynomials shifted to [lower, upper] (centre θ,
  // half-width δ, σ = θ / δ): the first step is D⁻¹ r / θ, each next one
  // step_k = g_k g_{k−1} step_{k−1} + (2 g_k / δ) D⁻¹ r with g_k = 1 / (2 σ − g_{k−1}), g_0 = 1 / σ
  // (g_k = T_k(σ) / T_{k+1}(σ)). After k steps from x the error is T_k((θ − t) / δ) / T_k(σ) of what
  // it was, on each eigenvector of D⁻¹ A with eigenvalue t.
  const double lower = upper / kChebyshevRange;
  const double theta = 0.5 * (upper + lower), delta = 0.5 * (upper - lower), sigma = theta / delta;
  ChebyshevSteps steps;
  double g = 1.0 / sigma;
  steps.keep[0] = 0.0;
  steps.scale[0] = 1.0 / theta;
  for (int k = 1; k < kSmoothingSweeps; ++k)
  {
    const double g_next = 1.0 / (2.0 * sigma - g);
    steps.keep[k] = g_next * g;
    steps.scale[k] = 2.0 * g_next / delta;
    g = g_next;
  }
  return steps;
}

// step = keep step + scale D⁻¹ r, x += step, node by node.
template <int B>
void SmoothedAggregation::chebyshevStep(Level& level, const Eigen::VectorXd& residual, double keep, double scale)
{
  shareLoop(workers_, level.nodes, kNodesPerChunk<B>, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
    {
      SegmentMap<B> step(level.chebyshev_step.data() + B * i);
      const Eigen::Matrix<double, B, 1> correction =
          scale * (ConstBlockMap<B, B>(level.inverse_diagonal.data() + B * B * i) *
                   ConstSegmentMap<B>(residual.data() + B * i));
      if (keep == 0.0)
        step = correction;  // the first step: the last cycle's step is not read
      else
        step = keep * step + correction;
      SegmentMap<B>(level.x.data() + B * i) += step;
    }
  });
}

template <int B>
void SmoothedAggregation::restrictResidual(const Level& level, Eigen::VectorXd& coarse_rhs) const
{
  // Each aggregate gathers P_qᵀ r_i over its column's blocks (pt_p, in order), by ascending row i:
  // the sums of a scatter row after row, so the aggregates are shared with the workers.
  const int aggregates = static_cast<int>(level.pt_start.size()) - 1;
  shareLoop(workers_, aggregates, kNodesPerChunk<kModes>, [&](int begin, int end) {
    for (int a = begin; a < end; ++a)
    {
      Eigen::Matrix<double, kModes, 1> sum = Eigen::Matrix<double, kModes, 1>::Zero();
      for (int t = level.pt_start[a]; t < level.pt_start[a + 1]; ++t)
        sum.noalias() += ConstBlockMap<B, kModes>(level.pt_p.data() + B * kModes * t).transpose() *
                         ConstSegmentMap<B>(level.residual.data() + B * level.pt_row[t]);
      SegmentMap<kModes>(coarse_rhs.data() + kModes * a) = sum;
    }
  });
}

template <int B>
void SmoothedAggregation::prolongAdd(const Level& level, const Eigen::VectorXd& coarse, Eigen::VectorXd& x) const
{
  shareLoop(workers_, level.nodes, kNodesPerChunk<B>, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
    {
      Eigen::Matrix<double, B, 1> sum = Eigen::Matrix<double, B, 1>::Zero();
      for (int q = level.p_start[i]; q < level.p_start[i + 1]; ++q)
        sum.noalias() += ConstBlockMap<B, kModes>(level.p.data() + B * kModes * q) *
                         ConstSegmentMap<kModes>(coarse.data() + kModes * level.p_column[q]);
      SegmentMap<B>(x.data() + B * i) += sum;
    }
  });
}

void SmoothedAggregation::cycle(int index)
{
  Level& level = levels_[index];
  if (static_cast<std::size_t>(index) + 1 == levels_.size())
  {
    // The coarsest level: solved exactly (or by its block Jacobi when too large to factor).
    if (coarsest_.rows() > 0)
    {
      level.x = coarsest_factor_.solve(level.rhs);
      return;
    }
    const int b = level.block;
    for (int i = 0; i < level.nodes; ++i)
      level.x.segment(b * i, b).noalias() =
          Eigen::Map<const Eigen::MatrixXd>(level.inverse_diagonal.data() + b * b * i, b, b).transpose() *
          level.rhs.segment(b * i, b);
    return;
  }
  // Pre-smoothing from zero, the coarse correction of the residual left (visitNext()),
  // post-smoothing; in the kernels of the level's block size B.
  Level& next = levels_[index + 1];
  auto levelCycle = [&](auto block_size) {
    constexpr int B = decltype(block_size)::value;
    // The finest level's residuals through the product from outside when there is one.
    auto residual = [&] {
      if (index == 0 && use_finest_product_)
        finestResidualOutside(level.x, level.residual);
      else
        residualOf<B>(level, level.x, level.residual);
    };
    // One smoothing: kSmoothingSweeps Chebyshev steps, each after a residual but the first from
    // zero, whose residual is the rhs.
    auto smoothing = [&](bool from_zero) {
      for (int sweep = 0; sweep < kSmoothingSweeps; ++sweep)
      {
        if (sweep > 0 || !from_zero) residual();
        chebyshevStep<B>(level, sweep == 0 && from_zero ? level.rhs : level.residual, level.smoother.keep[sweep],
                         level.smoother.scale[sweep]);
      }
    };
    level.x.setZero();
    smoothing(true);
    residual();
    restrictResidual<B>(level, next.rhs);
    visitNext(index);
    prolongAdd<B>(level, next.x, level.x);
    smoothing(false);
  };
  if (level.block == 3)
    levelCycle(std::integral_constant<int, 3>());
  else
    levelCycle(std::integral_constant<int, kModes>());
}

void SmoothedAggregation::visitNext(int index)
{
  // The first visit solves for next.rhs; each further one for the residual its answer leaves on the
  // next level, r_c − A_c x_c (the restriction of the fine residual, A_c being Galerkin's), and adds
  // its answer. The next level's own vectors serve its cycles, so the first answer and the rhs wait
  // in first_visit_x and first_visit_rhs.
  Level& next = levels_[index + 1];
  cycle(index + 1);
  const int visits = visitsOfNext(index);
  if (visits == 1) return;
  next.first_visit_rhs = next.rhs;
  for (int visit = 1; visit < visits; ++visit)
  {
    next.first_visit_x = next.x;
    residualOf<kModes>(next, next.x, next.residual);
    next.rhs = next.residual;
    cycle(index + 1);
    next.x += next.first_visit_x;
    next.rhs = next.first_visit_rhs;
  }
}

void SmoothedAggregation::apply(const Eigen::Matrix3Xd& r, Eigen::Matrix3Xd& z)
{
  Level& finest = levels_[0];
  finest.rhs = Eigen::Map<const Eigen::VectorXd>(r.data(), r.size());
  cycle(0);
  Eigen::Map<Eigen::VectorXd>(z.data(), z.size()) = finest.x;
}

void SmoothedAggregation::finestResidualOutside(const Eigen::VectorXd& x, Eigen::VectorXd& residual) const
{
  const Level& finest = levels_[0];
  finest_product_(x.data(), residual.data());
  shareLoop(workers_, finest.nodes, kNodesPerChunk<3>, [&](int begin, int end) {
    residual.segment(3 * begin, 3 * (end - begin)) =
        finest.rhs.segment(3 * begin, 3 * (end - begin)) - residual.segment(3 * begin, 3 * (end - begin));
  });
}

void SmoothedAggregation::multiplyFinest(const Eigen::Matrix3Xd& x, Eigen::Matrix3Xd& y) const
{
  if (use_finest_product_)
  {
    finest_product_(x.data(), y.data());
    return;
  }
  const Level& finest = levels_[0];
  blockSparseProduct<3>(workers_, finest.nodes, finest.start, finest.column, finest.a, x.data(), y.data());
}

Eigen::VectorXd SmoothedAggregation::tentativeTimesCoarseModes(int index, int mode) const
{
  const Level& level = levels_[index];
  const Level& next = levels_[index + 1];
  const int b = level.block;
  Eigen::VectorXd out(static_cast<Eigen::Index>(level.nodes) * b);
  for (int i = 0; i < level.nodes; ++i)
  {
    const int a = level.aggregate[i];
    for (int r = 0; r < b; ++r)
    {
      double sum = 0.0;
      for (int c = 0; c < kModes; ++c)
        sum += level.tentative[b * kModes * i + kModes * r + c] * next.modes[kModes * kModes * a + kModes * c + mode];
      out[b * i + r] = sum;
    }
  }
  return out;
}

SmoothedAggregation::BlockRows SmoothedAggregation::matrixOf(int index) const
{
  const Level& level = levels_[index];
  return {level.nodes, level.nodes, level.block, level.block, level.start, level.column, level.a};
}

SmoothedAggregation::BlockRows SmoothedAggregation::prolongatorOf(int index) const
{
  const Level& level = levels_[index];
  return {level.nodes, levels_[index + 1].nodes, level.block, kModes, level.p_start, level.p_column, level.p};
}

Eigen::VectorXd SmoothedAggregation::modes(int index, int mode) const
{
  const Level& level = levels_[index];
  const int b = level.block;
  Eigen::VectorXd out(static_cast<Eigen::Index>(level.nodes) * b);
  for (int i = 0; i < level.nodes; ++i)
    for (int r = 0; r < b; ++r)
      out[b * i + r] = level.modes[b * kModes * i + kModes * r + mode];
  return out;
}

}  // namespace core
}  // namespace particle_sim
