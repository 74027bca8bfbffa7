#include "particle_sim/ros/sim_node.h"

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <geometry_msgs/TransformStamped.h>
#include <rosgraph_msgs/Clock.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <thread>

#include "particle_sim/core/limits.h"
#include "particle_sim/ros/mesh_builder.h"
#include "particle_sim/ros/message_text.h"
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
// than a bare "service call failed". The message is valid UTF-8 of bounded length whatever the
// request held (names are echoed in it).
template <typename Response>
bool answer(Response& res, const core::Status& status)
{
  res.success = status.ok;
  res.message = toMessageText(status.message);
  return true;
}

// Reads the integrator name of a spawn request into `integrator` (empty keeps the world's default).
core::Status parseIntegratorField(const std::string& name, core::IntegratorDef& integrator)
{
  if (name.empty() || core::parseIntegratorType(name, integrator.type)) return core::Status::success();
  return core::Status::failure("integrator = " + quoteName(name) +
                               " is not an integrator; allowed: " + core::integratorTypeNames());
}

// "field = value is out of range: must be in [min, max] unit" for a node parameter, the value as
// received.
std::string outOfRange(const std::string& field, double value, const core::limits::Range& range)
{
  return field + " = " + formatReceived(value) + " is out of range: must be in [" + formatReceived(range.min) + ", " +
         formatReceived(range.max) + "] " + range.unit;
}

geometry_msgs::Vector3 toVector3(const Eigen::Vector3d& v)
{
  geometry_msgs::Vector3 out;
  out.x = v.x();
  out.y = v.y();
  out.z = v.z();
  return out;
}

// The integrator the body's last step ran: its own, or what auto chose (the core records the
// latter only for completed steps, so a body that froze in its first step would otherwise show
// the default).
core::IntegratorType integratorThatRan(const core::SpringNetworkBody& body)
{
  return body.integrator().type == core::IntegratorType::Auto ? body.lastIntegrator() : body.integrator().type;
}

// A count field of a request (uint32) as the core's int: a value beyond int is refused as
// received instead of being clamped (which would show the clamped value in the core's message);
// the core checks the rest of the range.
core::Status readCount(const char* field, std::uint32_t value, int& count)
{
  constexpr auto kMax = static_cast<std::uint32_t>(std::numeric_limits<int>::max());
  if (value > kMax)
    return core::Status::failure(std::string(field) + " = " + std::to_string(value) +
                                 " is out of range: must be at most " + std::to_string(kMax));
  count = static_cast<int>(value);
  return core::Status::success();
}
}  // namespace

SimNode::SimNode(ros::NodeHandle node, ros::NodeHandle private_node, const std::string& name)
    : node_(std::move(node)), private_node_(std::move(private_node)), name_(name)
{
  // Every callback of ours (services, dynamic_reconfigure) waits in our own queue until run()
  // serves it between two ticks, whichever thread runs us.
  node_.setCallbackQueue(&callback_queue_);
  private_node_.setCallbackQueue(&callback_queue_);
}

SimNode::~SimNode()
{
  master_link_.stop();
  // A ~step client still waiting (the loop never ran) gets an answer, so that its thread ends.
  {
    std::lock_guard<std::mutex> lock(step_mutex_);
    step_service_closing_ = true;
    if (step_requested_)
    {
      step_answer_.success = false;
      step_answer_.message = "the node is shutting down";
      step_requested_ = false;
      step_answer_ready_ = true;
    }
  }
  step_answered_.notify_all();
  step_thread_running_ = false;
  if (step_thread_.joinable()) step_thread_.join();
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
  private_node_.param(names::kFrameOffsetParam, s.frame_offset, s.frame_offset);
  private_node_.param(names::kPublishClockParam, s.publish_clock, s.publish_clock);
  private_node_.param(names::kParticleSizeParam, s.particle_size, s.particle_size);
  private_node_.param(names::kMaxParticlesParam, s.max_particles_per_body, s.max_particles_per_body);
  private_node_.param(names::kStatusPeriodParam, s.status_period, s.status_period);
  private_node_.param(names::kColorByStrainParam, s.color_by_strain, s.color_by_strain);
  private_node_.param(names::kStrainColorMaxParam, s.strain_color_max, s.strain_color_max);
  private_node_.param(names::kDiagnosticPeriodParam, s.diagnostic_period, s.diagnostic_period);
  private_node_.param(names::kDiagnosticMaxStrainParam, s.diagnostic_max_strain, s.diagnostic_max_strain);

  // Parameters are checked before anything starts; a bad one stops the node with its reason.
  auto refuse = [](const std::string& message) {
    ROS_FATAL_NAMED("sim", "%s", message.c_str());
    return false;
  };
  using core::limits::kPublishRate;
  using core::limits::kRealTimeFactor;
  if (!(s.rate >= kPublishRate.min && s.rate <= kPublishRate.max))
    return refuse(outOfRange("~rate", s.rate, kPublishRate));
  if (!(s.real_time_factor >= kRealTimeFactor.min && s.real_time_factor <= kRealTimeFactor.max))
    return refuse(outOfRange("~real_time_factor", s.real_time_factor, kRealTimeFactor) +
                  " (0 = as fast as possible; negative values have no meaning)");
  if (!(s.particle_size > 0.0 && std::isfinite(s.particle_size)))
    return refuse("~particle_size = " + formatReceived(s.particle_size) + " must be > 0 m");
  if (s.frame_id.empty()) return refuse("~frame_id is empty");
  if (s.parent_frame_id.empty() || s.parent_frame_id == s.frame_id)
    return refuse("~parent_frame_id = " + quoteName(s.parent_frame_id) + " must be set and differ from ~frame_id");
  if (s.frame_offset.size() != 3 ||
      !std::all_of(s.frame_offset.begin(), s.frame_offset.end(), [](double v) { return std::isfinite(v); }))
    return refuse("~frame_offset must be a list of 3 finite numbers [x, y, z] in m");

  if (!(s.strain_color_max > 0.0 && std::isfinite(s.strain_color_max)))
    return refuse("~strain_color_max = " + formatReceived(s.strain_color_max) + " must be > 0");
  if (!(s.diagnostic_period > 0.0 && std::isfinite(s.diagnostic_period)))
    return refuse("~diagnostic_period = " + formatReceived(s.diagnostic_period) + " must be > 0 s");
  if (!(s.diagnostic_max_strain > 0.0 && std::isfinite(s.diagnostic_max_strain)))
    return refuse("~diagnostic_max_strain = " + formatReceived(s.diagnostic_max_strain) + " must be > 0");

  scene::SceneDef& scene = scene_;
  if (!s.scene_path.empty())
  {
    if (core::Status status = scene::loadSceneFile(s.scene_path, scene); !status) return refuse(status.message);
  }
  if (s.dt != 0.0) scene.world.dt = s.dt;
  if (s.max_particles_per_body != 0) scene.world.max_particles_per_body = s.max_particles_per_body;
  if (core::Status status = scene::buildWorld(scene, world_); !status) return refuse("~scene: " + status.message);
  // Scene pins that follow frames other than the scene's scripted ones follow them through tf.
  for (const scene::FramePinDef& pin : scene.frame_pins)
  {
    if (!scene::findFrame(scene, pin.frame))
      frame_pins_.push_back({pin.body, pin.index, pin.frame, pin.offset, ros::Time(), SteadyClock::now()});
  }

  updateSubsteps();
  default_integrator_ = world_->definition().integrator;
  paused_ = s.paused;
  style_.frame_id = s.frame_id;
  style_.particle_size = s.particle_size;
  style_.color_by_strain = s.color_by_strain;
  style_.strain_color_max = s.strain_color_max;

  advertiseInterfaces();
  status_window_.restart(world_->simTime(), paused_);
  diagnostics_window_.restart(world_->simTime(), paused_);

  ROS_INFO_NAMED(
      "sim",
      "particle_sim: scene '%s', %zu bodies, dt = %g s, %d substeps per tick at %g Hz, real-time factor %g%s, "
      "frame '%s'",
      s.scene_path.c_str(), world_->bodies().size(), world_->dt(), substeps_, s.rate, s.real_time_factor,
      paused_ ? ", paused" : "", s.frame_id.c_str());
  return true;
}

