#pragma once

#include <geometry_msgs/WrenchStamped.h>
#include <ros/time.h>

#include <Eigen/Geometry>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "particle_sim/Grasp.h"
#include "particle_sim/GraspStatus.h"
#include "particle_sim/core/capture.h"
#include "particle_sim/core/status.h"
#include "particle_sim/core/world.h"

namespace particle_sim
{
namespace ros_interface
{
/// A ~grasp request, checked: what to capture, in which frame, and when to let go by itself.
struct GraspSpec
{
  std::string name;
  std::string body;  ///< empty = every spring body
  std::string frame;
  core::CaptureRegion region;
  double breakaway_force = 0.0;  ///< [N]; 0 = never
};

/// The request as a GraspSpec; a refusal names the field, its value and what is allowed.
core::Status toGraspSpec(const Grasp::Request& req, GraspSpec& spec);

/// A grasp and what it holds: per body, the captured particles and their places in the frame.
struct GraspState
{
  struct Hold
  {
    std::string body;
    std::vector<core::CapturedParticle> particles;
  };
  GraspSpec spec;
  std::vector<Hold> holds;
  Eigen::Isometry3d frame_pose = Eigen::Isometry3d::Identity();  ///< the gripper's last known pose in the sim frame
  Eigen::Vector3d force = Eigen::Vector3d::Zero();   ///< [N] Σ pin reactions of the held particles (sim frame)
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();  ///< [N·m] about the frame's origin (sim frame)
  bool released = false;                             ///< let go by itself (breakaway)
  double released_at = 0.0;                          ///< [s] sim time
  std::string release_reason;
  int particleCount() const;
};

/// A particle let go by a grasp: the node's frame followers drop it.
using HeldParticle = std::pair<std::string, int>;  // body, index

/// Every grasp of the node: capture, release, breakaway and the forces, on a world the caller owns.
/// The particles a grasp holds are pinned in the world where they were caught; the caller makes
/// them follow the frame at their offsets (FrameFollowers), so they keep their places in it.
class Grasps
{
public:
  /// Captures what `spec` names with the gripper at `frame_pose` and pins it. Refused (nothing
  /// changes) when the name is held by an active grasp, the body is unknown, or nothing is caught.
  /// A grasp that broke away under the same name is replaced.
  core::Status grasp(core::World& world, const GraspSpec& spec, const Eigen::Isometry3d& frame_pose);
  /// Lets go of grasp `name` (its particles are unpinned, listed in `let_go`) and forgets it.
  core::Status release(core::World& world, const std::string& name, std::vector<HeldParticle>& let_go);
  /// After a tick's steps: each active grasp's force and torque about its frame's origin (`pose_of`
  /// gives the frame's pose, or false to keep the last one), and a grasp whose force exceeds its
  /// breakaway force lets go at once (released, with the reason; its particles in `let_go`).
  /// Returns the names of the grasps that broke away now.
  std::vector<std::string> update(core::World& world,
                                  const std::function<bool(const std::string&, Eigen::Isometry3d&)>& pose_of,
                                  double sim_time, std::vector<HeldParticle>& let_go);
  /// A particle pinned or unpinned by a service is no longer held by any grasp.
  void forgetParticle(const std::string& body, int index);
  /// A removed body: grasps drop its particles; a grasp left with none is forgotten.
  void forgetBody(const std::string& body);
  void clear() { grasps_.clear(); }
  const std::vector<GraspState>& all() const { return grasps_; }
  const GraspState* find(const std::string& name) const;

private:
  std::vector<GraspState> grasps_;
};

/// A grasp in ~status.
GraspStatus toGraspStatus(const GraspState& grasp);

/// The wrench a grasp's gripper exerts on what it holds, in the gripper frame (header.frame_id =
/// the frame) about its origin: R⁻¹ force and R⁻¹ torque, R the frame's rotation in the sim frame.
geometry_msgs::WrenchStamped buildGraspWrench(const GraspState& grasp, const ros::Time& stamp);

}  // namespace ros_interface
}  // namespace particle_sim
