// particle_sim_node_probe: measures a running particle_sim node from outside, as a subscriber
// would see it (goals 3 and 4 of issue 13; scripts/node_bench.py runs it).
//
//   particle_sim_node_probe [--node /particle_sim] [--topics markers,meshes,points] [--warmup S] [--duration S]
//
// It subscribes to the chosen topics with their real message types, so that every message is
// received and deserialised as rviz or a perception node would, and to /clock. After the first
// /clock it waits `warmup` seconds of wall time, then for `duration` seconds counts each topic's
// messages and reads /clock against the steady wall clock:
//   - the real-time factor: sim time gone by over wall time gone by (the one the node reaches, not
//     its target), also in one-second windows for its spread;
//   - each topic's rate [Hz] and its points per message (markers: all points of an array);
//   - the wall time between two /clock messages [ms]: min, median, max.
// Then it reads one ~status for what each spring body's integrator ran (auto's choice). The result
// is one line of key=value pairs on standard output; the exit status is 1 when no /clock came.
#include <particle_sim/ClothMesh.h>
#include <particle_sim/SimStatus.h>
#include <ros/ros.h>
#include <ros/topic.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/PointCloud2.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

namespace
{
using SteadyClock = std::chrono::steady_clock;

double secondsSince(SteadyClock::time_point start)
{
  return std::chrono::duration<double>(SteadyClock::now() - start).count();
}

// What the callbacks record, under one mutex (the spinner may use several threads).
struct Counts
{
  std::mutex mutex;
  bool measuring = false;
  long long messages[3] = {0, 0, 0};  // markers, meshes, points
  long long points[3] = {0, 0, 0};
  // (wall seconds since the probe started, sim time) of every /clock.
  std::vector<std::pair<double, double>> clock;
};

struct Options
{
  std::string node = "/particle_sim";
  std::string topics = "markers";
  double warmup = 5.0;     // [s] of wall time after the first /clock
  double duration = 15.0;  // [s] of wall time measured
};

bool parse(int argc, char** argv, Options& options)
{
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    if (i + 1 >= argc) return false;
    const std::string value = argv[++i];
    if (arg == "--node")
      options.node = value;
    else if (arg == "--topics")
      options.topics = value;
    else if (arg == "--warmup")
      options.warmup = std::atof(value.c_str());
    else if (arg == "--duration")
      options.duration = std::atof(value.c_str());
    else
      return false;
  }
  return options.duration > 0.0 && options.warmup >= 0.0;
}

double median(std::vector<double> values)
{
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}
}  // namespace

