#pragma once

#include <vector>

namespace particle_sim
{
namespace core
{
/// A list of particle pairs (springs, or the implicit solver's spring blocks) prepared for a loop
/// shared between threads by fixed chunks of particles, in which each pair adds something to its
/// two ends: each chunk's thread visits, in list order, every pair that touches the chunk and adds
/// only to the ends inside it. Every particle then gets the additions of a one-thread loop over the
/// list, in its order, and so its bits, at any thread count. A pair across two chunks is visited by
/// both.
///
/// A chunk's pairs are kept as runs of consecutive pairs with the same ends inside the chunk, so
/// that the inner loop tests nothing.
class PairChunks
{
public:
  static constexpr int kEndI = 1;
  static constexpr int kEndJ = 2;
  static constexpr int kBothEnds = kEndI | kEndJ;
  /// Consecutive pairs first … first + count − 1, all touching one chunk with the same ends inside it.
  struct Run
  {
    int first;
    int count;
    int ends;  // kEndI, kEndJ or kBothEnds: those inside the chunk
  };

  /// Rebuilds the runs for `pairs` pairs whose ends are end_i(k) and end_j(k), over `particles`
  /// particles in chunks of `chunk_size`. Allocates only when the lists grow.
  template <class EndI, class EndJ>
  void build(int pairs, int particles, int chunk_size, EndI&& end_i, EndJ&& end_j);

  /// Pairs listed over all chunks: the pairs, and once more each pair across two chunks.
  int listed() const { return listed_; }
  /// Whether the runs are worth using: at most a quarter of the pairs cross two chunks (else the
  /// pairs are numbered without locality, and a loop over them costs much more than one thread's).
  bool hasLocality() const { return listed_ - pairs_ <= pairs_ / 4; }
  int chunks() const { return static_cast<int>(chunk_start_.size()) - 1; }
  /// The runs of chunk c: runs()[runStart(c)] … runs()[runStart(c + 1) − 1].
  int runStart(int c) const { return chunk_start_[c]; }
  const Run* runs() const { return runs_.data(); }

private:
  std::vector<int> chunk_start_;
  std::vector<Run> runs_;
  std::vector<int> chunk_pairs_;  // build()'s scratch: per chunk, its pairs, ascending
  int listed_ = 0;
  int pairs_ = 0;
};

template <class EndI, class EndJ>
void PairChunks::build(int pairs, int particles, int chunk_size, EndI&& end_i, EndJ&& end_j)
{
  const int chunks = (particles + chunk_size - 1) / chunk_size;
  auto chunk_of = [chunk_size](int particle) { return particle / chunk_size; };
  // Counting sort of the pairs by the chunks they touch (one or two), filled in list order.
  chunk_start_.assign(chunks + 1, 0);
  for (int k = 0; k < pairs; ++k)
  {
    const int ci = chunk_of(end_i(k)), cj = chunk_of(end_j(k));
    ++chunk_start_[ci + 1];
    if (cj != ci) ++chunk_start_[cj + 1];
  }
  for (int c = 0; c < chunks; ++c)
    chunk_start_[c + 1] += chunk_start_[c];
  listed_ = chunk_start_[chunks];
  pairs_ = pairs;
  chunk_pairs_.resize(listed_);
  for (int k = 0; k < pairs; ++k)
  {
    const int ci = chunk_of(end_i(k)), cj = chunk_of(end_j(k));
    chunk_pairs_[chunk_start_[ci]++] = k;
    if (cj != ci) chunk_pairs_[chunk_start_[cj]++] = k;
  }
  // The fill moved each start to the next chunk's: shift them back.
  for (int c = chunks; c > 0; --c)
    chunk_start_[c] = chunk_start_[c - 1];
  chunk_start_[0] = 0;
  // Each chunk's list, cut into runs of consecutive pairs with the same ends inside the chunk;
  // chunk_start_ then indexes the runs. There are never more runs than listed pairs, so the runs
  // allocate only when the list grows.
  runs_.clear();
  runs_.reserve(chunk_pairs_.size());
  for (int c = 0; c < chunks; ++c)
  {
    const int first_run = static_cast<int>(runs_.size());
    for (int e = chunk_start_[c]; e < chunk_start_[c + 1]; ++e)
    {
      const int k = chunk_pairs_[e];
      const int ends = (chunk_of(end_i(k)) == c ? kEndI : 0) | (chunk_of(end_j(k)) == c ? kEndJ : 0);
      Run* const previous = static_cast<int>(runs_.size()) > first_run ? &runs_.back() : nullptr;
      if (previous && previous->ends == ends && previous->first + previous->count == k)
        ++previous->count;
      else
        runs_.push_back(Run{k, 1, ends});
    }
    chunk_start_[c] = first_run;
  }
  chunk_start_[chunks] = static_cast<int>(runs_.size());
}

}  // namespace core
}  // namespace particle_sim
