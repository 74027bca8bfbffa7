#pragma once

#include <ros/ros.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <chrono>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "particle_sim/PinParticle.h"
#include "particle_sim/RemoveBody.h"
#include "particle_sim/SetSpringConstants.h"
#include "particle_sim/SetWind.h"
#include "particle_sim/SpawnCloth.h"
#include "particle_sim/SpawnEmitter.h"
#include "particle_sim/SpawnJelly.h"
#include "particle_sim/SpawnRope.h"
#include "particle_sim/Step.h"
#include "particle_sim/UnpinParticle.h"
#include "particle_sim/core/world.h"
#include "particle_sim/ros/marker_builder.h"
#include "particle_sim/scene/scene.h"

namespace particle_sim
{
namespace ros_interface
{
/// The node's settings, read once from private parameters (README "Parameters").
struct NodeSettings
{
  std::string scene_path;          ///< ~scene, YAML scene file; empty = an empty world
  double rate = 50.0;              ///< ~rate [Hz] publish rate (and physics ticks)
  double dt = 0.0;                 ///< ~dt [s] physics step; 0 = the scene's world.dt
  double real_time_factor = 1.0;   ///< ~real_time_factor [-]; 0 = as fast as possible
  bool paused = false;             ///< ~paused: start paused
  std::string frame_id = "world";  ///< ~frame_id: frame of every marker
  std::string parent_frame_id = "map";  ///< ~parent_frame_id: tf parent of frame_id (identity)
  bool publish_clock = true;       ///< ~publish_clock: publish /clock from sim time
  double particle_size = 0.05;     ///< ~particle_size [m]
  int max_particles_per_body = 0;  ///< ~max_particles_per_body; 0 = the scene's value
  double status_period = 1.0;      ///< ~status_period [s] of wall time between status lines; 0 = none
  bool color_by_strain = false;    ///< ~color_by_strain: colour cloth and jelly by strain
  double strain_color_max = 0.1;   ///< ~strain_color_max [-]: strain drawn fully red
};

/// The simulator node: owns a core::World, steps it at a fixed rate on steady (wall) time, serves
/// its services between steps and publishes markers, tf and /clock.
class SimNode
{
public:
  SimNode(ros::NodeHandle node, ros::NodeHandle private_node);

  /// Reads parameters and loads the scene; false (after logging why) when they are unusable.
  bool initialize();

  /// Runs until ROS shuts down: spin callbacks, step, publish, sleep until the next tick.
  void run();

private:
  // One tick: `substeps_` physics steps unless paused, then publish.
  void tick();
  void stepPhysics(std::uint64_t steps);
  void publish();
  void printStatus(double wall_elapsed);

  // A particle pinned to a tf frame: its target is the frame's pose applied to `offset`, looked
  // up once per tick and approached linearly over the tick's substeps.
  struct FramePin
  {
    std::string body;
    int index = 0;
    std::string frame;
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  };
  // Looks `frame` up in the sim frame (latest transform), waiting up to `wait` wall seconds.
  bool lookupFrame(const std::string& frame, const Eigen::Vector3d& offset, double wait, Eigen::Vector3d& point,
                   std::string& error);
  // Drops frame pins whose body or pin is gone, and sets each remaining pin's start and goal for
  // this tick (the goal from tf; the start where its target is now).
  void updateFramePins();

  bool spawnEmitter(SpawnEmitter::Request& req, SpawnEmitter::Response& res);
  bool spawnRope(SpawnRope::Request& req, SpawnRope::Response& res);
  bool pinParticle(PinParticle::Request& req, PinParticle::Response& res);
  bool unpinParticle(UnpinParticle::Request& req, UnpinParticle::Response& res);
  bool setSpringConstants(SetSpringConstants::Request& req, SetSpringConstants::Response& res);
  bool spawnCloth(SpawnCloth::Request& req, SpawnCloth::Response& res);
  bool spawnJelly(SpawnJelly::Request& req, SpawnJelly::Response& res);
  bool setWind(SetWind::Request& req, SetWind::Response& res);
  // Moves spheres that follow tf frames (scripted frames are applied every step).
  void updateFrameSpheres();
  // Broadcasts the scene's scripted frames at the current sim time.
  void broadcastScriptedFrames(const ros::Time& stamp);
  bool removeBody(RemoveBody::Request& req, RemoveBody::Response& res);
  bool reset(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  bool pausePhysics(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  bool unpausePhysics(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  bool step(Step::Request& req, Step::Response& res);

  ros::NodeHandle node_;
  ros::NodeHandle private_node_;
  NodeSettings settings_;
  MarkerStyle style_;
  scene::SceneDef scene_;  // as loaded: scripted frames and what follows frames
  std::unique_ptr<core::World> world_;
  int substeps_ = 1;
  bool paused_ = false;

  ros::Publisher markers_pub_;
  ros::Publisher meshes_pub_;
  ros::Publisher clock_pub_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  std::vector<ros::ServiceServer> services_;

  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;  // created at the first frame pin
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::vector<FramePin> frame_pins_;
  std::vector<Eigen::Vector3d> frame_pin_start_, frame_pin_goal_;  // per frame pin, this tick

  std::set<std::string> reported_frozen_;  // frozen bodies already logged

  bool delete_all_pending_ = true;
  std::vector<std::string> removed_bodies_;
  double last_tf_time_ = -1.0;
  double last_clock_time_ = -1.0;

  // Measurements for the status line.
  std::uint64_t steps_since_status_ = 0;
  double step_seconds_since_status_ = 0.0;
  double sim_time_at_status_ = 0.0;
};

}  // namespace ros_interface
}  // namespace particle_sim
