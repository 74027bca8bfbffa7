// The node loop's schedule (README "Time"): a late tick is made up by the ticks after it, up to
// ~max_lag; what lies beyond is dropped and counted. The loop is simulated on a clock of our own:
// each tick takes its work, then waits until the next one is due.

#include "particle_sim/ros/tick_schedule.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

using namespace particle_sim::ros_interface;
using Clock = std::chrono::steady_clock;
using Seconds = std::chrono::duration<double>;

namespace
{
Clock::time_point at(double seconds)
{
  return Clock::time_point(std::chrono::duration_cast<Clock::duration>(Seconds(seconds)));
}

double secondsOf(Clock::time_point t)
{
  return Seconds(t.time_since_epoch()).count();
}

// Runs the loop over `work` (the wall seconds each tick takes) at `period`; returns the wall time
// at the end, the ticks' sim time being work.size() · period, and adds up the lag dropped.
double runLoop(const std::vector<double>& work, double period, double max_lag, double& dropped)
{
  double now = 0.0;
  Clock::time_point due = at(0.0);
  dropped = 0.0;
  for (const double seconds : work)
  {
    now = std::max(now, secondsOf(due)) + seconds;  // wait until due, then run the tick
    const NextTick next = nextTick(due, Seconds(period), at(now), Seconds(max_lag));
    dropped += next.dropped;
    due = next.due;
  }
  return std::max(now, secondsOf(due));  // the end of the last tick's period
}
}  // namespace

TEST(TickSchedule, OnTimeTheNextTickIsOnePeriodLater)
{
  const NextTick next = nextTick(at(1.0), Seconds(0.02), at(1.005), Seconds(0.5));
  EXPECT_EQ(next.due, at(1.0) + std::chrono::duration_cast<Clock::duration>(Seconds(0.02)));
  EXPECT_EQ(next.dropped, 0.0);
}

TEST(TickSchedule, AHiccupWithinMaxLagIsMadeUpSoSimTimeKeepsUpWithTheWallClock)
{
  // 60 Hz ticks of 5 ms work, one of them 200 ms: the ticks after it run back to back until the
  // loop is on schedule again, and at the end wall time is sim time (1000 periods).
  const double period = 1.0 / 60.0;
  std::vector<double> work(1000, 0.005);
  work[100] = 0.2;
  double dropped = 0.0;
  const double wall = runLoop(work, period, 0.5, dropped);
  EXPECT_EQ(dropped, 0.0);
  EXPECT_NEAR(wall, 1000 * period, 1e-6);  // each period is cut to the steady clock's nanoseconds

  // With no lag allowed, the same hiccup is lost: wall time runs ahead of sim time by what was
  // dropped, and that is the hiccup less the period it fell in.
  const double wall_without = runLoop(work, period, 0.0, dropped);
  EXPECT_NEAR(dropped, 0.2 - period, 1e-6);
  EXPECT_NEAR(wall_without, 1000 * period + dropped, 1e-6);
}

TEST(TickSchedule, LagBeyondMaxLagIsDroppedAndCountedTheRestKeepsTheSchedule)
{
  // A stall of 2 s against max_lag 0.5 s: the schedule starts again after it, 2 s less a period
  // behind; each later tick is on time.
  const double period = 0.01;
  std::vector<double> work(500, 0.004);
  work[10] = 2.0;
  double dropped = 0.0;
  const double wall = runLoop(work, period, 0.5, dropped);
  EXPECT_NEAR(dropped, 2.0 - period, 1e-6);
  EXPECT_NEAR(wall, 500 * period + dropped, 1e-6);

  // Ticks slower than the period all along: the loop runs them back to back, and drops whatever
  // goes past max_lag whenever it does; wall time is still sim time plus what was dropped.
  std::vector<double> slow(300, 0.015);
  const double slow_wall = runLoop(slow, period, 0.1, dropped);
  EXPECT_GT(dropped, 0.0);
  EXPECT_NEAR(slow_wall, 300 * period + dropped, 0.1 + period);
  EXPECT_NEAR(slow_wall, 300 * 0.015, 1e-6);  // never waiting: as fast as the ticks go
}