void SimNode::advertiseInterfaces()
{
  markers_pub_ = private_node_.advertise<visualization_msgs::MarkerArray>(names::kMarkersTopic, 10);
  meshes_pub_ = private_node_.advertise<ClothMesh>(names::kMeshesTopic, 10);
  status_pub_ = private_node_.advertise<SimStatus>(names::kStatusTopic, 10);
  if (settings_.publish_clock) clock_pub_ = node_.advertise<rosgraph_msgs::Clock>(names::kClockTopic, 10);
  tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
  // tf is listened to from the start (on the listener's own thread), so that a pin request can be
  // answered at once from what tf already knows.
  tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_);

  services_.push_back(private_node_.advertiseService(names::kSpawnEmitter, &SimNode::spawnEmitter, this));
  services_.push_back(private_node_.advertiseService(names::kRemoveBody, &SimNode::removeBody, this));
  services_.push_back(private_node_.advertiseService(names::kReset, &SimNode::reset, this));
  services_.push_back(private_node_.advertiseService(names::kPausePhysics, &SimNode::pausePhysics, this));
  services_.push_back(private_node_.advertiseService(names::kUnpausePhysics, &SimNode::unpausePhysics, this));
  services_.push_back(private_node_.advertiseService(names::kSpawnRope, &SimNode::spawnRope, this));
  services_.push_back(private_node_.advertiseService(names::kPinParticle, &SimNode::pinParticle, this));
  services_.push_back(private_node_.advertiseService(names::kUnpinParticle, &SimNode::unpinParticle, this));
  services_.push_back(private_node_.advertiseService(names::kSetSpringConstants, &SimNode::setSpringConstants, this));
  services_.push_back(private_node_.advertiseService(names::kSpawnCloth, &SimNode::spawnCloth, this));
  services_.push_back(private_node_.advertiseService(names::kSpawnJelly, &SimNode::spawnJelly, this));
  services_.push_back(private_node_.advertiseService(names::kSetWind, &SimNode::setWind, this));

  // ~step waits for the loop to run its steps in slices: its callback runs in a thread of its own.
  ros::AdvertiseServiceOptions step_options;
  step_options.init<Step::Request, Step::Response>(
      private_node_.resolveName(names::kStep),
      [this](Step::Request& req, Step::Response& res) { return step(req, res); });
  step_options.callback_queue = &step_queue_;
  step_service_ = private_node_.advertiseService(step_options);
  step_thread_running_ = true;
  step_thread_ = std::thread([this] {
    while (step_thread_running_)
      step_queue_.callAvailable(ros::WallDuration(0.05));
  });

  // dynamic_reconfigure starts from the world as built (the scene's gravity, wind, ...) and the
  // parameters read above: the config is pushed before the callback is set, so that the
  // callback's first call applies what is already there.
  reconfigure_server_ = std::make_unique<dynamic_reconfigure::Server<SimConfig>>(reconfigure_mutex_, private_node_);
  config_ = currentConfig();
  reconfigure_server_->updateConfig(config_);
  reconfigure_server_->setCallback([this](SimConfig& config, std::uint32_t level) { reconfigure(config, level); });

  // Diagnostics, updated on wall time by run() (diagnostic_updater's own update() runs on ROS time,
  // which stands still while paused).
  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(node_, private_node_, name_);
  diagnostics_->setHardwareID(name_);
  diagnostics_->add("simulation", this, &SimNode::produceDiagnostics);

  // When roscore restarts, register everything again with the new master (README "Topics").
  std::vector<std::string> service_names;
  for (const ros::ServiceServer& service : services_)
    service_names.push_back(service.getService());
  service_names.push_back(step_service_.getService());
  for (const char* name : {"set_parameters", "get_loggers", "set_logger_level"})
    service_names.push_back(private_node_.resolveName(name));
  master_link_.start(service_names);
}

void SimNode::releaseInterfaces()
{
  master_link_.stop();
  // A client waiting on ~step gets its answer before the service goes.
  bool step_waiting = false;
  {
    std::lock_guard<std::mutex> lock(step_mutex_);
    step_service_closing_ = true;
    step_waiting = step_requested_;
  }
  if (step_job_.active || step_waiting)
  {
    Step::Response res;
    res.success = false;
    res.message = "the node is shutting down; " +
                  std::to_string(step_job_.active ? step_job_.requested - step_job_.remaining : 0) + " steps were run";
    res.sim_time = world_->simTime();
    step_job_.active = false;
    deliverStepAnswer(res);
  }
  step_thread_running_ = false;
  if (step_thread_.joinable()) step_thread_.join();
  step_service_.shutdown();
  step_queue_.disable();
  step_queue_.clear();

  reconfigure_server_.reset();
  diagnostics_.reset();
  services_.clear();
  tf_listener_.reset();
  tf_buffer_.reset();
  tf_broadcaster_.reset();
  for (ros::Publisher* publisher : {&markers_pub_, &meshes_pub_, &clock_pub_, &status_pub_})
    publisher->shutdown();
}

void SimNode::updateSubsteps()
{
  // The publish period must be a whole number of physics steps.
  const double period = 1.0 / settings_.rate;
  substeps_ = std::max(1, static_cast<int>(std::lround(period / world_->dt())));
  if (std::abs(substeps_ * world_->dt() - period) > 1e-9 * period)
    ROS_WARN_NAMED("sim", "1/~rate = %g s is not a whole number of steps of dt = %g s; using %d substeps (%g s)",
                   period, world_->dt(), substeps_, substeps_ * world_->dt());
}

