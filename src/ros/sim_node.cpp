#include "particle_sim/ros/sim_node.h"

#include <geometry_msgs/TransformStamped.h>
#include <rosgraph_msgs/Clock.h>

#include <cmath>
#include <sstream>
#include <thread>

#include "particle_sim/ros/names.h"
#include "particle_sim/scene/scene.h"

namespace particle_sim
{
namespace ros_interface
{
namespace
{
using SteadyClock = std::chrono::steady_clock;

double secondsSince(SteadyClock::time_point start)
{
  return std::chrono::duration<double>(SteadyClock::now() - start).count();
}

// Fills a Trigger-style response and returns true, so that the client sees our message rather
// than a bare "service call failed".
template <typename Response>
bool answer(Response& res, const core::Status& status)
{
  res.success = status.ok;
  res.message = status.message;
  return true;
}
}  // namespace

SimNode::SimNode(ros::NodeHandle node, ros::NodeHandle private_node)
  : node_(std::move(node)), private_node_(std::move(private_node))
{
}

bool SimNode::initialize()
{
  NodeSettings& s = settings_;
  private_node_.param(names::kSceneParam, s.scene_path, s.scene_path);
  private_node_.param(names::kRateParam, s.rate, s.rate);
  private_node_.param(names::kDtParam, s.dt, s.dt);
  private_node_.param(names::kRealTimeFactorParam, s.real_time_factor, s.real_time_factor);
  private_node_.param(names::kPausedParam, s.paused, s.paused);
  private_node_.param(names::kFrameIdParam, s.frame_id, s.frame_id);
  private_node_.param(names::kParentFrameIdParam, s.parent_frame_id, s.parent_frame_id);
  private_node_.param(names::kPublishClockParam, s.publish_clock, s.publish_clock);
  private_node_.param(names::kParticleSizeParam, s.particle_size, s.particle_size);
  private_node_.param(names::kMaxParticlesParam, s.max_particles_per_body, s.max_particles_per_body);
  private_node_.param(names::kStatusPeriodParam, s.status_period, s.status_period);

  // Parameters are checked before anything starts; a bad one stops the node with its reason.
  auto refuse = [](const std::string& message) {
    ROS_FATAL_NAMED("sim", "%s", message.c_str());
    return false;
  };
  if (!(s.rate > 0.0 && s.rate <= 1000.0))
    return refuse("~rate = " + std::to_string(s.rate) + " is out of range: must be in (0, 1000] Hz");
  if (!(s.real_time_factor >= 0.0 && std::isfinite(s.real_time_factor)))
    return refuse("~real_time_factor = " + std::to_string(s.real_time_factor) + " must be >= 0 (0 = as fast as possible)");
  if (!(s.particle_size > 0.0 && std::isfinite(s.particle_size)))
    return refuse("~particle_size = " + std::to_string(s.particle_size) + " must be > 0 m");
  if (s.frame_id.empty()) return refuse("~frame_id is empty");

  scene::SceneDef scene;
  if (!s.scene_path.empty())
  {
    if (core::Status status = scene::loadSceneFile(s.scene_path, scene); !status) return refuse(status.message);
  }
  if (s.dt != 0.0) scene.world.dt = s.dt;
  if (s.max_particles_per_body != 0) scene.world.max_particles_per_body = s.max_particles_per_body;
  if (core::Status status = scene::buildWorld(scene, world_); !status) return refuse("~scene: " + status.message);

  // The publish period must be a whole number of physics steps.
  const double period = 1.0 / s.rate;
  substeps_ = std::max(1, static_cast<int>(std::lround(period / world_->dt())));
  if (std::abs(substeps_ * world_->dt() - period) > 1e-9 * period)
    ROS_WARN_NAMED("sim", "1/~rate = %g s is not a whole number of steps of dt = %g s; using %d substeps (%g s)",
                   period, world_->dt(), substeps_, substeps_ * world_->dt());
  paused_ = s.paused;
  style_.frame_id = s.frame_id;
  style_.particle_size = s.particle_size;

  markers_pub_ = private_node_.advertise<visualization_msgs::MarkerArray>(names::kMarkersTopic, 10);
  if (s.publish_clock) clock_pub_ = node_.advertise<rosgraph_msgs::Clock>(names::kClockTopic, 10);
  tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();

  services_.push_back(private_node_.advertiseService(names::kSpawnEmitter, &SimNode::spawnEmitter, this));
  services_.push_back(private_node_.advertiseService(names::kRemoveBody, &SimNode::removeBody, this));
  services_.push_back(private_node_.advertiseService(names::kReset, &SimNode::reset, this));
  services_.push_back(private_node_.advertiseService(names::kPausePhysics, &SimNode::pausePhysics, this));
  services_.push_back(private_node_.advertiseService(names::kUnpausePhysics, &SimNode::unpausePhysics, this));
  services_.push_back(private_node_.advertiseService(names::kStep, &SimNode::step, this));

  ROS_INFO_NAMED("sim",
                 "particle_sim: scene '%s', %zu bodies, dt = %g s, %d substeps per tick at %g Hz, real-time factor %g%s, "
                 "frame '%s'",
                 s.scene_path.c_str(), world_->bodies().size(), world_->dt(), substeps_, s.rate, s.real_time_factor,
                 paused_ ? ", paused" : "", s.frame_id.c_str());
  return true;
}

void SimNode::run()
{
  // The loop runs on steady time, never ros::Rate (which would wait on our own /clock). Each tick
  // covers substeps * dt of sim time, i.e. that much wall time divided by the real-time factor.
  const double sim_per_tick = substeps_ * world_->dt();
  const auto wall_period = std::chrono::duration<double>(
      settings_.real_time_factor > 0.0 ? sim_per_tick / settings_.real_time_factor : 0.0);
  const auto paused_period = std::chrono::duration<double>(1.0 / settings_.rate);

  auto next_tick = SteadyClock::now();
  auto last_status = SteadyClock::now();
  while (ros::ok())
  {
    ros::spinOnce();  // services run here, between steps
    tick();

    if (settings_.status_period > 0.0 && secondsSince(last_status) >= settings_.status_period)
    {
      printStatus(secondsSince(last_status));
      last_status = SteadyClock::now();
    }

    // Sleep until the next tick; if we fell more than a tick behind, do not try to catch up.
    next_tick += std::chrono::duration_cast<SteadyClock::duration>(paused_ ? paused_period : wall_period);
    const auto now = SteadyClock::now();
    if (next_tick < now - std::chrono::duration_cast<SteadyClock::duration>(paused_period))
      next_tick = now;
    if (next_tick > now) std::this_thread::sleep_until(next_tick);
  }
}

void SimNode::tick()
{
  if (!paused_) stepPhysics(substeps_);
  publish();
}

void SimNode::stepPhysics(std::uint64_t steps)
{
  const auto start = SteadyClock::now();
  for (std::uint64_t i = 0; i < steps; ++i) world_->step();
  step_seconds_since_status_ += secondsSince(start);
  steps_since_status_ += steps;
}

void SimNode::publish()
{
  const double sim_time = world_->simTime();
  const ros::Time stamp(sim_time);

  // /clock: from sim time, never 0, only when it moved.
  if (settings_.publish_clock && sim_time > 0.0 && sim_time != last_clock_time_)
  {
    rosgraph_msgs::Clock clock;
    clock.clock = stamp;
    clock_pub_.publish(clock);
    last_clock_time_ = sim_time;
  }

  // tf: the sim frame under its parent, re-sent only with a newer stamp (no TF_REPEATED_DATA).
  if (sim_time != last_tf_time_)
  {
    geometry_msgs::TransformStamped transform;
    transform.header.stamp = stamp;
    transform.header.frame_id = settings_.parent_frame_id;
    transform.child_frame_id = settings_.frame_id;
    transform.transform.rotation.w = 1.0;
    tf_broadcaster_->sendTransform(transform);
    last_tf_time_ = sim_time;
  }

  // Markers are only built when someone listens.
  if (markers_pub_.getNumSubscribers() == 0) return;
  auto markers = boost::make_shared<visualization_msgs::MarkerArray>(
      buildMarkers(*world_, stamp, style_, delete_all_pending_, removed_bodies_));
  markers_pub_.publish(markers);
  delete_all_pending_ = false;
  removed_bodies_.clear();
}

void SimNode::printStatus(double wall_elapsed)
{
  const double sim_time = world_->simTime();
  const double rtf = wall_elapsed > 0.0 ? (sim_time - sim_time_at_status_) / wall_elapsed : 0.0;
  const double step_us = steps_since_status_ ? 1e6 * step_seconds_since_status_ / steps_since_status_ : 0.0;
  ROS_INFO_NAMED("status", "sim time %.3f s | real-time factor %.2f | live particles %d | step %.1f us%s", sim_time,
                 rtf, world_->particleCount(), step_us, paused_ ? " | paused" : "");
  sim_time_at_status_ = sim_time;
  steps_since_status_ = 0;
  step_seconds_since_status_ = 0.0;
}

bool SimNode::spawnEmitter(SpawnEmitter::Request& req, SpawnEmitter::Response& res)
{
  // The request becomes the same EmitterDef a scene file builds, checked by the same validate().
  core::EmitterDef def;
  def.name = req.name;
  if (!core::parseEmitterType(req.type, def.type))
    return answer(res, core::Status::failure("type = '" + req.type +
                                             "' is not an emitter type; allowed: " + core::emitterTypeNames()));
  def.origin = {req.origin.x, req.origin.y, req.origin.z};
  def.rate = req.rate;
  def.burst_count = static_cast<int>(std::min<std::uint32_t>(req.burst_count, 2000000000u));
  def.speed = req.speed;
  def.spread = req.spread;
  if (req.lifetime != 0.0) def.lifetime = req.lifetime;
  if (req.mass != 0.0) def.particle_mass = req.mass;
  if (req.max_particles != 0) def.max_particles = static_cast<int>(std::min<std::uint32_t>(req.max_particles, 2000000000u));
  def.seed = req.seed != 0 ? req.seed : core::deriveSeed(world_->definition().seed, def.name);

  core::Status status = world_->addEmitter(def);
  if (status)
    status.message = "spawned " + std::string(core::toString(def.type)) + " emitter '" + def.name + "'";
  else
    ROS_WARN_NAMED("services", "spawn_emitter refused: %s", status.message.c_str());
  return answer(res, status);
}

bool SimNode::removeBody(RemoveBody::Request& req, RemoveBody::Response& res)
{
  core::Status status = world_->removeBody(req.name);
  if (status)
  {
    removed_bodies_.push_back(req.name);
    status.message = "removed '" + req.name + "'";
  }
  return answer(res, status);
}

bool SimNode::reset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res)
{
  world_->reset();
  delete_all_pending_ = true;
  std::ostringstream message;
  message << "reset every body; sim time goes on from " << world_->simTime() << " s";
  return answer(res, core::Status::success(message.str()));
}

bool SimNode::pausePhysics(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res)
{
  paused_ = true;
  return answer(res, core::Status::success("paused at sim time " + std::to_string(world_->simTime()) + " s"));
}

bool SimNode::unpausePhysics(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res)
{
  paused_ = false;
  return answer(res, core::Status::success("running from sim time " + std::to_string(world_->simTime()) + " s"));
}

bool SimNode::step(Step::Request& req, Step::Response& res)
{
  constexpr std::uint32_t kMaxSteps = 1000000;
  if (!paused_)
    answer(res, core::Status::failure("the simulation is running: call ~pause_physics before ~step"));
  else if (req.steps < 1 || req.steps > kMaxSteps)
    answer(res, core::Status::failure("steps = " + std::to_string(req.steps) + " is out of range: must be in [1, " +
                                      std::to_string(kMaxSteps) + "]"));
  else
  {
    stepPhysics(req.steps);
    publish();
    answer(res, core::Status::success("advanced " + std::to_string(req.steps) + " steps"));
  }
  res.sim_time = world_->simTime();
  return true;
}

}  // namespace ros_interface
}  // namespace particle_sim
