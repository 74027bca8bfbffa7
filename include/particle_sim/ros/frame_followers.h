#pragma once

#include <geometry_msgs/TransformStamped.h>
#include <ros/time.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "particle_sim/core/world.h"
#include "particle_sim/scene/scene.h"

namespace particle_sim
{
namespace ros_interface
{
/// A tf frame followed by a pin or a sphere whose latest transform has not changed for this long
/// [s of wall time] is taken as gone: the pin or sphere holds still and the node warns (throttled).
/// Static frames never age.
constexpr double kFramePinTimeout = 1.0;

/// What follows tf frames: particles pinned to a frame (from ~pin_particle or the scene) and
/// sphere colliders that follow a frame the scene does not script. Frames are looked up without
/// waiting, from what tf's listener (on its own thread) already knows, in `sim_frame`.
class FrameFollowers
{
public:
  /// Starts listening to tf: a frame known to tf from then on is known here, and looked up in
  /// `sim_frame`.
  void startListening(const std::string& sim_frame);
  /// Stops listening and lets go of tf (in the thread that runs ROS).
  void stopListening();
  /// The scene's scripted frames are known exactly, not through tf: a lookup of one answers its
  /// pose at `sim_time()` [s], and a particle pinned to one is put where the frame is at the end of
  /// each step, as the scene's own frame pins are. (Through tf, the node's own broadcast came back
  /// one or two ticks late, by how the messages happened to arrive: a grasped cloth was jerked
  /// along.) `scene` must outlive this object.
  void useScriptedFrames(const scene::SceneDef& scene, std::function<double()> sim_time);

  /// `offset` [m] in `frame` as a point [m] of the sim frame, from the frame's latest transform
  /// (its `stamp`; a scripted frame's exact pose now); false with the reason in `error` when tf does
  /// not know it (or it is not finite). Never waits.
  bool lookup(const std::string& frame, const Eigen::Vector3d& offset, Eigen::Vector3d& point, ros::Time& stamp,
              std::string& error) const;
  /// The pose of `frame` in the sim frame (x_sim = pose · x_frame), from its latest transform; false
  /// with the reason in `error` as for lookup(). Never waits.
  bool lookupPose(const std::string& frame, Eigen::Isometry3d& pose, ros::Time& stamp, std::string& error) const;

  /// Particle `index` of `body`, pinned, follows `frame` at `offset` [m] from the next tick on,
  /// instead of any frame it followed before.
  void follow(const std::string& body, int index, const std::string& frame, const Eigen::Vector3d& offset);
  /// Particle `index` of `body` follows no frame any more.
  void unfollow(const std::string& body, int index);
  /// No particle of `body` follows a frame any more.
  void forgetBody(const std::string& body);

  /// Before a tick's steps: drops pins whose body or pin is gone, looks every followed frame up
  /// (a frame not available holds its particles still, with a warning) and moves the spheres that
  /// follow frames the scene does not script; boxes and capsules that do get this tick's goal.
  void beginTick(core::World& world, const scene::SceneDef& scene);
  /// Before step `step` (0-based) of the tick's `steps`: particles pinned to frames, and boxes and
  /// capsules following tf frames, move in equal parts from where they were towards this tick's
  /// frame pose (orientations by slerp), so that a collider's velocity is its frame's; particles
  /// pinned to a scripted frame go where it is at the end of the step.
  void moveTargets(core::World& world, std::uint64_t step, std::uint64_t steps) const;

private:
  /// When a followed frame's transform last changed.
  struct FrameAge
  {
    ros::Time stamp;                                                                   // of the latest transform seen
    std::chrono::steady_clock::time_point updated = std::chrono::steady_clock::now();  // when it changed
  };
  struct FramePin
  {
    std::string body;
    int index = 0;
    std::string frame;
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
    FrameAge age;
    const scene::ScriptedFrameDef* scripted = nullptr;  // the scene's frame of that name, this tick
  };
  /// Records the transform's `stamp` in `age`; false, with the reason in `error`, when a
  /// non-static frame's transform has not changed for more than kFramePinTimeout.
  static bool stillFresh(FrameAge& age, const ros::Time& stamp, std::chrono::steady_clock::time_point now,
                         std::string& error);
  void updateFramePins(core::World& world);
  void updateFrameSpheres(core::World& world, const scene::SceneDef& scene);
  void updateFrameColliders(const core::World& world, const scene::SceneDef& scene);

  std::string sim_frame_;
  const scene::SceneDef* scene_ = nullptr;  // scripted frames (useScriptedFrames)
  std::function<double()> sim_time_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::vector<FramePin> pins_;
  std::map<std::string, FrameAge> sphere_frames_;  // per sphere that follows a tf frame
  std::vector<Eigen::Vector3d> start_, goal_;      // per pin, this tick
  // A box or capsule following a tf frame: where it was at the start of this tick and where its
  // frame is now.
  struct ColliderMove
  {
    std::string name;
    Eigen::Vector3d start_center, goal_center;
    Eigen::Quaterniond start_orientation, goal_orientation;
    FrameAge age;
  };
  std::vector<ColliderMove> collider_moves_;  // one per tf-followed collider, kept across ticks
};

/// The scene's scripted frames at `stamp` (sim time) as transforms under `sim_frame`, for tf.
std::vector<geometry_msgs::TransformStamped> scriptedFrameTransforms(const scene::SceneDef& scene,
                                                                     const std::string& sim_frame,
                                                                     const ros::Time& stamp);

}  // namespace ros_interface
}  // namespace particle_sim
