#include "particle_sim/ros/frame_followers.h"

#include <ros/console.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "particle_sim/ros/message_text.h"

namespace particle_sim
{
namespace ros_interface
{
void FrameFollowers::startListening(const std::string& sim_frame)
{
  sim_frame_ = sim_frame;
  tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_);
}

void FrameFollowers::stopListening()
{
  tf_listener_.reset();
  tf_buffer_.reset();
}

bool FrameFollowers::lookup(const std::string& frame, const Eigen::Vector3d& offset, Eigen::Vector3d& point,
                            ros::Time& stamp, std::string& error) const
{
  Eigen::Isometry3d pose;
  if (!lookupPose(frame, pose, stamp, error)) return false;
  point = pose * offset;
  return true;
}

void FrameFollowers::useScriptedFrames(const scene::SceneDef& scene, std::function<double()> sim_time)
{
  scene_ = &scene;
  sim_time_ = std::move(sim_time);
}

bool FrameFollowers::lookupPose(const std::string& frame, Eigen::Isometry3d& pose, ros::Time& stamp,
                                std::string& error) const
{
  // A scripted frame: where the scene puts it now (it does not turn).
  if (const scene::ScriptedFrameDef* scripted = scene_ ? scene::findFrame(*scene_, frame) : nullptr)
  {
    const double now = sim_time_();
    pose = Eigen::Isometry3d::Identity();
    pose.translation() = scripted->position(now);
    stamp = ros::Time(now);
    return true;
  }
  if (!tf_buffer_->canTransform(sim_frame_, frame, ros::Time(0), &error)) return false;
  try
  {
    const geometry_msgs::TransformStamped t = tf_buffer_->lookupTransform(sim_frame_, frame, ros::Time(0));
    const auto& q = t.transform.rotation;
    const auto& v = t.transform.translation;
    const Eigen::Quaterniond rotation(q.w, q.x, q.y, q.z);
    const Eigen::Vector3d translation(v.x, v.y, v.z);
    if (!rotation.coeffs().allFinite() || rotation.norm() == 0.0 || !translation.allFinite())
    {
      error = "its transform is not finite";
      return false;
    }
    pose = Eigen::Isometry3d::Identity();
    pose.linear() = rotation.normalized().toRotationMatrix();
    pose.translation() = translation;
    stamp = t.header.stamp;
    return true;
  }
  catch (const tf2::TransformException& exception)
  {
    error = exception.what();
    return false;
  }
}

void FrameFollowers::follow(const std::string& body, int index, const std::string& frame, const Eigen::Vector3d& offset)
{
  unfollow(body, index);
  pins_.push_back({body, index, frame, offset, FrameAge()});
}

void FrameFollowers::unfollow(const std::string& body, int index)
{
  // A particle follows at most one frame.
  pins_.erase(
      std::remove_if(pins_.begin(), pins_.end(), [&](const FramePin& p) { return p.body == body && p.index == index; }),
      pins_.end());
}

void FrameFollowers::forgetBody(const std::string& body)
{
  for (std::size_t k = pins_.size(); k-- > 0;)
  {
    if (pins_[k].body == body) pins_.erase(pins_.begin() + static_cast<std::ptrdiff_t>(k));
  }
}

void FrameFollowers::beginTick(core::World& world, const scene::SceneDef& scene)
{
  updateFramePins(world);
  updateFrameSpheres(world, scene);
  updateFrameColliders(world, scene);
}

void FrameFollowers::moveTargets(core::World& world, std::uint64_t step, std::uint64_t steps) const
{
  // Particles pinned to tf frames move in equal parts towards this tick's frame pose; those pinned
  // to a scripted frame go where it is at the end of this step.
  for (std::size_t k = 0; k < pins_.size(); ++k)
  {
    const double s = static_cast<double>(step + 1) / static_cast<double>(steps);
    const FramePin& pin = pins_[k];
    const Eigen::Vector3d target =
        pin.scripted ? Eigen::Vector3d(pin.scripted->position(world.simTime() + world.dt()) + pin.offset)
                     : Eigen::Vector3d(start_[k] + s * (goal_[k] - start_[k]));
    world.findSpringBody(pin.body)->setPinTarget(pin.index, target);
  }
  // Boxes and capsules likewise, one step's worth of their frame's motion at a time.
  for (const ColliderMove& move : collider_moves_)
  {
    if (move.name.empty()) continue;
    const double s = static_cast<double>(step + 1) / static_cast<double>(steps);
    world.setColliderPose(move.name, move.start_center + s * (move.goal_center - move.start_center),
                          move.start_orientation.slerp(s, move.goal_orientation), world.dt());
  }
}

void FrameFollowers::updateFramePins(core::World& world)
{
  // Forget pins whose body was removed or whose particle was unpinned or reset.
  pins_.erase(std::remove_if(pins_.begin(), pins_.end(),
                             [&](const FramePin& pin) {
                               const core::SpringNetworkBody* body = world.findSpringBody(pin.body);
                               return !body || !body->isPinned(pin.index);
                             }),
              pins_.end());
  start_.resize(pins_.size());
  goal_.resize(pins_.size());
  const auto now = std::chrono::steady_clock::now();
  for (std::size_t k = 0; k < pins_.size(); ++k)
  {
    FramePin& pin = pins_[k];
    start_[k] = world.findSpringBody(pin.body)->pinTarget(pin.index);
    pin.scripted = scene_ ? scene::findFrame(*scene_, pin.frame) : nullptr;
    if (pin.scripted) continue;  // placed step by step (moveTargets)
    std::string error;
    ros::Time stamp;
    const bool available =
        lookup(pin.frame, pin.offset, goal_[k], stamp, error) && stillFresh(pin.age, stamp, now, error);
    if (!available)
    {
      goal_[k] = start_[k];  // hold still until the frame is back
      ROS_WARN_THROTTLE_NAMED(5.0, "pins",
                              "particle %d of %s follows frame %s, which is not available: %s; it holds still",
                              pin.index, quoteName(pin.body).c_str(), quoteName(pin.frame).c_str(), error.c_str());
    }
  }
}

bool FrameFollowers::stillFresh(FrameAge& age, const ros::Time& stamp, std::chrono::steady_clock::time_point now,
                                std::string& error)
{
  // A frame whose transform stopped changing is gone (tf keeps its last transform for ever);
  // a static frame (stamp 0) never goes.
  if (stamp != age.stamp)
  {
    age.stamp = stamp;
    age.updated = now;
    return true;
  }
  const double unchanged = std::chrono::duration<double>(now - age.updated).count();
  if (stamp.isZero() || unchanged <= kFramePinTimeout) return true;
  error = "no new transform for " + formatReceived(std::round(unchanged)) + " s";
  return false;
}

void FrameFollowers::updateFrameSpheres(core::World& world, const scene::SceneDef& scene)
{
  const auto now = std::chrono::steady_clock::now();
  for (const scene::FrameSphereDef& follower : scene.frame_spheres)
  {
    if (scene::findFrame(scene, follower.frame)) continue;  // scripted: applied every step
    Eigen::Vector3d center;
    std::string error;
    ros::Time stamp;
    // A sphere whose frame is not available (unknown, or its transform stopped) holds still.
    if (lookup(follower.frame, Eigen::Vector3d::Zero(), center, stamp, error) &&
        stillFresh(sphere_frames_[follower.sphere], stamp, now, error))
      world.setSphereCenter(follower.sphere, center);
    else
      ROS_WARN_THROTTLE_NAMED(5.0, "colliders",
                              "sphere %s follows frame %s, which is not available: %s; it holds still",
                              quoteName(follower.sphere).c_str(), quoteName(follower.frame).c_str(), error.c_str());
  }
}

void FrameFollowers::updateFrameColliders(const core::World& world, const scene::SceneDef& scene)
{
  const auto now = std::chrono::steady_clock::now();
  std::size_t k = 0;
  for (const scene::FrameColliderDef& follower : scene.frame_colliders)
  {
    if (scene::findFrame(scene, follower.frame)) continue;  // scripted: applied every step
    if (k == collider_moves_.size()) collider_moves_.emplace_back();
    ColliderMove& move = collider_moves_[k++];
    if (move.name != follower.collider)  // a new follower (or the list changed under ~remove_collider)
    {
      move.name = follower.collider;
      move.age = FrameAge();
    }
    if (!world.colliderPose(follower.collider, move.start_center, move.start_orientation))
    {
      move.name.clear();  // no such collider: nothing to move
      continue;
    }
    move.goal_center = move.start_center;
    move.goal_orientation = move.start_orientation;
    // A collider whose frame is not available (unknown, or its transform stopped) holds still.
    Eigen::Isometry3d pose;
    std::string error;
    ros::Time stamp;
    if (lookupPose(follower.frame, pose, stamp, error) && stillFresh(move.age, stamp, now, error))
    {
      move.goal_center = pose.translation();
      move.goal_orientation = Eigen::Quaterniond(pose.rotation()).normalized();
    }
    else
      ROS_WARN_THROTTLE_NAMED(5.0, "colliders",
                              "collider %s follows frame %s, which is not available: %s; it holds still",
                              quoteName(follower.collider).c_str(), quoteName(follower.frame).c_str(), error.c_str());
  }
  collider_moves_.resize(k);  // followers that are gone move nothing
}

std::vector<geometry_msgs::TransformStamped> scriptedFrameTransforms(const scene::SceneDef& scene,
                                                                     const std::string& sim_frame,
                                                                     const ros::Time& stamp)
{
  std::vector<geometry_msgs::TransformStamped> transforms;
  transforms.reserve(scene.frames.size());
  for (const scene::ScriptedFrameDef& frame : scene.frames)
  {
    const Eigen::Vector3d x = frame.position(stamp.toSec());
    geometry_msgs::TransformStamped transform;
    transform.header.stamp = stamp;
    transform.header.frame_id = sim_frame;
    transform.child_frame_id = frame.name;
    transform.transform.translation.x = x.x();
    transform.transform.translation.y = x.y();
    transform.transform.translation.z = x.z();
    transform.transform.rotation.w = 1.0;
    transforms.push_back(transform);
  }
  return transforms;
}

}  // namespace ros_interface
}  // namespace particle_sim
