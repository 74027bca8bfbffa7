// PublishingThread (src/ros/publishing_thread.cpp): the node's sender of markers, meshes and clouds.
// Its sends here are plain functions that record what ran, where and when.
#include "particle_sim/ros/publishing_thread.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <future>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

namespace particle_sim
{
namespace ros_interface
{
namespace
{
// Polls until the thread has sent its batch; false if it is still busy after 30 s (a hang).
bool waitUntilIdle(const PublishingThread& publishing)
{
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (publishing.busy())
  {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

// What the sends did: their numbers in the order they ran, and the threads they ran on.
struct SendLog
{
  std::mutex mutex;
  std::vector<int> order;
  std::vector<std::thread::id> threads;
  PublishingThread::Send send(int number)
  {
    return [this, number] {
      std::lock_guard<std::mutex> lock(mutex);
      order.push_back(number);
      threads.push_back(std::this_thread::get_id());
    };
  }
};
}  // namespace

TEST(PublishingThread, SendsEachBatchInOrderOnAThreadOfItsOwn)
{
  PublishingThread publishing;
  SendLog log;
  for (int batch = 0; batch < 3; ++batch)
  {
    std::vector<PublishingThread::Send> sends;
    for (int i = 0; i < 4; ++i)
      sends.push_back(log.send(10 * batch + i));
    publishing.submit(sends);
    EXPECT_TRUE(sends.empty()) << "the sends were handed over";
    ASSERT_TRUE(waitUntilIdle(publishing));
  }
  EXPECT_EQ(log.order, (std::vector<int>{0, 1, 2, 3, 10, 11, 12, 13, 20, 21, 22, 23}));
  for (const std::thread::id& thread : log.threads)
  {
    EXPECT_NE(thread, std::this_thread::get_id()) << "a send ran on the caller's thread";
    EXPECT_EQ(thread, log.threads.front()) << "one thread sends every batch";
  }
}

TEST(PublishingThread, SendsAtALowerPriorityThanTheLoop)
{
  // The sends run at a nice value kNiceIncrement above the caller's (capped at 19): the physics
  // comes first when the cores are short. The caller's own priority is left alone.
  errno = 0;
  const int caller_nice = getpriority(PRIO_PROCESS, 0);  // Linux: this thread's
  ASSERT_EQ(errno, 0);
  std::atomic<int> sender_nice{-100};
  PublishingThread publishing;
  std::vector<PublishingThread::Send> sends{[&] { sender_nice = getpriority(PRIO_PROCESS, 0); }};
  publishing.submit(sends);
  ASSERT_TRUE(waitUntilIdle(publishing));
  EXPECT_EQ(sender_nice, std::min(caller_nice + PublishingThread::kNiceIncrement, 19));
  EXPECT_EQ(getpriority(PRIO_PROCESS, 0), caller_nice);
}

TEST(PublishingThread, IsBusyUntilTheBatchsLastSendReturnsAndRefusesASecondBatchMeanwhile)
{
  PublishingThread publishing;
  EXPECT_FALSE(publishing.busy());
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  std::atomic<int> sent{0};
  std::vector<PublishingThread::Send> sends{[&sent] { ++sent; },
                                            [released, &sent] {
                                              released.wait();
                                              ++sent;
                                            }};
  publishing.submit(sends);
  // The second send waits for `release`: the batch is still being sent.
  EXPECT_TRUE(publishing.busy());
  std::vector<PublishingThread::Send> second{[&sent] { sent += 100; }};
  EXPECT_THROW(publishing.submit(second), std::logic_error);
  EXPECT_EQ(second.size(), 1u) << "a refused batch stays with the caller";
  release.set_value();
  ASSERT_TRUE(waitUntilIdle(publishing));
  EXPECT_EQ(sent.load(), 2);
  publishing.submit(second);
  ASSERT_TRUE(waitUntilIdle(publishing));
  EXPECT_EQ(sent.load(), 102);
}

TEST(PublishingThread, StopSendsTheBatchInProgressAndALaterBatchStartsItAgain)
{
  PublishingThread publishing;
  SendLog log;
  std::vector<PublishingThread::Send> sends;
  sends.push_back([] { std::this_thread::sleep_for(std::chrono::milliseconds(50)); });
  for (int i = 0; i < 3; ++i)
    sends.push_back(log.send(i));
  publishing.submit(sends);
  publishing.stop();
  EXPECT_FALSE(publishing.busy());
  EXPECT_EQ(log.order, (std::vector<int>{0, 1, 2})) << "stop() returned before the batch was sent";

  sends.push_back(log.send(3));
  publishing.submit(sends);
  publishing.stop();
  EXPECT_EQ(log.order, (std::vector<int>{0, 1, 2, 3})) << "the batch after a stop was not sent";
}

}  // namespace ros_interface
}  // namespace particle_sim
