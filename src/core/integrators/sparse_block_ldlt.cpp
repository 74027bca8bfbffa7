#include "particle_sim/core/integrators/sparse_block_ldlt.h"

#include <Eigen/LU>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>

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
}  // namespace

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
  forEachFactorBlock(start, column, eliminationTree(start, column), [&counts](int, int j) { ++counts[j]; });
  Cost cost;
  for (int count : counts)
  {
    cost.factor_blocks += count;
    addColumnFlops(count, cost.factor_flops, cost.solve_flops);
  }
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

  // The elimination's updates, in the order factorize() makes them, and the flop counts.
  update_slot_.clear();
  factor_flops_ = solve_flops_ = 0.0;
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
    addColumnFlops(count, factor_flops_, solve_flops_);
  }
}

bool SparseBlockLdlt::factorize(const std::vector<Eigen::Matrix3d>& blocks, const std::vector<char>& pinned)
{
  const int n = static_cast<int>(pivot_.size());
  for (int i = 0; i < n; ++i)
  {
    pinned_new_[i] = pinned[old_of_[i]];
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
  for (int i = 0; i < n; ++i)
    work_.col(i) = b.col(old_of_[i]);
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
  for (int i = 0; i < n; ++i)
    x.col(old_of_[i]) = work_.col(i);
}

}  // namespace core
}  // namespace particle_sim
