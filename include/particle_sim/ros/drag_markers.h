#pragma once

#include <interactive_markers/interactive_marker_server.h>
#include <ros/node_handle.h>

#include <chrono>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "particle_sim/core/world.h"
#include "particle_sim/ros/dragging.h"

namespace particle_sim
{
namespace ros_interface
{
/// Most particles drawn in one body's drag marker (every k-th beyond); any of the body's free
/// particles can still be dragged: the click picks the nearest.
constexpr int kMaxDragMarkerPoints = 2000;
/// Wall time [s] between two refreshes of the drag markers' particles while rviz shows them.
constexpr double kDragMarkerRefreshPeriod = 0.2;

/// Dragging particles in rviz (~drag, interactive markers): one interactive marker per spring body,
/// drawn as its particles, with a free 3-D move control. Mouse down on it pins the body's free
/// particle nearest the click (a temporary grasp), moving the marker moves that pin, mouse up lets
/// go (Dragging). The server runs its own thread; its feedback is queued and applied in the loop,
/// before a tick's steps.
class DragMarkers
{
public:
  /// Serves on `<private namespace>/drag` (update, update_full, feedback), markers in `frame_id`.
  DragMarkers(const ros::NodeHandle& private_node, const std::string& frame_id, double particle_size);
  /// Stops the server's thread first: it calls back into this object.
  ~DragMarkers();
  /// Before a tick's steps: applies the queued mouse events, keeps one marker per spring body and
  /// refreshes their particles at most every kDragMarkerRefreshPeriod while someone subscribes.
  void beginTick(core::World& world);
  /// A body removed, or every body after ~reset: a drag of it ends.
  void forgetBody(const std::string& body);
  void forgetAll();

private:
  visualization_msgs::InteractiveMarker bodyMarker(const core::SpringNetworkBody& body) const;
  void feedback(const visualization_msgs::InteractiveMarkerFeedbackConstPtr& feedback);
  /// The world's spring bodies are those with a marker (names unique, so counting suffices).
  bool sameBodies(const core::World& world) const;

  std::string frame_id_;
  double particle_size_;
  std::unique_ptr<interactive_markers::InteractiveMarkerServer> server_;
  ros::Publisher update_listeners_;  // the server's update topic: who listens (the same publication)
  std::mutex events_mutex_;
  std::vector<DragEvent> events_;  // from the server's thread
  Dragging dragging_;
  std::set<std::string> shown_;  // bodies with a marker
  std::chrono::steady_clock::time_point last_refresh_;
};

}  // namespace ros_interface
}  // namespace particle_sim
