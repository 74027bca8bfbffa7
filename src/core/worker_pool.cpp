#include "particle_sim/core/worker_pool.h"

#include <algorithm>

namespace particle_sim
{
namespace core
{
namespace
{
// How long a thread polls before it sleeps or yields: a few microseconds, about the gap between
// two loops of one substep, so that a step's loops do not pay a wake-up each.
constexpr int kSpins = 4000;

inline void pause()
{
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}
}  // namespace

WorkerPool::WorkerPool(int threads) : threads_(std::max(1, threads)), ranges_(threads_) {}

WorkerPool::~WorkerPool()
{
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  for (std::thread& worker : workers_)
    worker.join();
}

int WorkerPool::coreCount()
{
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

void WorkerPool::start()
{
  workers_.reserve(threads_ - 1);
  for (int worker = 1; worker < threads_; ++worker)
    workers_.emplace_back([this, worker] { work(worker); });
}

void WorkerPool::run(int items, int chunk, void* callable, Trampoline trampoline)
{
  if (workers_.empty()) start();
  ++shared_loops_;
  callable_ = callable;
  trampoline_ = trampoline;
  items_ = items;
  chunk_ = chunk;
  const int chunks = (items + chunk - 1) / chunk;
  for (int t = 0; t < threads_; ++t)
  {
    ranges_[t].next.store(static_cast<int>(static_cast<long long>(chunks) * t / threads_), std::memory_order_relaxed);
    ranges_[t].end = static_cast<int>(static_cast<long long>(chunks) * (t + 1) / threads_);
  }
  finished_workers_.store(0, std::memory_order_relaxed);
  open_places_.store(threads_ - 1, std::memory_order_release);  // publishes the loop to join()
  {
    // Under the lock, so that a worker between its check and its wait cannot miss the bump.
    std::lock_guard<std::mutex> lock(mutex_);
    generation_.fetch_add(1, std::memory_order_release);
  }
  wake_.notify_all();
  takeChunks(0);
  // Every chunk is taken: close the loop, then wait for the workers that joined it to finish
  // theirs (each counts itself out once). A worker that wakes later skips this loop.
  const int joined = (threads_ - 1) - open_places_.exchange(0, std::memory_order_acq_rel);
  for (int spin = 0; finished_workers_.load(std::memory_order_acquire) != joined; ++spin)
  {
    if (spin < kSpins)
      pause();
    else
      std::this_thread::yield();
  }
}

bool WorkerPool::join()
{
  int places = open_places_.load(std::memory_order_acquire);
  while (places > 0)
  {
    if (open_places_.compare_exchange_weak(places, places - 1, std::memory_order_acq_rel, std::memory_order_acquire))
      return true;
  }
  return false;
}

void WorkerPool::takeChunks(int thread)
{
  // The home range first, then the others' in turn: a range's chunks go to whichever thread takes
  // them first, and which thread runs a chunk never changes its result.
  for (int turn = 0; turn < threads_; ++turn)
  {
    HomeRange& range = ranges_[(thread + turn) % threads_];
    for (int c = range.next.fetch_add(1, std::memory_order_relaxed); c < range.end;
         c = range.next.fetch_add(1, std::memory_order_relaxed))
    {
      const int begin = c * chunk_;
      trampoline_(callable_, begin, std::min(items_, begin + chunk_));
    }
  }
}

void WorkerPool::work(int thread)
{
  std::uint64_t seen = 0;
  for (;;)
  {
    // Poll for the next loop, then sleep until run() or the destructor wakes us.
    std::uint64_t now = generation_.load(std::memory_order_acquire);
    for (int spin = 0; now == seen && spin < kSpins && !stopping_.load(std::memory_order_relaxed); ++spin)
    {
      pause();
      now = generation_.load(std::memory_order_acquire);
    }
    if (now == seen)
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || generation_.load(std::memory_order_acquire) != seen; });
      if (stopping_) return;
      now = generation_.load(std::memory_order_acquire);
    }
    seen = now;
    if (!join()) continue;
    takeChunks(thread);
    finished_workers_.fetch_add(1, std::memory_order_release);
  }
}

}  // namespace core
}  // namespace particle_sim