void SimNode::run()
{
  auto next_tick = SteadyClock::now();
  while (ros::ok() && !stop_requested_)
  {
    callback_queue_.callAvailable();  // services and dynamic_reconfigure run here, between steps
    acceptStepRequest();
    tick();

    if (settings_.status_period > 0.0 && secondsSince(status_window_.start) >= settings_.status_period) printStatus();
    if (secondsSince(diagnostics_window_.start) >= settings_.diagnostic_period)
    {
      diagnostics_->force_update();
      diagnostics_window_.restart(world_->simTime(), paused_);
    }

    // The loop runs on steady time, never ros::Rate (which would wait on our own /clock). Each
    // tick covers substeps * dt of sim time, i.e. that much wall time divided by the real-time
    // factor (both may change at run time).
    const double sim_per_tick = substeps_ * world_->dt();
    const auto wall_period = std::chrono::duration<double>(
        settings_.real_time_factor > 0.0 ? sim_per_tick / settings_.real_time_factor : 0.0);
    const auto paused_period = std::chrono::duration<double>(1.0 / settings_.rate);

    // Sleep until the next tick; if we fell more than a tick behind, do not try to catch up.
    next_tick += std::chrono::duration_cast<SteadyClock::duration>(paused_ ? paused_period : wall_period);
    const auto now = SteadyClock::now();
    if (next_tick < now - std::chrono::duration_cast<SteadyClock::duration>(paused_period)) next_tick = now;
    if (step_job_.active) next_tick = now;  // a ~step in slices: the next slice at once
    if (next_tick > now) std::this_thread::sleep_until(next_tick);
  }

  // Let go of every ROS handle here, in the loop's thread, while ROS still exists: in a nodelet
  // manager the simulator may otherwise be destroyed after ROS's own singletons, and its
  // publishers and servers would unregister from destroyed objects.
  releaseInterfaces();
  callback_queue_.disable();
  callback_queue_.clear();
}

void SimNode::tick()
{
  if (step_job_.active)
    runStepSlice();
  else if (!paused_)
    stepPhysics(substeps_);
  publish();
  if (step_job_.active && step_job_.remaining == 0) finishStepJob();
}

void SimNode::stepPhysics(std::uint64_t steps)
{
  updateFramePins();
  updateFrameSpheres();
  const auto start = SteadyClock::now();
  for (std::uint64_t i = 0; i < steps; ++i)
  {
    // Particles pinned to tf frames move in equal parts towards this tick's frame pose.
    for (std::size_t k = 0; k < frame_pins_.size(); ++k)
    {
      const double s = static_cast<double>(i + 1) / static_cast<double>(steps);
      world_->findSpringBody(frame_pins_[k].body)
          ->setPinTarget(frame_pins_[k].index, frame_pin_start_[k] + s * (frame_pin_goal_[k] - frame_pin_start_[k]));
    }
    // Scripted frames are known exactly: where they are at the end of this step.
    scene::applyScriptedFrames(scene_, world_->simTime() + world_->dt(), *world_);
    world_->step();
  }
  const double seconds = secondsSince(start);
  for (Window* window : {&status_window_, &diagnostics_window_})
  {
    window->step_seconds += seconds;
    window->steps += steps;
  }

  // A body that froze is reported once; other stability events (substeps added, blow-ups rolled
  // back, energy removed) and auto's choices as they happen, at most every 2 s each. The rest of
  // the world goes on.
  for (const auto& body : world_->bodies())
  {
    if (body->kind() != core::BodyKind::SpringNetwork) continue;
    const auto& spring_body = static_cast<const core::SpringNetworkBody&>(*body);
    // Logged once per freeze: a body unfrozen by ~reset is reported again if it freezes again.
    if (!spring_body.frozen())
      reported_frozen_.erase(body->name());
    else if (reported_frozen_.insert(body->name()).second)
      ROS_ERROR_NAMED("sim", "body %s is frozen (integrator %s, last ran %s): %s", quoteName(body->name()).c_str(),
                      core::toString(spring_body.integrator().type), core::toString(integratorThatRan(spring_body)),
                      spring_body.frozenReason().c_str());
    long long& seen = reported_events_[body->name()];
    if (spring_body.stabilityEvents() > seen)
    {
      ROS_WARN_THROTTLE_NAMED(2.0, "stability", "body '%s': %lld stability events; last: %s", body->name().c_str(),
                              spring_body.stabilityEvents(), spring_body.lastStabilityEvent().c_str());
      events_since_diagnostics_ += spring_body.stabilityEvents() - seen;
      seen = spring_body.stabilityEvents();
    }
    std::string& choice = reported_auto_[body->name()];
    if (spring_body.autoChoice() != choice)
    {
      choice = spring_body.autoChoice();
      if (!choice.empty()) ROS_INFO_NAMED("stability", "body '%s' auto: %s", body->name().c_str(), choice.c_str());
    }
  }
}

bool SimNode::lookupFrame(const std::string& frame, const Eigen::Vector3d& offset, Eigen::Vector3d& point,
                          ros::Time& stamp, std::string& error)
{
  if (!tf_buffer_->canTransform(settings_.frame_id, frame, ros::Time(0), &error)) return false;
  try
  {
    const geometry_msgs::TransformStamped t = tf_buffer_->lookupTransform(settings_.frame_id, frame, ros::Time(0));
    const auto& q = t.transform.rotation;
    const auto& v = t.transform.translation;
    point = Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized() * offset + Eigen::Vector3d(v.x, v.y, v.z);
    stamp = t.header.stamp;
    if (!point.allFinite()) error = "its transform is not finite";
    return point.allFinite();
  }
  catch (const tf2::TransformException& exception)
  {
    error = exception.what();
    return false;
  }
}

void SimNode::updateFramePins()
{
  // Forget pins whose body was removed or whose particle was unpinned or reset.
  frame_pins_.erase(std::remove_if(frame_pins_.begin(), frame_pins_.end(),
                                   [&](const FramePin& pin) {
                                     const core::SpringNetworkBody* body = world_->findSpringBody(pin.body);
                                     return !body || !body->isPinned(pin.index);
                                   }),
                    frame_pins_.end());
  frame_pin_start_.resize(frame_pins_.size());
  frame_pin_goal_.resize(frame_pins_.size());
  const auto now = SteadyClock::now();
  for (std::size_t k = 0; k < frame_pins_.size(); ++k)
  {
    FramePin& pin = frame_pins_[k];
    frame_pin_start_[k] = world_->findSpringBody(pin.body)->pinTarget(pin.index);
    std::string error;
    ros::Time stamp;
    bool available = lookupFrame(pin.frame, pin.offset, frame_pin_goal_[k], stamp, error);
    // A frame whose transform stopped changing is gone (tf keeps its last transform for ever);
    // a static frame (stamp 0) never goes.
    if (available && stamp != pin.stamp)
    {
      pin.stamp = stamp;
      pin.updated = now;
    }
    else if (available && !stamp.isZero() &&
             std::chrono::duration<double>(now - pin.updated).count() > kFramePinTimeout)
    {
      available = false;
      error = "no new transform for " +
              formatReceived(std::round(std::chrono::duration<double>(now - pin.updated).count())) + " s";
    }
    if (!available)
    {
      frame_pin_goal_[k] = frame_pin_start_[k];  // hold still until the frame is back
      ROS_WARN_THROTTLE_NAMED(5.0, "pins",
                              "particle %d of %s follows frame %s, which is not available: %s; it holds still",
                              pin.index, quoteName(pin.body).c_str(), quoteName(pin.frame).c_str(), error.c_str());
    }
  }
}