int main(int argc, char** argv)
{
  constexpr const char* kUsage =
      "usage: particle_sim_node_probe [--node /particle_sim] [--topics markers,meshes,points] [--warmup S] "
      "[--duration S]\n"
      "  measures a running particle_sim node as a subscriber sees it (scripts/node_bench.py runs it):\n"
      "  its real-time factor from /clock against the wall clock, and each topic's rate and points\n";
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h")
    {
      std::printf("%s", kUsage);
      return 0;
    }
  ros::init(argc, argv, "particle_sim_node_probe", ros::init_options::AnonymousName);
  Options options;
  if (!parse(argc, argv, options))
  {
    std::fprintf(stderr, "%s", kUsage);
    return 2;
  }
  ros::NodeHandle nh;
  const auto start = SteadyClock::now();
  Counts counts;
  const auto count = [&counts](int topic, long long points) {
    std::lock_guard<std::mutex> lock(counts.mutex);
    if (!counts.measuring) return;
    ++counts.messages[topic];
    counts.points[topic] += points;
  };

  std::vector<ros::Subscriber> subscribers;
  const ros::TransportHints hints = ros::TransportHints().tcpNoDelay();
  const bool markers = options.topics.find("markers") != std::string::npos;
  const bool meshes = options.topics.find("meshes") != std::string::npos;
  const bool points = options.topics.find("points") != std::string::npos;
  if (markers)
    subscribers.push_back(nh.subscribe<visualization_msgs::MarkerArray>(
        options.node + "/markers", 1,
        [&count](const visualization_msgs::MarkerArray::ConstPtr& array) {
          long long n = 0;
          for (const auto& marker : array->markers)
            n += static_cast<long long>(marker.points.size());
          count(0, n);
        },
        ros::VoidConstPtr(), hints));
  if (meshes)
    subscribers.push_back(nh.subscribe<particle_sim::ClothMesh>(
        options.node + "/meshes", 1,
        [&count](const particle_sim::ClothMesh::ConstPtr& mesh) {
          count(1, static_cast<long long>(mesh->mesh.vertices.size()));
        },
        ros::VoidConstPtr(), hints));
  if (points)
    subscribers.push_back(nh.subscribe<sensor_msgs::PointCloud2>(
        options.node + "/points", 1,
        [&count](const sensor_msgs::PointCloud2::ConstPtr& cloud) {
          count(2, static_cast<long long>(cloud->width) * cloud->height);
        },
        ros::VoidConstPtr(), hints));
  subscribers.push_back(nh.subscribe<rosgraph_msgs::Clock>(
      "/clock", 100,
      [&counts, start](const rosgraph_msgs::Clock::ConstPtr& clock) {
        std::lock_guard<std::mutex> lock(counts.mutex);
        counts.clock.emplace_back(secondsSince(start), clock->clock.toSec());
      },
      ros::VoidConstPtr(), hints));

  ros::AsyncSpinner spinner(2);
  spinner.start();

  // The first /clock, then the warm-up, then the measured window.
  const auto clock_count = [&counts] {
    std::lock_guard<std::mutex> lock(counts.mutex);
    return counts.clock.size();
  };
  while (ros::ok() && clock_count() == 0 && secondsSince(start) < 60.0)
    ros::WallDuration(0.01).sleep();
  if (clock_count() == 0)
  {
    std::fprintf(stderr, "particle_sim_node_probe: no /clock within 60 s\n");
    return 1;
  }
  ros::WallDuration(options.warmup).sleep();
  std::size_t first_clock = 0;
  {
    std::lock_guard<std::mutex> lock(counts.mutex);
    counts.measuring = true;
    first_clock = counts.clock.size();
  }
  const auto window_start = SteadyClock::now();
  ros::WallDuration(options.duration).sleep();
  const double window = secondsSince(window_start);
  std::vector<std::pair<double, double>> clock;
  long long messages[3], points_per_topic[3];
  {
    std::lock_guard<std::mutex> lock(counts.mutex);
    counts.measuring = false;
    clock.assign(counts.clock.begin() + static_cast<long>(first_clock > 0 ? first_clock - 1 : 0), counts.clock.end());
    std::copy(counts.messages, counts.messages + 3, messages);
    std::copy(counts.points, counts.points + 3, points_per_topic);
  }
  if (clock.size() < 2)
  {
    std::fprintf(stderr, "particle_sim_node_probe: /clock stopped during the measurement\n");
    return 1;
  }

  // Real-time factor over the window and in one-second windows; wall time between ticks.
  const double rtf = (clock.back().second - clock.front().second) / (clock.back().first - clock.front().first);
  std::vector<double> window_rtf;
  std::size_t from = 0;
  for (std::size_t k = 1; k < clock.size(); ++k)
    if (clock[k].first - clock[from].first >= 1.0)
    {
      window_rtf.push_back((clock[k].second - clock[from].second) / (clock[k].first - clock[from].first));
      from = k;
    }
  std::vector<double> tick_ms;
  for (std::size_t k = 1; k < clock.size(); ++k)
    tick_ms.push_back(1e3 * (clock[k].first - clock[k - 1].first));

  // What each spring body's integrator ran, from one ~status.
  std::string integrators;
  const auto status =
      ros::topic::waitForMessage<particle_sim::SimStatus>(options.node + "/status", nh, ros::Duration(5.0));
  if (status)
    for (const auto& body : status->bodies)
      if (!body.last_integrator.empty())
        integrators += (integrators.empty() ? "" : "; ") + body.name + ": " + body.last_integrator + " " +
                       std::to_string(body.substeps) + " substeps" +
                       (body.linear_solver.empty() ? "" : " " + body.linear_solver) +
                       (body.auto_choice.empty() ? "" : " (auto: " + body.auto_choice + ")");
  std::replace(integrators.begin(), integrators.end(), '\n', ' ');

  std::ostringstream line;
  line << "rtf=" << rtf
       << " rtf_window_min=" << (window_rtf.empty() ? rtf : *std::min_element(window_rtf.begin(), window_rtf.end()))
       << " rtf_window_max=" << (window_rtf.empty() ? rtf : *std::max_element(window_rtf.begin(), window_rtf.end()))
       << " tick_ms_min=" << *std::min_element(tick_ms.begin(), tick_ms.end()) << " tick_ms_median=" << median(tick_ms)
       << " tick_ms_max=" << *std::max_element(tick_ms.begin(), tick_ms.end());
  const char* names[3] = {"markers", "meshes", "points"};
  const bool wanted[3] = {markers, meshes, points};
  for (int t = 0; t < 3; ++t)
    if (wanted[t])
      line << " " << names[t] << "_hz=" << messages[t] / window << " " << names[t]
           << "_points=" << (messages[t] ? points_per_topic[t] / messages[t] : 0);
  line << " integrators=" << (integrators.empty() ? "-" : integrators);
  std::printf("%s\n", line.str().c_str());
  spinner.stop();
  return 0;
}
