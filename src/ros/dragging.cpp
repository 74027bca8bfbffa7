#include "particle_sim/ros/dragging.h"

#include <limits>

#include "particle_sim/ros/message_text.h"

namespace particle_sim
{
namespace ros_interface
{
std::string Dragging::apply(core::World& world, const DragEvent& event)
{
  switch (event.type)
  {
    case DragEvent::Type::Down: {
      release(world);  // a second button down without an up: the first drag ends
      core::SpringNetworkBody* body = world.findSpringBody(event.body);
      if (!body) return "";
      // The free particle nearest the click (or the marker, when the click has no point).
      const Eigen::Vector3d click = event.has_mouse_point ? event.mouse_point : event.marker_position;
      const core::ParticlePool& p = body->particles();
      int nearest = -1;
      double best = std::numeric_limits<double>::infinity();
      for (int i = 0; i < p.size(); ++i)
      {
        if (body->isPinned(i)) continue;
        const double d = (p.position.col(i) - click).squaredNorm();
        if (d < best)
        {
          best = d;
          nearest = i;
        }
      }
      if (nearest < 0) return "";
      start_particle_ = p.position.col(nearest);
      start_marker_ = event.marker_position;
      if (!body->pin(nearest, start_particle_)) return "";
      body_ = event.body;
      index_ = nearest;
      return "dragging particle " + std::to_string(nearest) + " of " + quoteName(body_);
    }
    case DragEvent::Type::Move: {
      if (!active() || event.body != body_) return "";
      core::SpringNetworkBody* body = world.findSpringBody(body_);
      if (!body) return "";
      body->setPinTarget(index_, start_particle_ + (event.marker_position - start_marker_));
      return "";
    }
    case DragEvent::Type::Up: {
      if (!active() || event.body != body_) return "";
      const std::string text = "let go of particle " + std::to_string(index_) + " of " + quoteName(body_);
      release(world);
      return text;
    }
  }
  return "";
}

void Dragging::release(core::World& world)
{
  if (!active()) return;
  if (core::SpringNetworkBody* body = world.findSpringBody(body_)) body->unpin(index_);
  body_.clear();
  index_ = -1;
}

void Dragging::forget(const std::string& body)
{
  if (body == body_)
  {
    body_.clear();
    index_ = -1;
  }
}

}  // namespace ros_interface
}  // namespace particle_sim