void SimNode::updateFrameSpheres()
{
  for (const scene::FrameSphereDef& follower : scene_.frame_spheres)
  {
    if (scene::findFrame(scene_, follower.frame)) continue;  // scripted: applied every step
    Eigen::Vector3d center;
    std::string error;
    ros::Time stamp;
    if (lookupFrame(follower.frame, Eigen::Vector3d::Zero(), center, stamp, error))
      world_->setSphereCenter(follower.sphere, center);
    else
      ROS_WARN_THROTTLE_NAMED(5.0, "colliders", "sphere '%s' follows frame '%s', which is not available: %s",
                              follower.sphere.c_str(), follower.frame.c_str(), error.c_str());
  }
}

void SimNode::broadcastScriptedFrames(const ros::Time& stamp)
{
  for (const scene::ScriptedFrameDef& frame : scene_.frames)
  {
    const Eigen::Vector3d x = frame.position(stamp.toSec());
    geometry_msgs::TransformStamped transform;
    transform.header.stamp = stamp;
    transform.header.frame_id = settings_.frame_id;
    transform.child_frame_id = frame.name;
    transform.transform.translation.x = x.x();
    transform.transform.translation.y = x.y();
    transform.transform.translation.z = x.z();
    transform.transform.rotation.w = 1.0;
    tf_broadcaster_->sendTransform(transform);
  }
}

void SimNode::publish()
{
  const double sim_time = world_->simTime();
  const ros::Time stamp(sim_time);

  // /clock: from sim time, never 0, only when it moved (forward: sim time never goes back).
  if (settings_.publish_clock && sim_time > 0.0 && sim_time > last_clock_time_)
  {
    auto clock = boost::make_shared<rosgraph_msgs::Clock>();
    clock->clock = stamp;
    clock_pub_.publish(clock);
    last_clock_time_ = sim_time;
  }

  // tf: the sim frame under its parent, re-sent only with a newer stamp (no TF_REPEATED_DATA).
  if (sim_time > last_tf_time_)
  {
    geometry_msgs::TransformStamped transform;
    transform.header.stamp = stamp;
    transform.header.frame_id = settings_.parent_frame_id;
    transform.child_frame_id = settings_.frame_id;
    transform.transform.translation.x = settings_.frame_offset[0];
    transform.transform.translation.y = settings_.frame_offset[1];
    transform.transform.translation.z = settings_.frame_offset[2];
    transform.transform.rotation.w = 1.0;
    tf_broadcaster_->sendTransform(transform);
    broadcastScriptedFrames(stamp);
    last_tf_time_ = sim_time;
  }

  // Cloth and jelly meshes, one message per body, only when someone listens.
  if (meshes_pub_.getNumSubscribers() > 0)
  {
    for (const auto& body : world_->bodies())
    {
      if (body->kind() != core::BodyKind::SpringNetwork) continue;
      const auto& spring_body = static_cast<const core::SpringNetworkBody&>(*body);
      if (spring_body.definition().triangles.empty()) continue;
      meshes_pub_.publish(boost::make_shared<ClothMesh>(buildClothMesh(spring_body, stamp, settings_.frame_id)));
    }
  }

  // Status, only when someone listens. Messages are published as shared pointers and never
  // touched again, so that a nodelet in the same process gets them without a copy.
  if (status_pub_.getNumSubscribers() > 0) status_pub_.publish(buildStatus(stamp));

  // Markers are only built when someone listens.
  if (markers_pub_.getNumSubscribers() == 0) return;
  auto markers = boost::make_shared<visualization_msgs::MarkerArray>(
      buildMarkers(*world_, stamp, style_, delete_all_pending_, removed_bodies_));
  markers_pub_.publish(markers);
  delete_all_pending_ = false;
  removed_bodies_.clear();
}

void SimNode::printStatus()
{
  const double sim_time = world_->simTime();
  const double wall_elapsed = secondsSince(status_window_.start);
  const double rtf = wall_elapsed > 0.0 ? (sim_time - status_window_.sim_time_at_start) / wall_elapsed : 0.0;
  const double step_us =
      status_window_.steps ? 1e6 * status_window_.step_seconds / static_cast<double>(status_window_.steps) : 0.0;
  // The implicit solves of the last step: most CG iterations and worst relative residual.
  int cg_iterations = 0;
  double cg_residual = 0.0;
  bool any_implicit = false;
  for (const auto& body : world_->bodies())
  {
    if (body->kind() != core::BodyKind::SpringNetwork) continue;
    const auto& spring_body = static_cast<const core::SpringNetworkBody&>(*body);
    if (integratorThatRan(spring_body) != core::IntegratorType::ImplicitEuler) continue;
    any_implicit = true;
    cg_iterations = std::max(cg_iterations, spring_body.lastSolve().iterations);
    cg_residual = std::max(cg_residual, spring_body.lastSolve().relative_residual);
  }
  char solver[96] = "";
  if (any_implicit)
    std::snprintf(solver, sizeof(solver), " | CG %d iterations, residual %.1e", cg_iterations, cg_residual);
  ROS_INFO_NAMED("status", "sim time %.3f s | real-time factor %.2f | live particles %d | step %.1f us%s%s", sim_time,
                 rtf, world_->particleCount(), step_us, solver, paused_ ? " | paused" : "");
  status_window_.restart(sim_time, paused_);
}

bool SimNode::spawnEmitter(SpawnEmitter::Request& req, SpawnEmitter::Response& res)
{
  // The request becomes the same EmitterDef a scene file builds, checked by the same validate().
  core::EmitterDef def;
  def.name = req.name;
  if (!core::parseEmitterType(req.type, def.type))
    return answer(res, core::Status::failure("type = " + quoteName(req.type) +
                                             " is not an emitter type; allowed: " + core::emitterTypeNames()));
  def.origin = {req.origin.x, req.origin.y, req.origin.z};
  def.rate = req.rate;
  if (core::Status s = readCount("burst_count", req.burst_count, def.burst_count); !s) return answer(res, s);
  def.speed = req.speed;
  def.spread = req.spread;
  if (req.lifetime != 0.0) def.lifetime = req.lifetime;
  if (req.mass != 0.0) def.particle_mass = req.mass;
  if (req.max_particles != 0)
  {
    if (core::Status s = readCount("max_particles", req.max_particles, def.max_particles); !s) return answer(res, s);
  }
  def.seed = req.seed != 0 ? req.seed : core::deriveSeed(world_->definition().seed, def.name);

  core::Status status = world_->addEmitter(def);
  if (status)
    status.message = "spawned " + std::string(core::toString(def.type)) + " emitter " + quoteName(def.name);
  else
    ROS_WARN_NAMED("services", "spawn_emitter refused: %s", toMessageText(status.message).c_str());
  return answer(res, status);
}

bool SimNode::spawnRope(SpawnRope::Request& req, SpawnRope::Response& res)
{
  // The request becomes the same RopeDef a scene file builds, checked by the same validate().
  core::RopeDef def;
  def.name = req.name;
  if (req.particles != 0)
  {
    if (core::Status s = readCount("particles", req.particles, def.particles); !s) return answer(res, s);
  }
  def.start = {req.start.x, req.start.y, req.start.z};
  def.end = {req.end.x, req.end.y, req.end.z};
  if (req.mass != 0.0) def.mass = req.mass;
  def.rest_length = req.rest_length;
  def.stretch_stiffness = req.stretch_stiffness;
  def.stretch_damping = req.stretch_damping;
  def.bend_stiffness = req.bend_stiffness;
  def.bend_damping = req.bend_damping;
  def.pins.assign(req.pins.begin(), req.pins.end());
  def.integrator = default_integrator_;
  if (core::Status s = parseIntegratorField(req.integrator, def.integrator); !s) return answer(res, s);
  core::Status status = world_->addRope(def);
  if (status)
    status.message = "spawned rope " + quoteName(def.name) + " with " + std::to_string(def.particles) + " particles, " +
                     core::toString(def.integrator.type);
  else
    ROS_WARN_NAMED("services", "spawn_rope refused: %s", toMessageText(status.message).c_str());
  return answer(res, status);
}

