#include "particle_sim/ros/publishing_thread.h"

#include <unistd.h>

#include <stdexcept>

namespace particle_sim
{
namespace ros_interface
{
PublishingThread::~PublishingThread()
{
  stop();
}

bool PublishingThread::busy() const
{
  std::lock_guard<std::mutex> lock(mutex_);
  return sending_;
}

void PublishingThread::submit(std::vector<Send>& sends)
{
  if (sends.empty()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (sending_) throw std::logic_error("PublishingThread::submit while a batch is being sent");
    batch_.swap(sends);
    sending_ = true;
    stopping_ = false;
  }
  sends.clear();
  if (!thread_.joinable()) thread_ = std::thread(&PublishingThread::sendBatches, this);
  batch_ready_.notify_one();
}

void PublishingThread::stop()
{
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  batch_ready_.notify_one();
  if (thread_.joinable()) thread_.join();
}

void PublishingThread::sendBatches()
{
  // Below the physics in the scheduler's eyes: when the cores are short, the step runs first and
  // the messages wait (and skip ticks). Linux keeps a nice value per thread; nice() sets this one's.
  // If the system refuses, the thread just sends at the loop's priority.
  const int nice_value = nice(kNiceIncrement);
  static_cast<void>(nice_value);
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;)
  {
    // A batch handed over before a stop is still sent.
    batch_ready_.wait(lock, [this] { return sending_ || stopping_; });
    if (!sending_) return;
    std::vector<Send> batch;
    batch.swap(batch_);
    lock.unlock();
    for (Send& send : batch)
      send();
    // The messages and publisher handles the sends hold are let go before the loop hears the batch
    // is done: after stop(), nothing of a batch outlives the publishers.
    batch.clear();
    lock.lock();
    batch_.swap(batch);  // keeps the capacity for the next batch
    sending_ = false;
  }
}

}  // namespace ros_interface
}  // namespace particle_sim
