#include <ros/ros.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstring>

#include "particle_sim/process/huge_pages.h"
#include "particle_sim/ros/sim_node.h"

namespace
{
/// What `particle_sim_node --help` prints: how to run it and where its interface is described.
constexpr const char* kUsage =
    "usage: rosrun particle_sim particle_sim_node [_scene:=FILE] [_rate:=HZ] [_dt:=S] [_real_time_factor:=F]\n"
    "                                             [_paused:=true] [_frame_id:=NAME] [ROS remappings ...]\n"
    "The particle_sim simulator node: steps the scene and publishes ~markers, ~meshes, ~status, /tf,\n"
    "/clock and /diagnostics; services ~spawn_emitter, ~spawn_rope, ~spawn_cloth, ~spawn_jelly,\n"
    "~remove_body, ~reset, ~pause_physics, ~unpause_physics, ~step, ~pin_particle, ~unpin_particle,\n"
    "~set_wind, ~set_spring_constants; live parameters through dynamic_reconfigure.\n"
    "Needs a ROS master. Usually started by: roslaunch particle_sim particle_sim.launch scene:=NAME\n"
    "Every parameter, topic and service: README.md, section \"The node: particle_sim_node\".\n";

/// The node whose loop runs, for the signal handler; null before and after.
std::atomic<particle_sim::ros_interface::SimNode*> g_running_node{nullptr};

/// SIGINT and SIGTERM end the loop (an atomic store, async-signal-safe) while ROS is still up, so
/// that a ~step client gets its answer and every handle is released before ros::shutdown(); roscpp's
/// own SIGINT handler would shut ROS down first, dropping the client's connection, and SIGTERM
/// would kill the node on the spot. Before the loop runs (start-up), they ask roscpp to shut down.
void endOnSignal(int /*signal*/)
{
  if (particle_sim::ros_interface::SimNode* node = g_running_node.load())
    node->stop();
  else
    ros::requestShutdown();
}
}  // namespace

int main(int argc, char** argv)
{
  particle_sim::process::restartWithHugePagesIfAdvised(argv);
  for (int i = 1; i < argc; ++i)
  {
    if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0)
    {
      std::fputs(kUsage, stdout);
      return 0;
    }
  }
  ros::init(argc, argv, "particle_sim", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, endOnSignal);
  std::signal(SIGTERM, endOnSignal);
  particle_sim::ros_interface::SimNode node(ros::NodeHandle(), ros::NodeHandle("~"), ros::this_node::getName());
  if (!node.initialize()) return 1;
  g_running_node = &node;
  node.run();
  g_running_node = nullptr;
  ros::shutdown();
  return 0;
}