bool SimNode::pinParticle(PinParticle::Request& req, PinParticle::Response& res)
{
  res.index = -1;
  core::SpringNetworkBody* body = world_->findSpringBody(req.body);
  if (!body)
    return answer(res,
                  core::Status::failure("body = " + quoteName(req.body) + ": no rope or spring network has that name"));
  const Eigen::Vector3d point(req.point.x, req.point.y, req.point.z);
  int index = req.index;
  if (index == -1)
  {
    if (!point.allFinite())
      return answer(
          res, core::Status::failure("point = [" + formatReceived(point.x()) + ", " + formatReceived(point.y()) + ", " +
                                     formatReceived(point.z()) + "] m is not finite"));
    index = body->nearestParticle(point);
  }
  else if (index < 0 || index >= body->particles().size())
  {
    return answer(res, core::Status::failure("index = " + std::to_string(index) + " is out of range: must be in [0, " +
                                             std::to_string(body->particles().size() - 1) +
                                             "], or -1 for the particle nearest to point"));
  }

  Eigen::Vector3d target;
  std::string what;
  switch (req.target)
  {
    case PinParticle::Request::TARGET_CURRENT:
      target = body->particles().position.col(index);
      what = "where it is";
      break;
    case PinParticle::Request::TARGET_POINT:
      target = point;
      what = "at the given point";
      break;
    case PinParticle::Request::TARGET_FRAME: {
      const Eigen::Vector3d offset(req.offset.x, req.offset.y, req.offset.z);
      if (req.frame.empty()) return answer(res, core::Status::failure("frame is empty: name the tf frame to follow"));
      if (!offset.allFinite())
        return answer(
            res, core::Status::failure("offset = [" + formatReceived(offset.x()) + ", " + formatReceived(offset.y()) +
                                       ", " + formatReceived(offset.z()) + "] m is not finite"));
      // Answered at once from what tf knows (it has listened since the start): never wait here,
      // the loop would stall.
      std::string error;
      ros::Time stamp;
      if (!lookupFrame(req.frame, offset, target, stamp, error))
        return answer(res,
                      core::Status::failure("frame = " + quoteName(req.frame) + " is unknown to tf: no transform to " +
                                            quoteName(settings_.frame_id) + " (" + error + ")"));
      what = "to frame " + quoteName(req.frame);
      break;
    }
    default:
      return answer(res, core::Status::failure("target = " + std::to_string(req.target) +
                                               " is out of range: 0 (current), 1 (point) or 2 (frame)"));
  }
  core::Status status = body->pin(index, target);
  if (!status) return answer(res, status);

  // A particle follows at most one frame: replace any earlier frame pin of it.
  frame_pins_.erase(std::remove_if(frame_pins_.begin(), frame_pins_.end(),
                                   [&](const FramePin& p) { return p.body == req.body && p.index == index; }),
                    frame_pins_.end());
  if (req.target == PinParticle::Request::TARGET_FRAME)
    frame_pins_.push_back({req.body, index, req.frame, Eigen::Vector3d(req.offset.x, req.offset.y, req.offset.z),
                           ros::Time(), SteadyClock::now()});
  res.index = index;
  return answer(res, core::Status::success("pinned particle " + std::to_string(index) + " of " + quoteName(req.body) +
                                           " " + what));
}

bool SimNode::unpinParticle(UnpinParticle::Request& req, UnpinParticle::Response& res)
{
  core::SpringNetworkBody* body = world_->findSpringBody(req.body);
  if (!body)
    return answer(res,
                  core::Status::failure("body = " + quoteName(req.body) + ": no rope or spring network has that name"));
  core::Status status = body->unpin(req.index);
  if (status) status.message = "released particle " + std::to_string(req.index) + " of " + quoteName(req.body);
  return answer(res, status);
}

core::Status SimNode::applySpringConstants(const std::string& body_name, const std::string& class_name,
                                           double stiffness, double damping)
{
  core::SpringNetworkBody* body = world_->findSpringBody(body_name);
  if (!body)
    return core::Status::failure("body = " + quoteName(body_name) + ": no rope or spring network has that name");
  std::optional<core::SpringClass> spring_class;
  if (class_name != "all")
  {
    core::SpringClass parsed;
    if (!core::parseSpringClass(class_name, parsed))
      return core::Status::failure("spring_class = " + quoteName(class_name) +
                                   " is not a spring class; allowed: stretch, shear, bend, all");
    spring_class = parsed;
  }
  core::Status status = body->setSpringConstants(spring_class, stiffness, damping);
  if (status)
  {
    // Say what the change means for stability: the new frequency bound and, for an explicit
    // integrator, how many substeps a step of dt will take (auto re-decides at the next step).
    std::ostringstream message;
    message << "set " << class_name << " springs of '" << body_name << "' to " << stiffness << " N/m, " << damping
            << " N·s/m; omega_max <= " << body->frequencyBound() << " 1/s";
    const core::IntegratorType type = body->integrator().type;
    const double limit = core::stabilityLimit(type);
    if (std::isfinite(limit) && type != core::IntegratorType::Auto)
    {
      const double product = world_->dt() * (body->frequencyBound() + body->dampingBound());
      const int substeps = std::max(1, static_cast<int>(std::ceil(product / (0.9 * limit))));
      message << ", so " << core::toString(type) << " takes " << std::min(substeps, body->integrator().max_substeps)
              << " substep(s) per step of " << world_->dt() << " s";
      if (substeps > body->integrator().max_substeps)
        message << " (it would need " << substeps << ", above max_substeps: expect it to freeze)";
    }
    else if (type == core::IntegratorType::Auto)
    {
      const double product = world_->dt() * (body->frequencyBound() + body->dampingBound());
      message << ", so auto will use " << (product <= 1.0 ? "verlet" : "implicit_euler");
    }
    status.message = message.str();
  }
  return status;
}

