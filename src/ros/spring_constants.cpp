#include "particle_sim/ros/spring_constants.h"

#include <optional>

#include "particle_sim/ros/message_text.h"
#include "particle_sim/ros/request_conversions.h"
#include "particle_sim/ros/status_report.h"

namespace particle_sim
{
namespace ros_interface
{
core::Status applySpringConstants(core::World& world, const std::string& body_name, const std::string& class_name,
                                  double stiffness, double damping)
{
  core::SpringNetworkBody* body = world.findSpringBody(body_name);
  if (!body)
    return core::Status::failure("body = " + quoteName(body_name) + ": no rope or spring network has that name");
  std::optional<core::SpringClass> spring_class;
  if (core::Status s = parseSpringClassSelection(class_name, spring_class); !s) return s;
  core::Status status = body->setSpringConstants(spring_class, stiffness, damping);
  if (status) status.message = springConstantsReport(*body, body_name, class_name, stiffness, damping, world);
  return status;
}

bool readSpringConstants(const core::World& world, const std::string& body_name, const std::string& class_name,
                         double& stiffness, double& damping)
{
  const core::SpringNetworkBody* body = world.findSpringBody(body_name);
  if (!body) return false;
  core::SpringClass spring_class = core::SpringClass::Stretch;
  const bool any = class_name == "all";
  if (!any && !core::parseSpringClass(class_name, spring_class)) return false;
  // A Baraff–Witkin cloth has conditions, not springs: show those of the class (stretch for "all").
  if (const core::BaraffWitkinModel* model = body->baraffWitkin())
  {
    stiffness = model->constants(spring_class).stiffness;
    damping = model->constants(spring_class).damping;
    return true;
  }
  for (const core::Spring& spring : body->springs())
  {
    if (!any && spring.spring_class != spring_class) continue;
    stiffness = spring.stiffness;
    damping = spring.damping;
    return true;
  }
  return false;
}

}  // namespace ros_interface
}  // namespace particle_sim
