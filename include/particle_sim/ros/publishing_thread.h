#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace particle_sim
{
namespace ros_interface
{
/// Sends a tick's heavy messages (markers, meshes, point clouds) from a thread of its own, so that
/// sending them never holds up the physics.
///
/// The loop builds a tick's messages and hands them over as one batch of sends. This thread runs
/// the sends in order: each is a publish(), which is where roscpp serialises a message for its
/// remote subscribers and writes it to their sockets. The loop never waits for it. While a batch is
/// still being sent, busy() is true, and the loop skips that tick's heavy messages: the topic loses
/// a tick, the physics loses nothing. The thread starts with the first batch, at a lower CPU
/// priority than the loop's (its nice value kNiceIncrement higher): on a machine whose cores are
/// all busy, the physics gets them first, and the messages are what waits.
class PublishingThread
{
public:
  using Send = std::function<void()>;
  /// How much higher the thread's nice value is than its creator's (Linux: per thread, up to 19).
  static constexpr int kNiceIncrement = 10;

  PublishingThread() = default;
  /// stop().
  ~PublishingThread();
  PublishingThread(const PublishingThread&) = delete;
  PublishingThread& operator=(const PublishingThread&) = delete;

  /// True from submit() until the batch's last send has returned.
  bool busy() const;
  /// Hands the sends over, in order, and leaves `sends` empty (its capacity is kept). Call only
  /// when !busy(): a batch is never queued behind another.
  void submit(std::vector<Send>& sends);
  /// Waits for the batch in progress, then ends the thread. A later submit() starts it again.
  void stop();

private:
  void sendBatches();

  mutable std::mutex mutex_;
  std::condition_variable batch_ready_;
  std::vector<Send> batch_;  // the batch being sent; empty when idle
  bool sending_ = false;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace ros_interface
}  // namespace particle_sim
