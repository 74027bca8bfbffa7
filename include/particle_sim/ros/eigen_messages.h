#pragma once

#include <geometry_msgs/Point.h>
#include <geometry_msgs/Vector3.h>

#include <Eigen/Core>

namespace particle_sim
{
namespace ros_interface
{
/// Vectors and points between geometry_msgs and Eigen, component by component.
inline Eigen::Vector3d toEigen(const geometry_msgs::Point& p)
{
  return {p.x, p.y, p.z};
}

inline Eigen::Vector3d toEigen(const geometry_msgs::Vector3& v)
{
  return {v.x, v.y, v.z};
}

inline geometry_msgs::Vector3 toVector3(const Eigen::Ref<const Eigen::Vector3d>& v)
{
  geometry_msgs::Vector3 out;
  out.x = v.x();
  out.y = v.y();
  out.z = v.z();
  return out;
}

inline geometry_msgs::Point toPoint(const Eigen::Ref<const Eigen::Vector3d>& x)
{
  geometry_msgs::Point out;
  out.x = x.x();
  out.y = x.y();
  out.z = x.z();
  return out;
}

}  // namespace ros_interface
}  // namespace particle_sim
