#pragma once

#include <Eigen/Core>
#include <string>

#include "particle_sim/core/world.h"

namespace particle_sim
{
namespace ros_interface
{
/// One mouse event of rviz's interactive marker of a body (~drag): the mouse went down on it, the
/// marker moved, or the mouse came up.
struct DragEvent
{
  enum class Type
  {
    Down,
    Move,
    Up,
  };
  Type type = Type::Move;
  std::string body;                                           ///< the marker's name: the body's
  bool has_mouse_point = false;                               ///< Down: where the click hit the body
  Eigen::Vector3d mouse_point = Eigen::Vector3d::Zero();      ///< [m] sim frame
  Eigen::Vector3d marker_position = Eigen::Vector3d::Zero();  ///< [m] the marker's position (sim frame)
};

/// Dragging a particle with the mouse, as a temporary grasp: on Down, the free particle of the body
/// nearest the click is pinned where it is; while the marker moves, its target moves with it (by the
/// marker's displacement since Down); on Up it is let go with the velocity it has. One particle at a
/// time. Works on a world the caller owns; ROS-free, so that it is tested without rviz.
class Dragging
{
public:
  /// Applies one event; returns what happened, for the log ("" when nothing did).
  std::string apply(core::World& world, const DragEvent& event);
  /// The body is gone (removed or reset): nothing is dragged any more.
  void forget(const std::string& body);
  bool active() const { return index_ >= 0; }
  const std::string& body() const { return body_; }
  int index() const { return index_; }

private:
  void release(core::World& world);

  std::string body_;
  int index_ = -1;
  Eigen::Vector3d start_particle_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d start_marker_ = Eigen::Vector3d::Zero();
};

}  // namespace ros_interface
}  // namespace particle_sim
