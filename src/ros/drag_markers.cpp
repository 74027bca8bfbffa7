#include "particle_sim/ros/drag_markers.h"

#include <visualization_msgs/InteractiveMarkerUpdate.h>

#include "particle_sim/ros/eigen_messages.h"
#include "particle_sim/ros/marker_builder.h"

namespace particle_sim
{
namespace ros_interface
{
DragMarkers::DragMarkers(const ros::NodeHandle& private_node, const std::string& frame_id, double particle_size)
    : frame_id_(frame_id), particle_size_(particle_size)
{
  const std::string topic_ns = private_node.resolveName("drag");
  server_ = std::make_unique<interactive_markers::InteractiveMarkerServer>(topic_ns, "", true);
  // A second publisher of the server's own update topic shares its publication: its subscriber
  // count says whether rviz (or anyone) shows the markers.
  ros::NodeHandle node;
  update_listeners_ = node.advertise<visualization_msgs::InteractiveMarkerUpdate>(topic_ns + "/update", 100);
}

DragMarkers::~DragMarkers()
{
  server_.reset();
}

void DragMarkers::feedback(const visualization_msgs::InteractiveMarkerFeedbackConstPtr& feedback)
{
  using visualization_msgs::InteractiveMarkerFeedback;
  DragEvent event;
  switch (feedback->event_type)
  {
    case InteractiveMarkerFeedback::MOUSE_DOWN:
      event.type = DragEvent::Type::Down;
      break;
    case InteractiveMarkerFeedback::POSE_UPDATE:
      event.type = DragEvent::Type::Move;
      break;
    case InteractiveMarkerFeedback::MOUSE_UP:
      event.type = DragEvent::Type::Up;
      break;
    default:
      return;
  }
  event.body = feedback->marker_name;
  event.has_mouse_point = feedback->mouse_point_valid;
  event.mouse_point = {feedback->mouse_point.x, feedback->mouse_point.y, feedback->mouse_point.z};
  event.marker_position = {feedback->pose.position.x, feedback->pose.position.y, feedback->pose.position.z};
  std::lock_guard<std::mutex> lock(events_mutex_);
  events_.push_back(event);
}

visualization_msgs::InteractiveMarker DragMarkers::bodyMarker(const core::SpringNetworkBody& body) const
{
  // The marker sits at the sim frame's origin (its pose is the drag's displacement) and is drawn
  // as the body's particles, every k-th beyond kMaxDragMarkerPoints.
  visualization_msgs::InteractiveMarker marker;
  marker.header.frame_id = frame_id_;
  marker.name = body.name();
  marker.description = "drag a particle of " + body.name();
  marker.pose.orientation.w = 1.0;
  marker.scale = 0.2f;
  visualization_msgs::Marker points;
  points.type = visualization_msgs::Marker::SPHERE_LIST;
  points.pose.orientation.w = 1.0;
  points.scale.x = points.scale.y = points.scale.z = 1.5 * particle_size_;
  points.color.r = points.color.g = points.color.b = 1.0f;
  points.color.a = 0.25f;  // see-through: the body's own markers stay visible
  const core::ParticlePool& p = body.particles();
  const int stride = decimationStride(p.size(), kMaxDragMarkerPoints);
  for (int i = 0; i < p.size(); i += stride)
  {
    if (p.position.col(i).allFinite()) points.points.push_back(toPoint(p.position.col(i)));
  }
  visualization_msgs::InteractiveMarkerControl control;
  control.interaction_mode = visualization_msgs::InteractiveMarkerControl::MOVE_3D;
  control.always_visible = true;
  control.orientation.w = 1.0;
  if (!points.points.empty()) control.markers.push_back(points);
  marker.controls.push_back(control);
  return marker;
}

void DragMarkers::beginTick(core::World& world)
{
  // The mouse events since the last tick, in order.
  std::vector<DragEvent> events;
  {
    std::lock_guard<std::mutex> lock(events_mutex_);
    events.swap(events_);
  }
  bool changed = false;
  for (const DragEvent& event : events)
  {
    const std::string text = dragging_.apply(world, event);
    if (!text.empty()) ROS_INFO_NAMED("drag", "%s", text.c_str());
    if (event.type == DragEvent::Type::Up)
    {
      // Back at the origin, where the drawn particles are in the sim frame.
      geometry_msgs::Pose origin;
      origin.orientation.w = 1.0;
      server_->setPose(event.body, origin);
      changed = true;
    }
  }

  // One marker per spring body: new bodies get one, removed bodies lose theirs. A tick with no
  // event, no refresh due and the same bodies as shown does nothing (and allocates nothing).
  const auto now = std::chrono::steady_clock::now();
  const bool refresh = update_listeners_.getNumSubscribers() > 0 &&
                       std::chrono::duration<double>(now - last_refresh_).count() >= kDragMarkerRefreshPeriod;
  if (!changed && !refresh && sameBodies(world)) return;
  std::set<std::string> bodies;
  for (const auto& body : world.bodies())
  {
    if (body->kind() != core::BodyKind::SpringNetwork) continue;
    bodies.insert(body->name());
    const bool dragged = dragging_.active() && dragging_.body() == body->name();
    if (!shown_.count(body->name()) || (refresh && !dragged))
    {
      server_->insert(bodyMarker(static_cast<const core::SpringNetworkBody&>(*body)),
                      [this](const visualization_msgs::InteractiveMarkerFeedbackConstPtr& f) { feedback(f); });
      changed = true;
    }
  }
  for (const std::string& name : shown_)
  {
    if (bodies.count(name)) continue;
    server_->erase(name);
    dragging_.forget(name);
    changed = true;
  }
  shown_.swap(bodies);
  if (refresh) last_refresh_ = now;
  if (changed) server_->applyChanges();
}

bool DragMarkers::sameBodies(const core::World& world) const
{
  std::size_t count = 0;
  for (const auto& body : world.bodies())
  {
    if (body->kind() != core::BodyKind::SpringNetwork) continue;
    if (!shown_.count(body->name())) return false;
    ++count;
  }
  return count == shown_.size();
}

void DragMarkers::forgetBody(const std::string& body)
{
  dragging_.forget(body);
}

void DragMarkers::forgetAll()
{
  dragging_.forget(dragging_.body());
}

}  // namespace ros_interface
}  // namespace particle_sim
