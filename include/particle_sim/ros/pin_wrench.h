#pragma once

#include <geometry_msgs/WrenchStamped.h>
#include <ros/time.h>

#include <string>

#include "particle_sim/core/spring_network.h"

namespace particle_sim
{
namespace ros_interface
{
/// The topic, relative to the node's private namespace, that carries the wrench of `body`'s pins:
/// "pin_wrench/" and the body name made a valid ROS name ('-' becomes '_', and a name segment that
/// does not start with a letter gets a leading 'b'). Two body names can map to one topic
/// ("a-b", "a_b"); the node then publishes only the first body's.
std::string pinWrenchTopic(const std::string& body_name);
/// The topic of a grasp's wrench (~grasp): "grasp_wrench/" and its name, made valid the same way.
std::string graspWrenchTopic(const std::string& grasp_name);

/// What a body's pins exert on it as one wrench in `frame_id` (the sim frame), about that frame's
/// origin: force = Σ r_i [N], torque = Σ x_i × r_i [N·m] over its pinned particles, with r_i the
/// reaction that holds pinned particle i on its course against the springs, gravity, damping and
/// its own inertia (SpringNetworkBody::pinLoad). About another point p: torque − p × force.
geometry_msgs::WrenchStamped buildPinWrench(const core::SpringNetworkBody& body, const ros::Time& stamp,
                                            const std::string& frame_id);

}  // namespace ros_interface
}  // namespace particle_sim
