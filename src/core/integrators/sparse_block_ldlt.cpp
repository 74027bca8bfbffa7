#include "particle_sim/core/integrators/sparse_block_ldlt.h"

#include <Eigen/LU>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>
#include <algorithm>
#include <atomic>
#include <cmath>

#include "particle_sim/core/integrators/dense_panel.h"
#include "particle_sim/core/worker_pool.h"

namespace particle_sim
{
namespace core
{
namespace
{
// The particles in a fill-reducing order: old_of[new] (approximate minimum degree on the pattern).
std::vector<int> fillReducingOrder(const std::vector<int>& row_start, const std::vector<int>& block_column)
{
  const int n = static_cast<int>(row_start.size()) - 1;
  std::vector<int> old_of(n);
  for (int i = 0; i < n; ++i)
    old_of[i] = i;
  if (n < 3) return old_of;
  std::vector<Eigen::Triplet<double, int>> entries;
  entries.reserve(block_column.size());
  for (int i = 0; i < n; ++i)
    for (int k = row_start[i]; k < row_start[i + 1]; ++k)
      entries.emplace_back(i, block_column[k], 1.0);
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> pattern(n, n);
  pattern.setFromTriplets(entries.begin(), entries.end());
  // Eigen's AMD returns P⁻¹ of the order P A Pᵀ: its i-th index is the old index of new particle i.
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> inverse;
  Eigen::AMDOrdering<int>()(pattern, inverse);
  for (int i = 0; i < n; ++i)
    old_of[i] = inverse.indices()[i];
  return old_of;
}

// The lower neighbours (k < i) of each particle in the new order, as CSR.
void lowerNeighbours(const std::vector<int>& row_start, const std::vector<int>& block_column,
                     const std::vector<int>& new_of, std::vector<int>& start, std::vector<int>& column)
{
  const int n = static_cast<int>(row_start.size()) - 1;
  start.assign(n + 1, 0);
  for (int r = 0; r < n; ++r)
    for (int k = row_start[r]; k < row_start[r + 1]; ++k)
      if (new_of[block_column[k]] < new_of[r]) ++start[new_of[r] + 1];
  for (int i = 0; i < n; ++i)
    start[i + 1] += start[i];
  column.assign(start[n], 0);
  std::vector<int> next(start.begin(), start.end() - 1);
  for (int r = 0; r < n; ++r)
    for (int k = row_start[r]; k < row_start[r + 1]; ++k)
      if (new_of[block_column[k]] < new_of[r]) column[next[new_of[r]]++] = new_of[block_column[k]];
}

// The elimination tree of the pattern (Liu 1986, with path compression): parent[i], −1 at a root.
std::vector<int> eliminationTree(const std::vector<int>& start, const std::vector<int>& column)
{
  const int n = static_cast<int>(start.size()) - 1;
  std::vector<int> parent(n, -1), ancestor(n, -1);
  for (int i = 0; i < n; ++i)
  {
    for (int e = start[i]; e < start[i + 1]; ++e)
    {
      int r = column[e];
      while (ancestor[r] != -1 && ancestor[r] != i)
      {
        const int next = ancestor[r];
        ancestor[r] = i;
        r = next;
      }
      if (ancestor[r] == -1)
      {
        ancestor[r] = i;
        parent[r] = i;
      }
    }
  }
  return parent;
}

// Visits every off-diagonal block (i, j), j < i, of L's pattern, row by row: row i's pattern is
// the union of the etree paths from its lower neighbours up to i (its row subtree).
template <class Visit>
void forEachFactorBlock(const std::vector<int>& start, const std::vector<int>& column, const std::vector<int>& parent,
                        Visit&& visit)
{
  const int n = static_cast<int>(start.size()) - 1;
  std::vector<int> mark(n, -1);
  for (int i = 0; i < n; ++i)
  {
    mark[i] = i;
    for (int e = start[i]; e < start[i + 1]; ++e)
    {
      for (int r = column[e]; mark[r] != i; r = parent[r])
      {
        visit(i, r);
        mark[r] = i;
      }
    }
  }
}

// The flops of one factorization and one solve for a column of L with `count` off-diagonal blocks:
// D_j⁻¹ (about 60), L_ij = W_i D_j⁻¹ (45 each), one 3x3 product per update (45 each, count (count +
// 1) / 2 updates); the solve passes each block twice (18 flops each) and applies D_j⁻¹ (15).
void addColumnFlops(int count, double& factor_flops, double& solve_flops)
{
  factor_flops += 60.0 + 45.0 * count + 45.0 * count * (count + 1.0) / 2.0;
  solve_flops += 2.0 * 18.0 * count + 15.0;
}

// A supernode at least this many block columns wide is wide; the supernodal form is taken when the
// wide ones hold at least half the factorization's flops.
constexpr int kWideSupernode = 4;
constexpr double kWideShare = 0.5;
// The columns of a panel factored together: those before them are applied to them as one dense
// product (dense_panel), those among them one by one. Few, so that most of the work is in the
// product's tiles (hang64's step 4 % faster than with 16).
constexpr int kPanelColumns = 4;
// The blocks of columns that the updates into a panel above the two threads' shares are cut into
// (planSubtrees()): enough for the two threads to even out their work by taking blocks from each
// other, few enough that a run's product is not cut into many narrow ones.
constexpr int kBlocksPerPanel = 8;
// A scalar pivot at most this fraction of its diagonal entry in A (or not finite) is singular.
constexpr double kSingularPivot = 1e-14;

// The dense products' form (SparseBlockLdlt::setTiles()): the widest the processor has, by default.
std::atomic<dense_panel::Tiles>& tilesSetting()
{
  static std::atomic<dense_panel::Tiles> tiles(dense_panel::widestTiles());
  return tiles;
}

// The supernodes of L, as (first column, width), from its elimination tree and the counts of its
// columns' off-diagonal blocks: column j + 1 joins column j's when it is j's parent and its rows
// are j's but j + 1 (then the two columns have one pattern below them). supernode_of[j] is column
// j's; `wide` whether the supernodal form is worth it (kWideShare of the flops in wide ones).
std::vector<std::array<int, 2>> findSupernodes(const std::vector<int>& parent, const std::vector<int>& counts,
                                               std::vector<int>& supernode_of, bool& wide)
{
  const int n = static_cast<int>(counts.size());
  supernode_of.assign(n, 0);
  std::vector<std::array<int, 2>> found;
  double all_flops = 0.0, wide_flops = 0.0, unused = 0.0;
  for (int j = 0; j < n;)
  {
    const int first = j;
    double flops = 0.0;
    for (;; ++j)
    {
      addColumnFlops(counts[j], flops, unused);
      supernode_of[j] = static_cast<int>(found.size());
      if (j + 1 == n || parent[j] != j + 1 || counts[j + 1] != counts[j] - 1) break;
    }
    ++j;
    found.push_back({first, j - first});
    all_flops += flops;
    if (j - first >= kWideSupernode) wide_flops += flops;
  }
  wide = all_flops > 0.0 && wide_flops >= kWideShare * all_flops;
  return found;
}
}  // namespace

bool SparseBlockLdlt::useAvx2()
{
  return tiles() != dense_panel::Tiles::Scalar;
}

void SparseBlockLdlt::setUseAvx2(bool use)
{
  setTiles(use ? dense_panel::widestTiles() : dense_panel::Tiles::Scalar);
}

dense_panel::Tiles SparseBlockLdlt::tiles()
{
  return tilesSetting().load(std::memory_order_relaxed);
}

void SparseBlockLdlt::setTiles(dense_panel::Tiles form)
{
  tilesSetting().store(std::min(form, dense_panel::widestTiles()), std::memory_order_relaxed);
}

SparseBlockLdlt::Cost SparseBlockLdlt::estimateCost(const std::vector<int>& row_start,
                                                    const std::vector<int>& block_column)
{
  const std::vector<int> old_of = fillReducingOrder(row_start, block_column);
  std::vector<int> new_of(old_of.size());
  for (std::size_t i = 0; i < old_of.size(); ++i)
    new_of[old_of[i]] = static_cast<int>(i);
  std::vector<int> start, column;
  lowerNeighbours(row_start, block_column, new_of, start, column);
  std::vector<int> counts(old_of.size(), 0);
  const std::vector<int> parent = eliminationTree(start, column);
  forEachFactorBlock(start, column, parent, [&counts](int, int j) { ++counts[j]; });
  Cost cost;
  for (int count : counts)
  {
    cost.factor_blocks += count;
    addColumnFlops(count, cost.factor_flops, cost.solve_flops);
  }
  std::vector<int> supernode_of;
  findSupernodes(parent, counts, supernode_of, cost.supernodal);
  return cost;
}

void SparseBlockLdlt::analyze(const std::vector<int>& row_start, const std::vector<int>& block_column)
{
  const int n = static_cast<int>(row_start.size()) - 1;
  old_of_ = fillReducingOrder(row_start, block_column);
  new_of_.assign(n, 0);
  for (int i = 0; i < n; ++i)
    new_of_[old_of_[i]] = i;

  // Pattern of L by columns: count, then fill (rows arrive in increasing order).
  std::vector<int> start, column;
  lowerNeighbours(row_start, block_column, new_of_, start, column);
  const std::vector<int> parent = eliminationTree(start, column);
  column_start_.assign(n + 1, 0);
  forEachFactorBlock(start, column, parent, [this](int, int j) { ++column_start_[j + 1]; });
  for (int j = 0; j < n; ++j)
    column_start_[j + 1] += column_start_[j];
  row_index_.assign(column_start_[n], 0);
  std::vector<int> next(column_start_.begin(), column_start_.end() - 1);
  forEachFactorBlock(start, column, parent, [this, &next](int i, int j) { row_index_[next[j]++] = i; });
  lower_.assign(row_index_.size(), Eigen::Matrix3d::Zero());
  pivot_.assign(n, Eigen::Matrix3d::Identity());
  pivot_inverse_.assign(n, Eigen::Matrix3d::Identity());
  pinned_new_.assign(n, 0);
  work_.setZero(3, n);

  // The slot of block (i, k), i > k, in column k of L.
  auto slot = [this](int i, int k) {
    const auto first = row_index_.begin() + column_start_[k], last = row_index_.begin() + column_start_[k + 1];
    return static_cast<int>(std::lower_bound(first, last, i) - row_index_.begin());
  };

  // Where A's blocks go.
  block_slot_.assign(block_column.size(), kUnused);
  block_row_new_.assign(block_column.size(), 0);
  block_column_new_.assign(block_column.size(), 0);
  for (int r = 0; r < n; ++r)
  {
    for (int b = row_start[r]; b < row_start[r + 1]; ++b)
    {
      const int i = new_of_[r], k = new_of_[block_column[b]];
      block_row_new_[b] = i;
      block_column_new_[b] = k;
      if (i == k)
        block_slot_[b] = -1 - i;
      else if (i > k)
        block_slot_[b] = slot(i, k);
    }
  }

  // The flop counts, and the supernodes.
  factor_flops_ = solve_flops_ = 0.0;
  std::vector<int> counts(n);
  for (int j = 0; j < n; ++j)
  {
    counts[j] = column_start_[j + 1] - column_start_[j];
    addColumnFlops(counts[j], factor_flops_, solve_flops_);
  }
  std::vector<int> supernode_of;
  bool wide = false;
  const std::vector<std::array<int, 2>> found = findSupernodes(parent, counts, supernode_of, wide);

  supernodes_.clear();
  update_slot_.clear();
  forgetSubtrees();
  if (wide)
  {
    for (const auto& [first, width] : found)
    {
      Supernode supernode;
      supernode.first = first;
      supernode.width = width;
      supernodes_.push_back(supernode);
    }
    analyzeSupernodes(row_start, block_column, supernode_of);
    return;
  }

  // The elimination's updates of the 3x3 blocks, in the order factorize() makes them.
  for (int j = 0; j < n; ++j)
  {
    const int first = column_start_[j], count = column_start_[j + 1] - first;
    for (int a = 0; a < count; ++a)
    {
      for (int b = 0; b <= a; ++b)
      {
        const int i = row_index_[first + a], k = row_index_[first + b];
        update_slot_.push_back(i == k ? -1 - i : slot(i, k));
      }
    }
  }
}

void SparseBlockLdlt::analyzeSupernodes(const std::vector<int>& row_start, const std::vector<int>& block_column,
                                        const std::vector<int>& supernode_of)
{
  const int n = static_cast<int>(new_of_.size());
  lower_.clear();
  lower_.shrink_to_fit();
  // Each supernode's rows below it (those of its last column) and its panel.
  super_rows_.clear();
  std::size_t panel = 0, largest_panel = 0, largest_rows = 0;
  for (Supernode& supernode : supernodes_)
  {
    const int last = supernode.first + supernode.width - 1;
    supernode.rows = static_cast<int>(super_rows_.size());
    supernode.below = column_start_[last + 1] - column_start_[last];
    super_rows_.insert(super_rows_.end(), row_index_.begin() + column_start_[last],
                       row_index_.begin() + column_start_[last + 1]);
    supernode.panel = panel;
    const std::size_t m = 3 * static_cast<std::size_t>(supernode.width + supernode.below);
    const std::size_t size = m * 3 * static_cast<std::size_t>(supernode.width);
    panel += size;
    largest_panel = std::max(largest_panel, size);
    largest_rows = std::max(largest_rows, m);
  }
  panels_.assign(panel, 0.0);
  scaled_.assign(largest_panel, 0.0);
  gathered_.assign(largest_rows, 0.0);  // a panel's rows below, then its columns' dots (backwardSupernode())
  ascending_.resize(largest_rows);
  for (std::size_t r = 0; r < largest_rows; ++r)
    ascending_[r] = static_cast<int>(r);
  scalar_pivot_.assign(3 * static_cast<std::size_t>(n), 1.0);

  // The block row of block row `row` in supernode t's panel (its own columns first, then below).
  auto localRow = [this](int t, int row) {
    const Supernode& target = supernodes_[t];
    if (row < target.first + target.width) return row - target.first;
    const auto first = super_rows_.begin() + target.rows, last = first + target.below;
    return target.width + static_cast<int>(std::lower_bound(first, last, row) - first);
  };

  // Where A's blocks go: the panel of their column's supernode.
  block_place_.assign(block_column.size(), {-1, 0});
  for (int r = 0; r < n; ++r)
  {
    for (int b = row_start[r]; b < row_start[r + 1]; ++b)
    {
      const int i = new_of_[r], k = new_of_[block_column[b]];
      if (i < k) continue;
      const int t = supernode_of[k];
      const Supernode& target = supernodes_[t];
      const long m = 3L * (target.width + target.below);
      block_place_[b] = {static_cast<long>(target.panel) + 3L * (k - target.first) * m + 3L * localRow(t, i), m};
    }
  }

  // Each supernode's runs of rows below it by the supernode that holds them as columns, and where
  // each of the update's rows and columns lies in that supernode's panel.
  runs_.clear();
  update_row_offset_.clear();
  update_column_offset_.clear();
  run_start_.assign(supernodes_.size() + 1, 0);
  for (std::size_t s = 0; s < supernodes_.size(); ++s)
  {
    run_start_[s] = static_cast<int>(runs_.size());
    const Supernode& supernode = supernodes_[s];
    for (int a = 0; a < supernode.below;)
    {
      UpdateRun run;
      run.target = supernode_of[super_rows_[supernode.rows + a]];
      run.begin = a;
      while (a < supernode.below && supernode_of[super_rows_[supernode.rows + a]] == run.target)
        ++a;
      run.end = a;
      const Supernode& target = supernodes_[run.target];
      const long target_m = 3L * (target.width + target.below);
      run.rows = update_row_offset_.size();
      for (int row = run.begin; row < supernode.below; ++row)
      {
        const int local_row = 3 * localRow(run.target, super_rows_[supernode.rows + row]);
        for (int r = 0; r < 3; ++r)
          update_row_offset_.push_back(local_row + r);
      }
      run.columns = update_column_offset_.size();
      for (int column = run.begin; column < run.end; ++column)
      {
        const long local_column = 3L * (super_rows_[supernode.rows + column] - target.first);
        for (int cc = 0; cc < 3; ++cc)
          update_column_offset_.push_back(static_cast<long>(target.panel) + (local_column + cc) * target_m);
      }
      runs_.push_back(run);
    }
  }
  run_start_[supernodes_.size()] = static_cast<int>(runs_.size());
  planSubtrees(supernode_of);
}

void SparseBlockLdlt::forgetSubtrees()
{
  share_of_.clear();
  shared_order_[0].clear();
  shared_order_[1].clear();
  kept_scaled_at_.clear();
  block_start_.clear();
  piece_start_.clear();
  pieces_.clear();
  first_row_above_.clear();
  kept_sums_at_.clear();
  kept_scaled_.clear();
  second_scaled_.clear();
  kept_sums_.clear();
  second_gathered_.clear();
  shared_share_ = 0.0;
  last_above_ = -1;
}

void SparseBlockLdlt::planSubtrees(const std::vector<int>& supernode_of)
{
  const int count = static_cast<int>(supernodes_.size());
  forgetSubtrees();
  share_of_.assign(count, kAboveShares);
  kept_scaled_at_.assign(count, kNotKept);
  // The tree of supernodes: each one's parent is the supernode of its first row below (−1 at a
  // root), and comes after it. Its work: its panel's flops and its update's, as dense counts; its
  // subtree's, summed up the tree.
  std::vector<int> parent(count, -1), child_start(count + 1, 0);
  std::vector<double> work(count), subtree(count);
  for (int s = 0; s < count; ++s)
  {
    const Supernode& supernode = supernodes_[s];
    const double w = 3.0 * supernode.width, b = 3.0 * supernode.below;
    if (supernode.below > 0)
    {
      parent[s] = supernode_of[super_rows_[supernode.rows]];
      ++child_start[parent[s] + 1];
    }
    work[s] = w * w * w / 3.0 + b * w * w + b * b * w;
    subtree[s] = work[s];
  }
  std::vector<int> roots;
  double total = 0.0;
  for (int s = 0; s < count; ++s)
  {
    child_start[s + 1] += child_start[s];
    if (parent[s] >= 0)
    {
      subtree[parent[s]] += subtree[s];
    }
    else
    {
      roots.push_back(s);
      total += subtree[s];
    }
  }
  std::vector<int> children(child_start[count]);
  std::vector<int> next_child(child_start.begin(), child_start.end() - 1);
  for (int s = 0; s < count; ++s)
    if (parent[s] >= 0) children[next_child[parent[s]]++] = s;

  // Two threads' time for a frontier of whole subtrees under the supernodes above it: the larger of
  // two bins filled heaviest subtree first, each into the lighter bin, plus the work above.
  auto heaviestFirst = [&](std::vector<int> frontier) {
    std::sort(frontier.begin(), frontier.end(),
              [&](int a, int b) { return subtree[a] > subtree[b] || (subtree[a] == subtree[b] && a < b); });
    return frontier;
  };
  auto twoThreadTime = [&](const std::vector<int>& frontier, double above) {
    double bins[2] = {0.0, 0.0};
    for (const int r : heaviestFirst(frontier))
      bins[bins[1] < bins[0] ? 1 : 0] += subtree[r];
    return std::max(bins[0], bins[1]) + above;
  };
  // From the roots down: the heaviest subtree of the frontier is split (its root goes above, its
  // children join the frontier) a few times, and the frontier with the least time is kept.
  constexpr int kSplits = 64;
  std::vector<int> frontier = roots, best_frontier = roots;
  double above = 0.0, best_time = twoThreadTime(frontier, above);
  for (int split = 0; split < kSplits && !frontier.empty(); ++split)
  {
    const auto heaviest =
        std::max_element(frontier.begin(), frontier.end(), [&](int a, int b) { return subtree[a] < subtree[b]; });
    const int h = *heaviest;
    if (child_start[h] == child_start[h + 1]) break;
    frontier.erase(heaviest);
    frontier.insert(frontier.end(), children.begin() + child_start[h], children.begin() + child_start[h + 1]);
    above += work[h];
    const double time = twoThreadTime(frontier, above);
    if (time < best_time)
    {
      best_time = time;
      best_frontier = frontier;
    }
  }
  // Not worth a second thread below a tenth less time (a chain, a small sheet).
  if (!(best_time < 0.9 * total)) return;

  // Each subtree of the frontier into the lighter share, heaviest first, all its supernodes with it.
  double shares[2] = {0.0, 0.0};
  std::vector<int> stack;
  for (const int r : heaviestFirst(best_frontier))
  {
    const int share = shares[1] < shares[0] ? 1 : 0;
    shares[share] += subtree[r];
    stack.assign(1, r);
    while (!stack.empty())
    {
      const int s = stack.back();
      stack.pop_back();
      share_of_[s] = static_cast<signed char>(share);
      stack.insert(stack.end(), children.begin() + child_start[s], children.begin() + child_start[s + 1]);
    }
  }
  shared_share_ = (shares[0] + shares[1]) / total;
  // Each share's supernodes in order; those with runs into the supernodes above keep their T.
  std::size_t kept = 0;
  for (int s = 0; s < count; ++s)
  {
    if (share_of_[s] < 0) continue;
    shared_order_[share_of_[s]].push_back(s);
    for (int q = run_start_[s]; q < run_start_[s + 1]; ++q)
    {
      if (share_of_[runs_[q].target] >= 0) continue;
      const Supernode& supernode = supernodes_[s];
      kept_scaled_at_[s] = kept;
      kept += 9 * static_cast<std::size_t>(supernode.width + supernode.below) * supernode.width;
      break;
    }
  }
  kept_scaled_.assign(kept, 0.0);
  second_scaled_.assign(scaled_.size(), 0.0);
  // The solve's: each shared supernode's first row below that lies above the shares (its rows are
  // ascending: those of its own share, which are its ancestors there, come first), and room for the
  // sums of those rows.
  first_row_above_.assign(count, 0);
  kept_sums_at_.assign(count, kNotKept);
  std::size_t sums = 0;
  for (int s = 0; s < count; ++s)
  {
    if (share_of_[s] < 0) continue;
    const Supernode& supernode = supernodes_[s];
    int a = 0;
    while (a < supernode.below && share_of_[supernode_of[super_rows_[supernode.rows + a]]] >= 0)
      ++a;
    first_row_above_[s] = a;
    if (a == supernode.below) continue;
    kept_sums_at_[s] = sums;
    sums += 3 * static_cast<std::size_t>(supernode.below - a);
  }
  kept_sums_.assign(sums, 0.0);
  second_gathered_.assign(gathered_.size(), 0.0);
  // Each supernode above the shares: its columns in kBlocksPerPanel blocks of about equal entries on
  // and below the diagonal (column c of m rows has m − c of them), and each block's pieces, source
  // after source: the part of every update run into the supernode that lands in the block's columns
  // (a run's columns land in ascending columns of its target).
  std::vector<std::vector<std::array<int, 2>>> runs_into(count);  // (source, run), source after source
  for (int source = 0; source < count; ++source)
    for (int q = run_start_[source]; q < run_start_[source + 1]; ++q)
      if (share_of_[runs_[q].target] < 0) runs_into[runs_[q].target].push_back({source, q});
  block_start_.assign(count + 1, 0);
  piece_start_.assign(1, 0);
  for (int t = 0; t < count; ++t)
  {
    block_start_[t] = static_cast<int>(piece_start_.size()) - 1;
    if (share_of_[t] >= 0) continue;
    last_above_ = t;
    const Supernode& target = supernodes_[t];
    const long m = 3L * (target.width + target.below), width = 3L * target.width;
    const long entries = width * m - width * (width - 1) / 2;
    const long parts = std::min<long>(kBlocksPerPanel, width);
    long before = 0, first = 0;
    for (long part = 1; part <= parts; ++part)
    {
      long last = first;
      for (; last < width && (part == parts || (before + m - last) * parts <= part * entries); ++last)
        before += m - last;
      for (const auto& [source, q] : runs_into[t])
      {
        const UpdateRun& run = runs_[q];
        const long* const landing = update_column_offset_.data() + run.columns;
        const int columns = 3 * (run.end - run.begin);
        auto columnOf = [&](long offset) { return (offset - static_cast<long>(target.panel)) / m; };
        const int from = static_cast<int>(
            std::partition_point(landing, landing + columns, [&](long o) { return columnOf(o) < first; }) - landing);
        const int to = static_cast<int>(
            std::partition_point(landing, landing + columns, [&](long o) { return columnOf(o) < last; }) - landing);
        if (from < to) pieces_.push_back({source, q, from, to});
      }
      piece_start_.push_back(static_cast<int>(pieces_.size()));
      first = last;
    }
  }
  block_start_[count] = static_cast<int>(piece_start_.size()) - 1;
}

bool SparseBlockLdlt::factorizeAndSolve(const std::vector<Eigen::Matrix3d>& blocks, const std::vector<char>& pinned,
                                        const Eigen::Matrix3Xd& b, Eigen::Matrix3Xd& x)
{
  if (!supernodal() || !twoThreads())
  {
    if (!factorize(blocks, pinned)) return false;
    solve(b, x);
    return true;
  }
  pinnedInNewOrder(pinned);
  scatterBlocks(blocks);
  return factorizeAndSolveScattered(b, x);
}

bool SparseBlockLdlt::factorizeAndSolve(const PairedMatrix& matrix, const std::vector<char>& pinned,
                                        const Eigen::Matrix3Xd& b, Eigen::Matrix3Xd& x)
{
  if (!supernodal()) return false;
  pinnedInNewOrder(pinned);
  scatterPairs(matrix);
  return factorizeAndSolveScattered(b, x);
}

bool SparseBlockLdlt::factorizeAndSolveScattered(const Eigen::Matrix3Xd& b, Eigen::Matrix3Xd& x)
{
  // b in the new order first, so that with two threads the shares' forward passes can run beside
  // the factorization of the last panel above them.
  toNewOrder(b);
  const bool forward_beside = twoThreads();
  if (!factorizeSupernodes(forward_beside)) return false;
  solveSupernodes(forward_beside);
  fromNewOrder(x);
  return true;
}

bool SparseBlockLdlt::factorize(const std::vector<Eigen::Matrix3d>& blocks, const std::vector<char>& pinned)
{
  const int n = static_cast<int>(pivot_.size());
  pinnedInNewOrder(pinned);
  if (supernodal())
  {
    scatterBlocks(blocks);
    return factorizeSupernodes(false);
  }
  for (int i = 0; i < n; ++i)
  {
    if (pinned_new_[i])
      pivot_[i].setIdentity();
    else
      pivot_[i].setZero();
  }
  for (Eigen::Matrix3d& l : lower_)
    l.setZero();

  // Scatter A's lower triangle; a pinned particle's row and column stay 0 (its pivot is I).
  for (std::size_t b = 0; b < blocks.size(); ++b)
  {
    const int s = block_slot_[b];
    if (s == kUnused || pinned_new_[block_row_new_[b]] || pinned_new_[block_column_new_[b]]) continue;
    if (s < 0)
      pivot_[-1 - s] = blocks[b];
    else
      lower_[s] = blocks[b];
  }

  // Right-looking block LDLᵀ: for each column j, D_j is final; W_i = A_ij (updated) becomes
  // L_ij = W_i D_j⁻¹, and every later block (i, k) of the column pair gets A_ik −= W_i L_kjᵀ.
  const int* update = update_slot_.data();
  for (int j = 0; j < n; ++j)
  {
    const Eigen::Matrix3d& d = pivot_[j];
    if (!d.allFinite()) return false;
    bool invertible = false;
    double determinant = 0.0;
    d.computeInverseAndDetWithCheck(pivot_inverse_[j], determinant, invertible, 1e-300);
    if (!invertible || !std::isfinite(determinant) ||
        std::abs(determinant) <= 1e-14 * std::pow(d.cwiseAbs().maxCoeff(), 3))
      return false;
    const int first = column_start_[j], count = column_start_[j + 1] - first;
    // W_i kept in work_ columns, in the column's order (they are overwritten by L_ij below).
    for (int a = 0; a < count; ++a)
    {
      const Eigen::Matrix3d w = lower_[first + a];
      // L_ij = W_i D_j⁻¹ (inline: GCC called Eigen's product out of line here, a fifth of the time).
      multiplyInline(w, pivot_inverse_[j], lower_[first + a]);
      for (int b = 0; b <= a; ++b)
      {
        const int s = *update++;
        // Block (i, k), i = row a, k = row b: A_ik −= W_i L_kjᵀ, with W_i the old lower_[first + a]
        // and L_kj the new lower_[first + b] (b < a is done; b == a is the line above).
        if (s < 0)
          pivot_[-1 - s].noalias() -= w * lower_[first + b].transpose();
        else
          lower_[s].noalias() -= w * lower_[first + b].transpose();
      }
    }
  }
  return true;
}

void SparseBlockLdlt::solve(const Eigen::Matrix3Xd& b, Eigen::Matrix3Xd& x)
{
  const int n = static_cast<int>(pivot_.size());
  toNewOrder(b);
  if (supernodal())
  {
    solveSupernodes();
    fromNewOrder(x);
    return;
  }
  // L y = b (forward), then z = D⁻¹ y, then Lᵀ x = z (backward).
  for (int j = 0; j < n; ++j)
  {
    const Eigen::Vector3d yj = work_.col(j);
    for (int e = column_start_[j]; e < column_start_[j + 1]; ++e)
      work_.col(row_index_[e]).noalias() -= lower_[e] * yj;
  }
  for (int j = 0; j < n; ++j)
    work_.col(j) = pivot_inverse_[j] * work_.col(j).eval();
  for (int j = n - 1; j >= 0; --j)
  {
    Eigen::Vector3d xj = work_.col(j);
    for (int e = column_start_[j]; e < column_start_[j + 1]; ++e)
      xj.noalias() -= lower_[e].transpose() * work_.col(row_index_[e]);
    work_.col(j) = xj;
  }
  fromNewOrder(x);
}

void SparseBlockLdlt::toNewOrder(const Eigen::Matrix3Xd& b)
{
  for (int i = 0; i < static_cast<int>(old_of_.size()); ++i)
    work_.col(i) = b.col(old_of_[i]);
}

void SparseBlockLdlt::fromNewOrder(Eigen::Matrix3Xd& x) const
{
  for (int i = 0; i < static_cast<int>(old_of_.size()); ++i)
    x.col(old_of_[i]) = work_.col(i);
}

void SparseBlockLdlt::pinnedInNewOrder(const std::vector<char>& pinned)
{
  for (int i = 0; i < static_cast<int>(old_of_.size()); ++i)
    pinned_new_[i] = pinned[old_of_[i]];
}

void SparseBlockLdlt::zeroPanels()
{
  if (twoThreads())
    byHalves(*workers_, panels_.size(), [&](std::size_t first, std::size_t last) {
      std::fill(panels_.begin() + first, panels_.begin() + last, 0.0);
    });
  else
    std::fill(panels_.begin(), panels_.end(), 0.0);
}

void SparseBlockLdlt::scatterBlocks(const std::vector<Eigen::Matrix3d>& blocks)
{
  // Each block writes its own entries: with two threads, the blocks by halves.
  zeroPanels();
  auto scatter = [&](std::size_t first, std::size_t last) {
    for (std::size_t b = first; b < last; ++b)
    {
      if (block_place_[b][0] >= 0) putBlock(block_place_[b], block_row_new_[b], block_column_new_[b], blocks[b]);
    }
  };
  if (twoThreads())
    byHalves(*workers_, blocks.size(), scatter);
  else
    scatter(0, blocks.size());
}

void SparseBlockLdlt::putBlock(const std::array<long, 2>& place, int i, int k, const Eigen::Matrix3d& value)
{
  const auto [offset, ld] = place;
  double* const corner = panels_.data() + offset;
  if (pinned_new_[i] || pinned_new_[k])
  {
    if (i == k)
      for (int r = 0; r < 3; ++r)
      {
        corner[r + r * ld] = 1.0;
        scalar_pivot_[3 * i + r] = 1.0;
      }
    return;
  }
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r)
      corner[r + c * ld] = value(r, c);
  if (i == k)
    for (int r = 0; r < 3; ++r)
      scalar_pivot_[3 * i + r] = std::abs(value(r, r));
}

void SparseBlockLdlt::scatterPairs(const PairedMatrix& matrix)
{
  // The diagonal blocks, particle by particle; then each pair's C added onto the one of its two
  // blocks that lies in the lower triangle, pair after pair: each entry gets its terms in the order
  // its block would have had them, onto zero. With two threads, each takes half of the particles
  // and passes every pair, adding only to the blocks in its half of A's blocks.
  zeroPanels();
  const std::size_t rows = old_of_.size(), blocks = block_place_.size();
  auto diagonal = [&](std::size_t first, std::size_t last) {
    for (std::size_t old = first; old < last; ++old)
      putBlock(block_place_[matrix.diagonal_block[old]], new_of_[old], new_of_[old], matrix.diagonal[old]);
  };
  auto pairs = [&](std::size_t first_block, std::size_t last_block) {
    for (int k = 0; k < matrix.pairs; ++k)
    {
      const std::size_t lower = static_cast<std::size_t>(
          block_place_[matrix.blocks[k][0]][0] >= 0 ? matrix.blocks[k][0] : matrix.blocks[k][1]);
      if (lower < first_block || lower >= last_block) continue;
      const int i = block_row_new_[lower], j = block_column_new_[lower];
      if (i == j || pinned_new_[i] || pinned_new_[j]) continue;
      const auto [offset, ld] = block_place_[lower];
      double* const corner = panels_.data() + offset;
      const std::array<double, 6>& c = matrix.c[k];
      const double entry[3][3] = {{c[0], c[1], c[2]}, {c[1], c[3], c[4]}, {c[2], c[4], c[5]}};
      for (int column = 0; column < 3; ++column)
        for (int r = 0; r < 3; ++r)
          corner[r + column * ld] += entry[r][column];
    }
  };
  if (twoThreads())
  {
    workers_->forEachChunk(2, 1, [&](int half, int) {
      diagonal(half == 0 ? 0 : rows / 2, half == 0 ? rows / 2 : rows);
      pairs(half == 0 ? 0 : blocks / 2, half == 0 ? blocks / 2 : blocks);
    });
    return;
  }
  diagonal(0, rows);
  pairs(0, blocks);
}

bool SparseBlockLdlt::factorizeSupernodes(bool forward_beside)
{
  const bool two_threads = twoThreads();
  const dense_panel::Tiles tiles = SparseBlockLdlt::tiles();
  const std::size_t count = supernodes_.size();
  if (two_threads)
  {
    // The two shares at once, one a thread, each supernode's runs into the supernodes above the
    // shares held back.
    bool factored[2] = {true, true};
    workers_->forEachChunk(2, 1, [&](int share, int) {
      double* const scratch = share == 0 ? scaled_.data() : second_scaled_.data();
      for (const int s : shared_order_[share])
      {
        double* const scaled = kept_scaled_at_[s] == kNotKept ? scratch : kept_scaled_.data() + kept_scaled_at_[s];
        if (!factorSupernode(s, scaled, true, tiles))
        {
          factored[share] = false;
          return;
        }
      }
    });
    if (!factored[0] || !factored[1]) return false;
    // Then, in order, the supernodes above the shares, each after the held-back runs into it; the
    // updates into the panels above by blocks of their columns (subtractBlocks()).
    for (std::size_t s = 0; s < count;)
    {
      std::size_t end = s;
      bool held_back = false;
      for (; end < count && share_of_[end] >= 0; ++end)
        held_back = held_back || kept_scaled_at_[end] != kNotKept;
      if (end == count) break;  // (held back: none, as every supernode above comes later)
      const int source_end = static_cast<int>(end);
      const int later_blocks = block_start_[end + 1], all_blocks = block_start_[count];
      if (held_back) subtractBlocks(block_start_[end], later_blocks, static_cast<int>(s), source_end, nullptr, tiles);
      // `end`'s panel on one thread; beside it, the held-back runs into the supernodes after it, or
      // beside the last one the shares' forward passes (solve()), which read their own panels alone.
      const bool forward_here = forward_beside && source_end == last_above_;
      const int beside = forward_here ? 1 : (held_back ? all_blocks - later_blocks : 0);
      bool factored = true;
      workers_->forEachChunk(1 + beside, 1, [&](int first, int last) {
        for (int item = first; item < last; ++item)
        {
          if (item == 0)
            factored = factorPanel(end, scaled_.data(), tiles);
          else if (forward_here)
            forwardShares(false);
          else
            subtractBlock(later_blocks + item - 1, static_cast<int>(s), source_end, nullptr, tiles);
        }
      });
      if (!factored) return false;
      subtractBlocks(later_blocks, all_blocks, source_end, source_end + 1, scaled_.data(), tiles);
      s = end + 1;
    }
    return true;
  }
  for (std::size_t s = 0; s < count; ++s)
    if (!factorSupernode(s, scaled_.data(), false, tiles)) return false;
  return true;
}

void SparseBlockLdlt::subtractBlocks(int first, int last, int first_source, int last_source, const double* scaled,
                                     dense_panel::Tiles tiles)
{
  workers_->forEachChunk(last - first, 1, [&](int begin, int end) {
    for (int b = first + begin; b < first + end; ++b)
      subtractBlock(b, first_source, last_source, scaled, tiles);
  });
}

void SparseBlockLdlt::subtractBlock(int b, int first_source, int last_source, const double* scaled,
                                    dense_panel::Tiles tiles)
{
  for (int k = piece_start_[b]; k < piece_start_[b + 1]; ++k)
  {
    const BlockPiece& piece = pieces_[k];
    if (piece.source < first_source) continue;
    if (piece.source >= last_source) break;
    const double* const source_scaled =
        share_of_[piece.source] >= 0 ? kept_scaled_.data() + kept_scaled_at_[piece.source] : scaled;
    subtractRun(piece.source, source_scaled, piece.run, piece.from, piece.to, tiles);
  }
}

bool SparseBlockLdlt::twoThreads() const
{
  return workers_ && workers_->threads() > 1 && !shared_order_[0].empty() && !shared_order_[1].empty();
}

bool SparseBlockLdlt::factorSupernode(std::size_t s, double* scaled, bool shared_only, dense_panel::Tiles tiles)
{
  if (!factorPanel(s, scaled, tiles)) return false;
  subtractRuns(s, scaled, shared_only ? share_of_[s] : kEveryShare, tiles);
  return true;
}

bool SparseBlockLdlt::factorPanel(std::size_t s, double* scaled, dense_panel::Tiles tiles)
{
  const bool avx2 = tiles != dense_panel::Tiles::Scalar;
  const Supernode& supernode = supernodes_[s];
  const int width = 3 * supernode.width, below = 3 * supernode.below, m = width + below;
  double* const panel = panels_.data() + supernode.panel;
  double* const pivots = scalar_pivot_.data() + 3 * supernode.first;
  // Left-looking by groups of columns: the columns before a group, as one dense product, then the
  // group's own columns one by one; each column's pivot, T's column (the column before it is
  // divided by its pivot) and L's.
  for (int c0 = 0; c0 < width; c0 += kPanelColumns)
  {
    const int c1 = std::min(width, c0 + kPanelColumns);
    if (c0 > 0)
    {
      long group_columns[kPanelColumns];  // the group's columns in the panel, from its diagonal
      for (int c = c0; c < c1; ++c)
        group_columns[c - c0] = static_cast<long>(c - c0) * m;
      dense_panel::subtractLowerProducts(tiles, m - c0, c1 - c0, c0, scaled + c0, m, panel + c0, m, ascending_.data(),
                                         group_columns, panel + c0 + static_cast<long>(c0) * m);
    }
    for (int c = c0; c < c1; ++c)
    {
      // The group's columns before c subtracted from column c: its pivot first, then the rows below
      // the pivot in one pass that also keeps T's column and scales L's (each entry's terms in the
      // order of the columns, each a multiply and a subtraction: the bits of a pass a column).
      double* const column = panel + static_cast<long>(c) * m;
      double factors[kPanelColumns];
      double pivot = column[c];
      for (int p = c0; p < c; ++p)
      {
        factors[p - c0] = panel[c + static_cast<long>(p) * m];
        pivot -= scaled[c + static_cast<long>(p) * m] * factors[p - c0];
      }
      column[c] = pivot;
      if (!std::isfinite(pivot) || !(std::abs(pivot) > kSingularPivot * pivots[c])) return false;
      pivots[c] = pivot;
      dense_panel::subtractScaledColumnsKeepAndScale(
          avx2, m - c - 1, c - c0, scaled + static_cast<long>(c0) * m + c + 1, m, factors, 1.0 / pivot, column + c + 1,
          scaled + static_cast<long>(c) * m + c + 1);
    }
  }
  return true;
}

void SparseBlockLdlt::subtractRuns(std::size_t s, const double* scaled, int share, dense_panel::Tiles tiles)
{
  for (int q = run_start_[s]; q < run_start_[s + 1]; ++q)
  {
    const UpdateRun& run = runs_[q];
    if (share != kEveryShare && share_of_[run.target] != share) continue;
    subtractRun(s, scaled, q, 0, 3 * (run.end - run.begin), tiles);
  }
}

void SparseBlockLdlt::subtractRun(std::size_t s, const double* scaled, int q, int from, int to,
                                  dense_panel::Tiles tiles)
{
  // The update of the run's rows, −L_R D L_Rᵀ, subtracted where it belongs in the panel that holds
  // them; its columns [from, to) alone, each from its diagonal down.
  const Supernode& supernode = supernodes_[s];
  const int width = 3 * supernode.width, below = 3 * supernode.below, m = width + below;
  const double* const panel = panels_.data() + supernode.panel;
  const UpdateRun& run = runs_[q];
  const int first_row = 3 * run.begin, rows = below - first_row;
  dense_panel::subtractLowerProducts(tiles, rows - from, to - from, width, scaled + width + first_row + from, m,
                                     panel + width + first_row + from, m, update_row_offset_.data() + run.rows + from,
                                     update_column_offset_.data() + run.columns + from, panels_.data());
}

void SparseBlockLdlt::solveSupernodes(bool shares_forwarded)
{
  // L y = b by supernodes (each panel's own triangle, then its rows below gathered as one sum a
  // row), y = D⁻¹ y, then Lᵀ x = y backwards; on work_'s numbers in the new order. With two threads
  // planned (planSubtrees()): forwards, the two shares at once, each supernode's sums for the rows
  // above the shares kept and added after both, in order, with the supernodes above; backwards,
  // the supernodes above first, then the two shares at once. Every number of y gets its terms in the
  // order of one thread.
  double* const y = work_.data();
  const bool avx2 = useAvx2();
  const std::size_t count = supernodes_.size();
  if (!twoThreads())
  {
    for (std::size_t s = 0; s < count; ++s)
      forwardSupernode(s, y, gathered_.data(), avx2, nullptr);
    for (std::size_t q = 0; q < scalar_pivot_.size(); ++q)
      y[q] /= scalar_pivot_[q];
    for (std::size_t s = count; s-- > 0;)
      backwardSupernode(s, y, gathered_.data(), avx2);
    return;
  }
  if (!shares_forwarded) forwardShares(true);
  for (std::size_t s = 0; s < count; ++s)
  {
    if (share_of_[s] < 0)
    {
      forwardSupernode(s, y, gathered_.data(), avx2, nullptr);
    }
    else if (kept_sums_at_[s] != kNotKept)
    {
      const Supernode& supernode = supernodes_[s];
      const int* const rows = super_rows_.data() + supernode.rows;
      const double* const kept = kept_sums_.data() + kept_sums_at_[s];
      for (int a = first_row_above_[s]; a < supernode.below; ++a)
        for (int r = 0; r < 3; ++r)
          y[3L * rows[a] + r] += kept[3 * (a - first_row_above_[s]) + r];
    }
  }
  byHalves(*workers_, scalar_pivot_.size(), [&](std::size_t first, std::size_t last) {
    for (std::size_t q = first; q < last; ++q)
      y[q] /= scalar_pivot_[q];
  });
  for (std::size_t s = count; s-- > 0;)
    if (share_of_[s] < 0) backwardSupernode(s, y, gathered_.data(), avx2);
  workers_->forEachChunk(2, 1, [&](int share, int) {
    double* const gathered = share == 0 ? gathered_.data() : second_gathered_.data();
    for (auto s = shared_order_[share].rbegin(); s != shared_order_[share].rend(); ++s)
      backwardSupernode(*s, y, gathered, avx2);
  });
}

void SparseBlockLdlt::forwardShares(bool two_threads)
{
  // Each share's supernodes in order, each share with its own scratch; the two at once, or one
  // after the other on this thread.
  double* const y = work_.data();
  const bool avx2 = useAvx2();
  auto forward = [&](int share) {
    double* const gathered = share == 0 ? gathered_.data() : second_gathered_.data();
    for (const int s : shared_order_[share])
      forwardSupernode(s, y, gathered, avx2,
                       kept_sums_at_[s] == kNotKept ? nullptr : kept_sums_.data() + kept_sums_at_[s]);
  };
  if (two_threads)
  {
    workers_->forEachChunk(2, 1, [&](int share, int) { forward(share); });
    return;
  }
  forward(0);
  forward(1);
}

void SparseBlockLdlt::forwardSupernode(std::size_t s, double* y, double* gathered, bool avx2, double* kept)
{
  // The own triangle, then −Σ of the rows below into `gathered` and added to them: all of them, or
  // (`kept` not null) those of the supernode's own share, the sums of the rows above the shares
  // written to `kept` instead.
  const Supernode& supernode = supernodes_[s];
  const int width = 3 * supernode.width, below = 3 * supernode.below, m = width + below;
  const double* const panel = panels_.data() + supernode.panel;
  double* const own = y + 3L * supernode.first;
  std::fill(gathered, gathered + below, 0.0);
  for (int c = 0; c < width; ++c)
  {
    const double* const column = panel + static_cast<long>(c) * m;
    dense_panel::subtractScaled(avx2, width - c - 1, column + c + 1, own[c], own + c + 1);
  }
  // −Σ of the rows below, column after column for each row (own is final once its triangle is done).
  dense_panel::subtractScaledColumns(avx2, below, width, panel + width, m, own, gathered);
  const int* const rows = super_rows_.data() + supernode.rows;
  const int added = kept ? first_row_above_[s] : supernode.below;
  for (int a = 0; a < added; ++a)
    for (int r = 0; r < 3; ++r)
      y[3L * rows[a] + r] += gathered[3 * a + r];
  if (kept) std::copy(gathered + 3 * added, gathered + below, kept);
}

void SparseBlockLdlt::backwardSupernode(std::size_t s, double* y, double* gathered, bool avx2)
{
  const Supernode& supernode = supernodes_[s];
  const int width = 3 * supernode.width, below = 3 * supernode.below, m = width + below;
  const double* const panel = panels_.data() + supernode.panel;
  double* const own = y + 3L * supernode.first;
  const int* const rows = super_rows_.data() + supernode.rows;
  for (int a = 0; a < supernode.below; ++a)
    for (int r = 0; r < 3; ++r)
      gathered[3 * a + r] = y[3L * rows[a] + r];
  // The rows below's dots first, all columns at once (they read only `gathered`), into the scratch
  // after it; then the own triangle backwards.
  double* const dots = gathered + below;
  dense_panel::dotColumns(avx2, below, width, panel + width, m, gathered, dots);
  for (int c = width - 1; c >= 0; --c)
  {
    const double* const column = panel + static_cast<long>(c) * m;
    own[c] -= dots[c] + dense_panel::dot(avx2, width - c - 1, column + c + 1, own + c + 1);
  }
}

}  // namespace core
}  // namespace particle_sim
