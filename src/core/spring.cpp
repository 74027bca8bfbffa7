#include "particle_sim/core/spring.h"

#include <algorithm>

namespace particle_sim
{
namespace core
{
const char* toString(SpringClass spring_class)
{
  switch (spring_class)
  {
    case SpringClass::Stretch:
      return "stretch";
    case SpringClass::Shear:
      return "shear";
    case SpringClass::Bend:
      return "bend";
  }
  return "unknown";
}

bool parseSpringClass(const std::string& text, SpringClass& spring_class)
{
  for (SpringClass candidate : {SpringClass::Stretch, SpringClass::Shear, SpringClass::Bend})
  {
    if (text == toString(candidate))
    {
      spring_class = candidate;
      return true;
    }
  }
  return false;
}

void springJacobians(const Eigen::Vector3d& xi, const Eigen::Vector3d& xj, double rest_length, double stiffness,
                     double damping, bool definite, Eigen::Matrix3d& dfdx, Eigen::Matrix3d& dfdv)
{
  const Eigen::Vector3d delta = xj - xi;
  const double length = delta.norm();
  if (length == 0.0)
  {
    // No direction: take the along-spring stiffness in every direction.
    dfdx = -stiffness * Eigen::Matrix3d::Identity();
    dfdv = -damping * Eigen::Matrix3d::Identity();
    return;
  }
  const Eigen::Vector3d d = delta / length;
  const Eigen::Matrix3d along = d * d.transpose();
  double transverse = 1.0 - rest_length / length;
  if (definite) transverse = std::max(transverse, 0.0);
  dfdx = -stiffness * (along + transverse * (Eigen::Matrix3d::Identity() - along));
  dfdv = -damping * along;
}

}  // namespace core
}  // namespace particle_sim
