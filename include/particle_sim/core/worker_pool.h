#pragma once

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <thread>
#include <type_traits>
#include <vector>

namespace particle_sim
{
namespace core
{
/// Threads that share the loops of a step, deterministically. forEachChunk() cuts the items
/// 0 … n−1 into chunks of a fixed size (set by the caller, never by the thread count). Each thread
/// has a home range of the chunks, the same one in every loop (thread t of T: the t-th of T equal
/// runs), so that the particles a thread integrates are those whose forces it summed and stay in
/// its core's cache from loop to loop; a thread done with its own range takes what is left of the
/// others'. A loop may use it only when each item's result is computed alone and written to its own
/// place (no sum across chunks): then the results are the same bits at any thread count, whichever
/// thread runs a chunk, and one thread runs the whole range in a single call.
///
/// The threads start at the first loop that has more than one chunk (a scene of small bodies never
/// starts one) and then wait for work, spinning briefly before they sleep. Nothing allocates after
/// the start. Loops must not nest, and one thread at a time may call forEachChunk().
class WorkerPool
{
public:
  /// `threads` >= 1 counts the calling thread: 1 runs everything on the caller.
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int threads() const { return threads_; }
  /// Loops that were shared between threads since construction (for tests and the bench).
  std::uint64_t sharedLoops() const { return shared_loops_; }

  /// Calls body(begin, end) on chunks that cover [0, items) once each, `chunk` items long but the
  /// last; returns when all are done.
  template <class Body>
  void forEachChunk(int items, int chunk, Body&& body)
  {
    if (items <= 0) return;
    if (threads_ == 1 || items <= chunk)
    {
      body(0, items);
      return;
    }
    using Plain = std::remove_reference_t<Body>;
    run(items, chunk, const_cast<void*>(static_cast<const void*>(&body)),
        [](void* callable, int begin, int end) { (*static_cast<Plain*>(callable))(begin, end); });
  }

  /// The machine's core count (at least 1): what a thread count of 0 stands for.
  static int coreCount();

private:
  using Trampoline = void (*)(void*, int, int);
  void run(int items, int chunk, void* callable, Trampoline trampoline);
  void start();
  void work(int thread);
  // Takes one of the current loop's open places; false when the loop is closed (its caller is done
  // with every chunk, or the other workers took the places).
  bool join();
  // Runs the chunks of `thread`'s home range, then those left in the other threads' ranges.
  void takeChunks(int thread);

  const int threads_;
  std::vector<std::thread> workers_;
  std::uint64_t shared_loops_ = 0;

  // The loop being shared: set by run() before it bumps `generation_`.
  void* callable_ = nullptr;
  Trampoline trampoline_ = nullptr;
  int items_ = 0;
  int chunk_ = 0;
  // Each thread's home range [next, end) of the loop's chunks; `next` is taken by fetch_add, by the
  // owner and then by any thread done with its own. One cache line each, so that the owners' takes
  // do not contend.
  struct alignas(64) HomeRange
  {
    std::atomic<int> next{0};
    int end = 0;
  };
  std::vector<HomeRange> ranges_;
  // Workers join a loop by taking one of its open places; the caller closes it when every chunk is
  // taken and waits only for those that joined, never for a worker that has not woken yet.
  std::atomic<int> open_places_{0};
  std::atomic<int> finished_workers_{0};

  std::atomic<std::uint64_t> generation_{0};  // one more for each shared loop
  std::atomic<bool> stopping_{false};
  std::mutex mutex_;
  std::condition_variable wake_;
};

/// Particles per chunk of a shared per-particle vector loop (a few arithmetic operations each).
constexpr int kParticlesPerVectorChunk = 4096;

/// body(begin, end) over [0, items) in chunks of `chunk`: shared with `workers`, or in one call
/// when there are none.
template <class Body>
void shareLoop(WorkerPool* workers, int items, int chunk, Body&& body)
{
  if (workers)
    workers->forEachChunk(items, chunk, body);
  else if (items > 0)
    body(0, items);
}

/// body(first, last) on the two halves of [0, n), each as one chunk of its own (on two threads where
/// `workers` has them): for a pass whose two parts are cut by something other than a chunk size.
template <class Body>
void byHalves(WorkerPool& workers, std::size_t n, Body&& body)
{
  workers.forEachChunk(2, 1, [&](int begin, int end) {
    for (int half = begin; half < end; ++half)
      body(half == 0 ? std::size_t{0} : n / 2, half == 0 ? n / 2 : n);
  });
}

/// body(index, first, last) once for every chunk [first, last) of `chunk` items (the last one
/// shorter), index = first / chunk: shared with `workers`, always one call a chunk, whatever the
/// thread count. For loops whose chunks keep a result of their own, such as a partial sum.
template <class Body>
void forEachFixedChunk(WorkerPool* workers, int items, int chunk, Body&& body)
{
  shareLoop(workers, items, chunk, [&](int begin, int end) {
    for (int first = begin; first < end; first += chunk)
      body(first / chunk, first, std::min(end, first + chunk));
  });
}

/// Σ chunk_sum(first, last) over the fixed chunks [first, last) of `chunk` items that cover
/// [0, items) (shared with `workers`), summed chunk after chunk on the calling thread: the same bits
/// at any thread count, one included, since the chunks never depend on it. For a chunk's sum that
/// does more on its way (sumByChunks() is the plain one). `partial` holds each chunk's sum; it
/// allocates only when it grows.
template <class ChunkSum>
double sumChunks(WorkerPool* workers, int items, int chunk, std::vector<double>& partial, ChunkSum&& chunk_sum)
{
  if (items <= 0) return 0.0;
  partial.resize((items + chunk - 1) / chunk);
  forEachFixedChunk(workers, items, chunk,
                    [&](int index, int first, int last) { partial[index] = chunk_sum(first, last); });
  double total = 0.0;
  for (const double sum : partial)
    total += sum;
  return total;
}

/// Σ term(i) over [0, items): summed in order within fixed chunks of `chunk` items (sumChunks()).
template <class Term>
double sumByChunks(WorkerPool* workers, int items, int chunk, std::vector<double>& partial, Term&& term)
{
  return sumChunks(workers, items, chunk, partial, [&](int first, int last) {
    double sum = 0.0;
    for (int i = first; i < last; ++i)
      sum += term(i);
    return sum;
  });
}

}  // namespace core
}  // namespace particle_sim