bool SimNode::readSpringConstants(const std::string& body_name, const std::string& class_name, double& stiffness,
                                  double& damping) const
{
  const core::SpringNetworkBody* body = world_->findSpringBody(body_name);
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

bool SimNode::setSpringConstants(SetSpringConstants::Request& req, SetSpringConstants::Response& res)
{
  const core::Status status = applySpringConstants(req.body, req.spring_class, req.stiffness, req.damping);
  if (status)
  {
    // dynamic_reconfigure (rqt) shows the body just changed.
    config_.body = req.body;
    config_.spring_class = req.spring_class;
    config_.stiffness = req.stiffness;
    config_.damping = req.damping;
    reconfigure_server_->updateConfig(config_);
  }
  return answer(res, status);
}

SimConfig SimNode::currentConfig() const
{
  SimConfig config = config_;
  const core::Environment& env = world_->environment();
  config.gravity_x = env.gravity.x();
  config.gravity_y = env.gravity.y();
  config.gravity_z = env.gravity.z();
  config.global_damping = env.damping;
  config.wind_x = env.air.wind.x();
  config.wind_y = env.air.wind.y();
  config.wind_z = env.air.wind.z();
  config.real_time_factor = settings_.real_time_factor;
  config.rate = settings_.rate;
  config.integrator = core::toString(default_integrator_.type);
  // Show the first spring body, if there is one, so that rqt has something to edit.
  if (config.body.empty() || !world_->findSpringBody(config.body))
  {
    config.body.clear();
    for (const auto& body : world_->bodies())
    {
      if (body->kind() != core::BodyKind::SpringNetwork) continue;
      config.body = body->name();
      break;
    }
  }
  if (config.spring_class.empty()) config.spring_class = "stretch";
  if (!readSpringConstants(config.body, config.spring_class, config.stiffness, config.damping) &&
      !readSpringConstants(config.body, "all", config.stiffness, config.damping))
  {
    config.stiffness = 0.0;
    config.damping = 0.0;
  }
  return config;
}

void SimNode::reconfigure(SimConfig& config, std::uint32_t level)
{
  // Runs in run()'s callAvailable(), between two steps. A value the world refuses is put back, so
  // rqt always shows what the simulation uses.
  auto refuse = [](const std::string& what, const core::Status& status) {
    ROS_WARN_NAMED("reconfigure", "%s refused: %s", what.c_str(), toMessageText(status.message).c_str());
  };
  if (level & 1u)
  {
    if (core::Status s = world_->setGravity({config.gravity_x, config.gravity_y, config.gravity_z}); !s)
    {
      refuse("gravity", s);
      config.gravity_x = config_.gravity_x, config.gravity_y = config_.gravity_y, config.gravity_z = config_.gravity_z;
    }
    if (core::Status s = world_->setGlobalDamping(config.global_damping); !s)
    {
      refuse("global_damping", s);
      config.global_damping = config_.global_damping;
    }
    if (core::Status s = world_->setWind({config.wind_x, config.wind_y, config.wind_z}); !s)
    {
      refuse("wind", s);
      config.wind_x = config_.wind_x, config.wind_y = config_.wind_y, config.wind_z = config_.wind_z;
    }
  }
  if (level & 2u)
  {
    settings_.real_time_factor = config.real_time_factor;
    if (config.rate != settings_.rate)
    {
      settings_.rate = config.rate;
      updateSubsteps();
    }
  }
  if (level & 4u)
  {
    core::IntegratorType type;
    if (core::parseIntegratorType(config.integrator, type))
      default_integrator_.type = type;
    else
    {
      refuse("integrator", core::Status::failure("integrator = " + quoteName(config.integrator) +
                                                 " is not an integrator; allowed: " + core::integratorTypeNames()));
      config.integrator = config_.integrator;
    }
  }
  if (level & 8u)
  {
    // New constants are applied to the body shown; choosing another body or class (constants
    // unchanged) shows that one's constants.
    const bool constants_changed = config.stiffness != config_.stiffness || config.damping != config_.damping;
    const bool selection_changed = config.body != config_.body || config.spring_class != config_.spring_class;
    if (constants_changed && !config.body.empty())
    {
      const core::Status s = applySpringConstants(config.body, config.spring_class, config.stiffness, config.damping);
      if (s)
        ROS_INFO_NAMED("reconfigure", "%s", s.message.c_str());
      else
      {
        refuse("spring constants", s);
        config.body = config_.body, config.spring_class = config_.spring_class;
        config.stiffness = config_.stiffness, config.damping = config_.damping;
      }
    }
    else if (selection_changed && !config.body.empty())
    {
      if (!readSpringConstants(config.body, config.spring_class, config.stiffness, config.damping))
      {
        refuse("body", core::Status::failure("body = " + quoteName(config.body) + " has no " + config.spring_class +
                                             " springs (or is not a rope, cloth, jelly or spring network)"));
        config.body = config_.body, config.spring_class = config_.spring_class;
      }
    }
  }
  config_ = config;
}

bool SimNode::spawnCloth(SpawnCloth::Request& req, SpawnCloth::Response& res)
{
  core::ClothGridDef def;
  def.name = req.name;
  if (!req.model.empty() && !core::parseClothModel(req.model, def.model))
    return answer(res, core::Status::failure("model = " + quoteName(req.model) +
                                             " is not a cloth model; allowed: springs, baraff_witkin"));
  if (req.b_u != 0.0) def.b_u = req.b_u;
  if (req.b_v != 0.0) def.b_v = req.b_v;
  def.origin = {req.origin.x, req.origin.y, req.origin.z};
  def.edge_u = {req.edge_u.x, req.edge_u.y, req.edge_u.z};
  def.edge_v = {req.edge_v.x, req.edge_v.y, req.edge_v.z};
  if (req.nu != 0)
  {
    if (core::Status s = readCount("nu", req.nu, def.nu); !s) return answer(res, s);
  }
  if (req.nv != 0)
  {
    if (core::Status s = readCount("nv", req.nv, def.nv); !s) return answer(res, s);
  }
  if (req.mass != 0.0) def.mass = req.mass;
  def.stretch = {req.stretch_stiffness, req.stretch_damping};
  def.shear = {req.shear_stiffness, req.shear_damping};
  def.bend = {req.bend_stiffness, req.bend_damping};
  def.pins.assign(req.pins.begin(), req.pins.end());
  def.named_pins = req.named_pins;
  def.strain_limit.max_strain = req.max_strain;
  def.integrator = default_integrator_;
  if (core::Status s = parseIntegratorField(req.integrator, def.integrator); !s) return answer(res, s);
  core::Status status = world_->addClothGrid(def);
  if (status)
    status.message = "spawned " + std::string(core::toString(def.model)) + " cloth " + quoteName(def.name) + " of " +
                     std::to_string(def.nu) + " x " + std::to_string(def.nv) + " particles";
  else
    ROS_WARN_NAMED("services", "spawn_cloth refused: %s", toMessageText(status.message).c_str());
  return answer(res, status);
}

bool SimNode::spawnJelly(SpawnJelly::Request& req, SpawnJelly::Response& res)
{
  core::JellyDef def;
  def.name = req.name;
  def.origin = {req.origin.x, req.origin.y, req.origin.z};
  def.size = {req.size.x, req.size.y, req.size.z};
  if (req.nx != 0)
  {
    if (core::Status s = readCount("nx", req.nx, def.nx); !s) return answer(res, s);
  }
  if (req.ny != 0)
  {
    if (core::Status s = readCount("ny", req.ny, def.ny); !s) return answer(res, s);
  }
  if (req.nz != 0)
  {
    if (core::Status s = readCount("nz", req.nz, def.nz); !s) return answer(res, s);
  }
  if (req.mass != 0.0) def.mass = req.mass;
  def.stretch = {req.stretch_stiffness, req.stretch_damping};
  def.shear = {req.shear_stiffness, req.shear_damping};
  def.bend = {req.bend_stiffness, req.bend_damping};
  def.velocity = {req.velocity.x, req.velocity.y, req.velocity.z};
  def.pins.assign(req.pins.begin(), req.pins.end());
  def.strain_limit.max_strain = req.max_strain;
  def.integrator = default_integrator_;
  if (core::Status s = parseIntegratorField(req.integrator, def.integrator); !s) return answer(res, s);
  core::Status status = world_->addJelly(def);
  if (status)
    status.message =
        "spawned jelly " + quoteName(def.name) + " of " + std::to_string(def.nx * def.ny * def.nz) + " particles";
  else
    ROS_WARN_NAMED("services", "spawn_jelly refused: %s", toMessageText(status.message).c_str());
  return answer(res, status);
}

bool SimNode::setWind(SetWind::Request& req, SetWind::Response& res)
{
  const Eigen::Vector3d wind(req.wind.x, req.wind.y, req.wind.z);
  core::Status status = world_->setWind(wind);
  if (status)
  {
    std::ostringstream message;
    message << "wind set to [" << wind.x() << ", " << wind.y() << ", " << wind.z() << "] m/s";
    if (world_->environment().air.drag == 0.0) message << "; world.air.drag is 0, so nothing feels it";
    status.message = message.str();
  }
  return answer(res, status);
}

bool SimNode::removeBody(RemoveBody::Request& req, RemoveBody::Response& res)
{
  core::Status status = world_->removeBody(req.name);
  if (status)
  {
    forgetBody(req.name);
    status.message = "removed " + quoteName(req.name);
  }
  return answer(res, status);
}

void SimNode::forgetBody(const std::string& name)
{
  // Markers: a listening rviz gets a DELETE for the body's ids. With nobody listening, or many
  // removals between two arrays, the next array starts with a DELETEALL instead, so that nothing
  // piles up here.
  if (!delete_all_pending_ && markers_pub_.getNumSubscribers() > 0 && removed_bodies_.size() < kMaxRemovedBodiesTracked)
    removed_bodies_.push_back(name);
  else
  {
    delete_all_pending_ = true;
    removed_bodies_.clear();
    removed_bodies_.shrink_to_fit();
  }
  // Everything else the node kept about it.
  reported_frozen_.erase(name);
  reported_events_.erase(name);
  reported_auto_.erase(name);
  for (std::size_t k = frame_pins_.size(); k-- > 0;)
  {
    if (frame_pins_[k].body == name) frame_pins_.erase(frame_pins_.begin() + static_cast<std::ptrdiff_t>(k));
  }
  // dynamic_reconfigure shows another body (or none) instead of the removed one.
  if (config_.body == name)
  {
    config_.body.clear();
    config_ = currentConfig();
    reconfigure_server_->updateConfig(config_);
  }
}

bool SimNode::reset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res)
{
  world_->reset();
  delete_all_pending_ = true;
  config_ = currentConfig();  // spring constants are back to the built ones
  reconfigure_server_->updateConfig(config_);
  std::ostringstream message;
  message << "reset every body; sim time goes on from " << world_->simTime() << " s";
  return answer(res, core::Status::success(message.str()));
}

