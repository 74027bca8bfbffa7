#include <ros/ros.h>

#include "particle_sim/ros/sim_node.h"

int main(int argc, char** argv)
{
  ros::init(argc, argv, "particle_sim");
  particle_sim::ros_interface::SimNode node(ros::NodeHandle(), ros::NodeHandle("~"), ros::this_node::getName());
  if (!node.initialize()) return 1;
  node.run();
  return 0;
}
