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

WorkerPool::WorkerPool(int threads) : threads_(std::max(1, threads)) {}

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
    workers_.emplace_back([this] { work(); });
}

void WorkerPool::run(int items, int chunk, void* callable, Trampoline trampoline)
{
  if (workers_.empty()) start();
  ++shared_loops_;
  callable_ = callable;
  trampoline_ = trampoline;
  items_ = items;
  chunk_ = chunk;
  chunks_ = (items + chunk - 1) / chunk;
  next_chunk_.store(0, std::memory_order_relaxed);
  finished_workers_.store(0, std::memory_order_relaxed);
  open_places_.store(threads_ - 1, std::memory_order_release);  // publishes the loop to join()
  {
    // Under the lock, so that a worker between its check and its wait cannot miss the bump.
    std::lock_guard<std::mutex> lock(mutex_);
    generation_.fetch_add(1, std::memory_order_release);
  }
  wake_.notify_all();
  takeChunks();
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

void WorkerPool::takeChunks()
{
  // Chunks go to whichever thread asks first: which thread runs a chunk never changes its result.
  for (int c = next_chunk_.fetch_add(1, std::memory_order_relaxed); c < chunks_;
       c = next_chunk_.fetch_add(1, std::memory_order_relaxed))
  {
    const int begin = c * chunk_;
    trampoline_(callable_, begin, std::min(items_, begin + chunk_));
  }
}

void WorkerPool::work()
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
    takeChunks();
    finished_workers_.fetch_add(1, std::memory_order_release);
  }
}

}  // namespace core
}  // namespace particle_sim