bool SimNode::pausePhysics(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res)
{
  paused_ = true;
  status_window_.paused = diagnostics_window_.paused = true;
  return answer(res, core::Status::success("paused at sim time " + std::to_string(world_->simTime()) + " s"));
}

bool SimNode::unpausePhysics(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res)
{
  if (step_job_.active)
    return answer(res,
                  core::Status::failure("a ~step of " + std::to_string(step_job_.requested) + " steps is running (" +
                                        std::to_string(step_job_.remaining) + " left): unpause after its answer"));
  paused_ = false;
  return answer(res, core::Status::success("running from sim time " + std::to_string(world_->simTime()) + " s"));
}

bool SimNode::step(Step::Request& req, Step::Response& res)
{
  // Runs in step_thread_: hand the request to the loop and wait for its answer, which comes when
  // every step has run (the loop serves everything else between slices meanwhile).
  std::unique_lock<std::mutex> lock(step_mutex_);
  if (step_service_closing_)
  {
    res.success = false;
    res.message = "the node is shutting down";
    return true;
  }
  step_request_steps_ = req.steps;
  step_requested_ = true;
  step_answer_ready_ = false;
  step_answered_.wait(lock, [this] { return step_answer_ready_; });
  step_answer_ready_ = false;
  res = step_answer_;
  return true;
}

void SimNode::deliverStepAnswer(const Step::Response& answer)
{
  {
    std::lock_guard<std::mutex> lock(step_mutex_);
    step_answer_ = answer;
    step_answer_.message = toMessageText(answer.message);
    step_requested_ = false;
    step_answer_ready_ = true;
  }
  step_answered_.notify_all();
}

long long SimNode::stabilityEventCount() const
{
  long long events = 0;
  for (const auto& body : world_->bodies())
  {
    if (const auto* spring_body = world_->findSpringBody(body->name())) events += spring_body->stabilityEvents();
  }
  return events;
}

void SimNode::acceptStepRequest()
{
  std::uint32_t steps = 0;
  {
    std::lock_guard<std::mutex> lock(step_mutex_);
    if (!step_requested_ || step_answer_ready_ || step_job_.active) return;
    steps = step_request_steps_;
  }
  Step::Response res;
  res.success = false;
  if (!paused_)
    res.message = "the simulation is running: call ~pause_physics before ~step";
  else if (steps < 1 || steps > kMaxStepsPerCall)
    res.message = "steps = " + std::to_string(steps) + " is out of range: must be in [1, " +
                  std::to_string(kMaxStepsPerCall) + "] per call (call ~step again for more)";
  else
  {
    // Accepted: the loop runs it in slices from this tick on.
    step_job_.active = true;
    step_job_.requested = step_job_.remaining = steps;
    step_job_.events_before = stabilityEventCount();
    return;
  }
  res.sim_time = world_->simTime();
  deliverStepAnswer(res);
}

void SimNode::runStepSlice()
{
  // One tick's worth of substeps per slice, whatever their cost: callbacks, ~status and markers
  // come between every two slices, so a long ~step is seen tick by tick as if running unpaused
  // as fast as possible (and how many ticks it takes does not depend on the machine's speed).
  const std::uint64_t chunk = std::min(static_cast<std::uint64_t>(substeps_), step_job_.remaining);
  stepPhysics(chunk);
  step_job_.remaining -= chunk;
}

void SimNode::finishStepJob()
{
  // Stability events and freezes during these steps are part of the answer.
  Step::Response res;
  std::string message = "advanced " + std::to_string(step_job_.requested) + " steps";
  const long long events = stabilityEventCount() - step_job_.events_before;
  std::string last_event;
  std::vector<std::string> frozen;
  for (const auto& body : world_->bodies())
  {
    const auto* spring_body = world_->findSpringBody(body->name());
    if (!spring_body) continue;
    if (!spring_body->lastStabilityEvent().empty())
      last_event = quoteName(body->name()) + ": " + spring_body->lastStabilityEvent();
    if (spring_body->frozen()) frozen.push_back(quoteName(body->name()) + " (" + spring_body->frozenReason() + ")");
  }
  if (events > 0) message += "; " + std::to_string(events) + " stability events, last " + last_event;
  if (!frozen.empty())
  {
    message += "; frozen: ";
    for (std::size_t k = 0; k < frozen.size(); ++k)
      message += (k ? ", " : "") + frozen[k];
  }
  step_job_.active = false;
  res.success = true;
  res.message = message;
  res.sim_time = world_->simTime();
  deliverStepAnswer(res);
}

