#include "particle_sim/ros/pin_wrench.h"

#include <algorithm>
#include <cctype>

#include "particle_sim/ros/eigen_messages.h"

namespace particle_sim
{
namespace ros_interface
{
namespace
{
// `prefix` and then `name` made a valid ROS name. Body and grasp names allow letters, digits, '_',
// '-' and '/' (core/names.cpp); a ROS name's segments start with a letter and go on with letters,
// digits and '_'. Empty segments are dropped.
std::string topicFor(const char* prefix, const std::string& body_name)
{
  std::string topic = prefix;
  std::size_t segments = 0;
  for (std::size_t at = 0; at < body_name.size();)
  {
    const std::size_t end = std::min(body_name.find('/', at), body_name.size());
    if (end > at)
    {
      topic += '/';
      if (!std::isalpha(static_cast<unsigned char>(body_name[at]))) topic += 'b';
      for (std::size_t k = at; k < end; ++k)
        topic += body_name[k] == '-' ? '_' : body_name[k];
      ++segments;
    }
    at = end + 1;
  }
  if (segments == 0) topic += "/b";  // no name at all (never a valid body name)
  return topic;
}
}  // namespace

std::string pinWrenchTopic(const std::string& body_name)
{
  return topicFor("pin_wrench", body_name);
}

std::string graspWrenchTopic(const std::string& grasp_name)
{
  return topicFor("grasp_wrench", grasp_name);
}

geometry_msgs::WrenchStamped buildPinWrench(const core::SpringNetworkBody& body, const ros::Time& stamp,
                                            const std::string& frame_id)
{
  const core::SpringNetworkBody::PinLoad load = body.pinLoad({}, Eigen::Vector3d::Zero());
  geometry_msgs::WrenchStamped wrench;
  wrench.header.stamp = stamp;
  wrench.header.frame_id = frame_id;
  wrench.wrench.force = toVector3(load.force);
  wrench.wrench.torque = toVector3(load.torque);
  return wrench;
}

}  // namespace ros_interface
}  // namespace particle_sim