SimStatus::Ptr SimNode::buildStatus(const ros::Time& stamp) const
{
  auto status = boost::make_shared<SimStatus>();
  status->header.stamp = stamp;
  status->header.frame_id = settings_.frame_id;
  status->sim_time = world_->simTime();
  status->step_count = world_->stepCount();
  status->paused = paused_;
  status->real_time_factor = settings_.real_time_factor;
  const core::Environment& env = world_->environment();
  status->gravity = toVector3(env.gravity);
  status->global_damping = env.damping;
  status->wind = toVector3(env.air.wind);
  status->bodies.reserve(world_->bodies().size());
  for (const auto& body : world_->bodies())
  {
    BodyStatus b;
    b.name = body->name();
    b.particle_count = static_cast<std::uint32_t>(body->particles().size());
    if (body->kind() == core::BodyKind::Emitter)
    {
      const auto& emitter = static_cast<const core::EmitterBody&>(*body);
      b.type = "emitter";
      b.model = core::toString(emitter.definition().type);
      // Free particles of equal mass: kinetic and gravitational potential energy.
      const core::ParticlePool& p = emitter.particles();
      const double m = emitter.definition().particle_mass;
      for (int i = 0; i < p.size(); ++i)
      {
        b.kinetic_energy += 0.5 * m * p.velocity.col(i).squaredNorm();
        b.potential_energy -= m * env.gravity.dot(p.position.col(i));
      }
    }
    else if (body->kind() == core::BodyKind::SpringNetwork)
    {
      const auto& spring_body = static_cast<const core::SpringNetworkBody&>(*body);
      b.type = core::toString(spring_body.shape());
      b.model = spring_body.definition().baraff_witkin.empty() ? core::toString(core::ClothModel::Springs)
                                                               : core::toString(core::ClothModel::BaraffWitkin);
      b.integrator = core::toString(spring_body.integrator().type);
      b.last_integrator = core::toString(integratorThatRan(spring_body));
      b.auto_choice = spring_body.autoChoice();
      b.substeps = static_cast<std::uint32_t>(spring_body.lastSubsteps());
      b.stability_events = static_cast<std::uint64_t>(spring_body.stabilityEvents());
      b.last_stability_event = spring_body.lastStabilityEvent();
      b.kinetic_energy = spring_body.kineticEnergy();
      b.potential_energy = spring_body.potentialEnergy(env.gravity);
      b.max_strain = spring_body.maxStrain();
      b.pinned_count = static_cast<std::uint32_t>(spring_body.pinnedCount());
      b.solver_iterations = static_cast<std::uint32_t>(std::max(0, spring_body.lastSolve().iterations));
      b.solver_residual = spring_body.lastSolve().relative_residual;
      b.frozen = spring_body.frozen();
      b.frozen_reason = spring_body.frozenReason();
    }
    status->bodies.push_back(std::move(b));
  }
  return status;
}

void SimNode::produceDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& stat)
{
  using diagnostic_msgs::DiagnosticStatus;
  const Window& w = diagnostics_window_;
  const double wall = secondsSince(w.start);
  const double rtf = wall > 0.0 ? (world_->simTime() - w.sim_time_at_start) / wall : 0.0;
  const double step_us = w.steps ? 1e6 * w.step_seconds / static_cast<double>(w.steps) : 0.0;

  // Over the spring bodies: the last implicit solves, strain and frozen bodies.
  int iterations = 0, not_converged = 0;
  double residual = 0.0, max_strain = 0.0;
  std::string strained_body;
  std::vector<std::string> frozen;
  for (const auto& body : world_->bodies())
  {
    if (body->kind() != core::BodyKind::SpringNetwork) continue;
    const auto& spring_body = static_cast<const core::SpringNetworkBody&>(*body);
    if (spring_body.frozen())
    {
      frozen.push_back(toMessageText(body->name(), kMaxQuotedBytes) + " (" +
                       core::toString(integratorThatRan(spring_body)) + ": " + spring_body.frozenReason() + ")");
      continue;
    }
    if (integratorThatRan(spring_body) == core::IntegratorType::ImplicitEuler)
    {
      iterations = std::max(iterations, spring_body.lastSolve().iterations);
      residual = std::max(residual, spring_body.lastSolve().relative_residual);
      if (!spring_body.lastSolve().converged) ++not_converged;
    }
    const double strain = spring_body.maxStrain();
    if (strain > max_strain)
    {
      max_strain = strain;
      strained_body = body->name();
    }
  }

  stat.summary(DiagnosticStatus::OK, w.paused || paused_ ? "paused" : "running");
  char text[256];
  // Thresholds: README "Diagnostics".
  if (!frozen.empty())
  {
    std::string names;
    for (const std::string& name : frozen)
      names += (names.empty() ? "" : ", ") + name;
    stat.mergeSummary(DiagnosticStatus::ERROR, "frozen bodies: " + names);
  }
  if (!w.paused && !paused_ && settings_.real_time_factor > 0.0 &&
      rtf < kRealTimeFactorWarnRatio * settings_.real_time_factor)
  {
    std::snprintf(text, sizeof(text), "real-time factor %.3g below %.0f %% of the target %.3g", rtf,
                  100.0 * kRealTimeFactorWarnRatio, settings_.real_time_factor);
    stat.mergeSummary(DiagnosticStatus::WARN, text);
  }
  if (not_converged > 0)
    stat.mergeSummary(DiagnosticStatus::WARN,
                      std::to_string(not_converged) + " implicit solves did not reach cg_tolerance in their last step");
  if (events_since_diagnostics_ > 0)
    stat.mergeSummary(DiagnosticStatus::WARN, std::to_string(events_since_diagnostics_) +
                                                  " stability events since the last report (see ~status)");
  if (max_strain > settings_.diagnostic_max_strain)
  {
    std::snprintf(text, sizeof(text), "max strain %.3g of '%s' above %.3g", max_strain, strained_body.c_str(),
                  settings_.diagnostic_max_strain);
    stat.mergeSummary(DiagnosticStatus::WARN, text);
  }

  stat.add("sim time [s]", world_->simTime());
  stat.add("paused", paused_);
  stat.add("real-time factor", rtf);
  stat.add("target real-time factor", settings_.real_time_factor);
  stat.add("step time [us]", step_us);
  stat.add("steps per tick", substeps_);
  stat.add("live particles", world_->particleCount());
  stat.add("bodies", static_cast<int>(world_->bodies().size()));
  stat.add("solver iterations (max, last step)", iterations);
  stat.add("solver residual (max, last step)", residual);
  stat.add("max strain", max_strain);
  stat.add("frozen bodies", static_cast<int>(frozen.size()));
  stat.add("stability events since last report", events_since_diagnostics_);
  events_since_diagnostics_ = 0;
}

}  // namespace ros_interface
}  // namespace particle_sim
