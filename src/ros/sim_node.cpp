#include "particle_sim/ros/sim_node.h"

#include <geometry_msgs/TransformStamped.h>
#include <rosgraph_msgs/Clock.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <thread>
#include <type_traits>
#include <variant>

#include "particle_sim/ros/material_conversions.h"
#include "particle_sim/ros/mesh_builder.h"
#include "particle_sim/ros/message_text.h"
#include "particle_sim/ros/names.h"
#include "particle_sim/ros/pin_wrench.h"
#include "particle_sim/ros/point_cloud_builder.h"
#include "particle_sim/ros/request_conversions.h"
#include "particle_sim/ros/spring_constants.h"
#include "particle_sim/ros/status_report.h"
#include "particle_sim/ros/tick_schedule.h"
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

// The publishing thread's send of one message (held until sent, then let go).
template <class Message>
PublishingThread::Send sendOf(const ros::Publisher& publisher, boost::shared_ptr<Message> message)
{
  return [publisher, message = std::move(message)] { publisher.publish(message); };
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
  // Parameters are checked before anything starts; a bad one stops the node with its reason.
  settings_ = readNodeSettings(private_node_);
  const NodeSettings& s = settings_;
  auto refuse = [](const std::string& message) {
    ROS_FATAL_NAMED("sim", "%s", message.c_str());
    return false;
  };
  if (core::Status status = validate(s); !status) return refuse(status.message);

  scene::SceneDef& scene = scene_;
  if (!s.scene_path.empty())
  {
    if (core::Status status = scene::loadSceneFile(s.scene_path, scene); !status) return refuse(status.message);
  }
  if (s.dt != 0.0) scene.world.dt = s.dt;
  if (s.max_particles_per_body != 0) scene.world.max_particles_per_body = s.max_particles_per_body;
  if (s.max_particles_per_world != 0) scene.world.max_particles_per_world = s.max_particles_per_world;
  if (s.threads != -1) scene.world.threads = s.threads;
  if (core::Status status = scene::buildWorld(scene, world_); !status) return refuse("~scene: " + status.message);
  // ~status names the material of the scene's ropes and cloth built of one.
  for (const scene::BodyDef& body : scene.bodies)
  {
    std::visit(
        [this](const auto& def) {
          using Def = std::decay_t<decltype(def)>;
          if constexpr (std::is_same_v<Def, core::RopeDef> || std::is_same_v<Def, core::ClothGridDef> ||
                        std::is_same_v<Def, core::MeshClothDef>)
          {
            if (def.material) body_materials_[def.name] = def.material->name;
          }
        },
        body);
  }
  // Scene pins that follow frames other than the scene's scripted ones follow them through tf.
  for (const scene::FramePinDef& pin : scene.frame_pins)
  {
    if (!scene::findFrame(scene, pin.frame)) frame_followers_.follow(pin.body, pin.index, pin.frame, pin.offset);
  }

  updateSubsteps();
  default_integrator_ = world_->definition().integrator;
  paused_ = s.paused;
  style_.frame_id = s.frame_id;
  style_.particle_size = s.particle_size;
  style_.max_points = s.max_marker_points;
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
  points_pub_ = private_node_.advertise<sensor_msgs::PointCloud2>(names::kPointsTopic, 10);
  if (settings_.drag_markers)
    drag_markers_ = std::make_unique<DragMarkers>(private_node_, settings_.frame_id, settings_.particle_size);
  if (settings_.publish_clock) clock_pub_ = node_.advertise<rosgraph_msgs::Clock>(names::kClockTopic, 10);
  tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
  // tf is listened to from the start (on the listener's own thread), so that a pin request can be
  // answered at once from what tf already knows.
  frame_followers_.startListening(settings_.frame_id);
  frame_followers_.useScriptedFrames(scene_, [this] { return world_->simTime(); });

  services_.push_back(private_node_.advertiseService(names::kSpawnEmitter, &SimNode::spawnEmitter, this));
  services_.push_back(private_node_.advertiseService(names::kRemoveBody, &SimNode::removeBody, this));
  services_.push_back(private_node_.advertiseService(names::kSpawnCollider, &SimNode::spawnCollider, this));
  services_.push_back(private_node_.advertiseService(names::kRemoveCollider, &SimNode::removeCollider, this));
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
  services_.push_back(private_node_.advertiseService(names::kGrasp, &SimNode::grasp, this));
  services_.push_back(private_node_.advertiseService(names::kRelease, &SimNode::release, this));

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

  // dynamic_reconfigure, from the world as built and the parameters read above.
  reconfigure_ = std::make_unique<ReconfigureHandler>(private_node_, *world_, settings_, default_integrator_,
                                                      [this] { updateSubsteps(); });

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

  publishing_.stop();  // sends the batch in progress, then nothing more
  drag_markers_.reset();
  reconfigure_.reset();
  diagnostics_.reset();
  services_.clear();
  frame_followers_.stopListening();
  tf_broadcaster_.reset();
  for (ros::Publisher* publisher : {&markers_pub_, &meshes_pub_, &clock_pub_, &status_pub_, &points_pub_})
    publisher->shutdown();
  pin_wrench_pubs_.clear();
  pin_wrench_topic_owner_.clear();
  grasp_wrench_pubs_.clear();
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

    // Wait for the next tick. A late tick is made up: the next ones follow at once until the loop
    // is back on its schedule, so that sim time keeps up with the wall clock through a hiccup (the
    // machine busy with other work, a long service). Lag beyond ~max_lag is dropped instead (the
    // schedule starts again from now; the diagnostics count it), and so is any while paused or
    // running as fast as possible.
    const bool keeps_schedule = !paused_ && settings_.real_time_factor > 0.0;
    const NextTick next = nextTick(next_tick, paused_ ? paused_period : wall_period, SteadyClock::now(),
                                   std::chrono::duration<double>(keeps_schedule ? settings_.max_lag : 0.0));
    next_tick = next.due;
    if (keeps_schedule) diagnostics_window_.lag_dropped += next.dropped;
    if (step_job_.active) next_tick = SteadyClock::now();  // a ~step in slices: the next slice at once
    waitForTick(next_tick);
  }

  // Let go of every ROS handle here, in the loop's thread, while ROS still exists: in a nodelet
  // manager the simulator may otherwise be destroyed after ROS's own singletons, and its
  // publishers and servers would unregister from destroyed objects.
  releaseInterfaces();
  callback_queue_.disable();
  callback_queue_.clear();
}

void SimNode::waitForTick(std::chrono::steady_clock::time_point next_tick)
{
  // The wait serves services and dynamic_reconfigure as they arrive, so that a request waits for
  // the tick in progress at most, never for the idle rest of the period. They still run between two
  // ticks, in this thread, as before. Each wait lasts at most 50 ms, so that a stop (a signal, ROS
  // shutting down) is seen at once even at a slow ~rate.
  constexpr double kLongestWait = 0.05;  // [s]
  for (auto now = SteadyClock::now(); now < next_tick && ros::ok() && !stop_requested_; now = SteadyClock::now())
    callback_queue_.callAvailable(
        ros::WallDuration(std::min(kLongestWait, std::chrono::duration<double>(next_tick - now).count())));
}

void SimNode::tick()
{
  // A snapshot of the emitters' particles serves the markers of the tick whose last step took it,
  // never a later tick's (services between ticks may have changed the particles).
  marker_samples_[free_samples_].asked = false;
  if (drag_markers_) drag_markers_->beginTick(*world_);  // mouse events from rviz, paused or not
  if (step_job_.active)
    runStepSlice();
  else if (!paused_)
    stepPhysics(substeps_, ServeRequests::BetweenSteps);
  publish();
  if (step_job_.active && step_job_.remaining == 0) finishStepJob();
}

std::uint64_t SimNode::stepPhysics(std::uint64_t steps, ServeRequests serve)
{
  frame_followers_.beginTick(*world_, scene_);
  const auto start = SteadyClock::now();
  double serving = 0.0;  // [s] spent on requests between steps, not on physics
  std::uint64_t ran = 0;
  std::uint64_t segment = 0;  // the step the frame targets were last computed at
  bool snapshot_asked = false;
  while (ran < steps)
  {
    // The tick's last step copies the emitters' particles that the markers will draw as it moves
    // them (marker_builder.h), when markers are wanted.
    if (ran + 1 == steps && markers_pub_.getNumSubscribers() > 0)
    {
      snapshotNextStep(*world_, style_, marker_samples_[free_samples_]);
      snapshot_asked = true;
    }
    // tf-followed pins move in equal parts towards this tick's frame pose.
    frame_followers_.moveTargets(*world_, ran - segment, steps - segment);
    // The step every front-end shares: scripted frames where they are at the end of this step
    // (known exactly), then the world's step.
    scene::stepScene(scene_, *world_);
    ++ran;
    // A request that arrived during this step is served before the next one, so that it waits for
    // one step at most rather than for the rest of the tick. A pause takes effect at once; other
    // requests may have changed pins and bodies, so the frame targets are computed again for the
    // steps left.
    if (serve == ServeRequests::BetweenSteps && ran < steps && !callback_queue_.isEmpty())
    {
      const auto served = SteadyClock::now();
      callback_queue_.callAvailable();
      serving += secondsSince(served);
      if (paused_) break;
      frame_followers_.beginTick(*world_, scene_);
      segment = ran;
    }
  }
  if (snapshot_asked) forgetSnapshotRequests(*world_);
  const double seconds = secondsSince(start) - serving;
  for (Window* window : {&status_window_, &diagnostics_window_})
  {
    window->step_seconds += seconds;
    window->steps += ran;
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
  if (ran > 0 && !grasps_.all().empty()) updateGrasps();
  return ran;
}

void SimNode::updateGrasps()
{
  std::vector<HeldParticle> let_go;
  const auto pose_of = [this](const std::string& frame, Eigen::Isometry3d& pose) {
    std::string error;
    ros::Time stamp;
    return frame_followers_.lookupPose(frame, pose, stamp, error);
  };
  for (const std::string& name : grasps_.update(*world_, pose_of, world_->simTime(), let_go))
    ROS_WARN_NAMED("grasps", "grasp %s broke away at sim time %.4f s: %s", quoteName(name).c_str(), world_->simTime(),
                   grasps_.find(name)->release_reason.c_str());
  unfollow(let_go);
}

void SimNode::unfollow(const std::vector<HeldParticle>& let_go)
{
  for (const auto& [body, index] : let_go)
    frame_followers_.unfollow(body, index);
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
    for (const geometry_msgs::TransformStamped& frame : scriptedFrameTransforms(scene_, settings_.frame_id, stamp))
      tf_broadcaster_->sendTransform(frame);
    last_tf_time_ = sim_time;
  }

  publishPinWrenches(stamp);
  // Each active grasp's wrench in its gripper frame, only while someone listens.
  for (const GraspState& grasp : grasps_.all())
  {
    const auto publisher = grasp_wrench_pubs_.find(grasp.spec.name);
    if (grasp.released || publisher == grasp_wrench_pubs_.end() || publisher->second.getNumSubscribers() == 0) continue;
    publisher->second.publish(boost::make_shared<geometry_msgs::WrenchStamped>(buildGraspWrench(grasp, stamp)));
  }

  // Status, only when someone listens. Messages are published as shared pointers and never
  // touched again, so that a nodelet in the same process gets them without a copy.
  if (status_pub_.getNumSubscribers() > 0)
  {
    auto status = boost::make_shared<SimStatus>(
        buildSimStatus(*world_, stamp, settings_.frame_id, paused_, settings_.real_time_factor, body_materials_));
    for (const GraspState& grasp : grasps_.all())
      status->grasps.push_back(toGraspStatus(grasp));
    status_pub_.publish(status);
  }

  publishHeavyMessages(stamp);
}

void SimNode::publishHeavyMessages(const ros::Time& stamp)
{
  // Markers, meshes and point clouds are built here, each only when someone listens, and sent by
  // the publishing thread (~publishing_thread), where roscpp serialises them and writes them to the
  // subscribers' sockets. While it still sends the last tick's, this tick's are skipped rather than
  // queued: the physics never waits for a subscriber.
  const bool markers_wanted = markers_pub_.getNumSubscribers() > 0;
  const bool meshes_wanted = meshes_pub_.getNumSubscribers() > 0;
  const bool points_wanted = points_pub_.getNumSubscribers() > 0;
  if (!markers_wanted && !meshes_wanted && !points_wanted) return;
  if (settings_.publishing_thread && publishing_.busy())
  {
    ++diagnostics_window_.ticks_skipped;
    return;
  }
  ++diagnostics_window_.ticks_sent;

  // Cloth and jelly meshes, one message per body.
  if (meshes_wanted)
  {
    for (const auto& body : world_->bodies())
    {
      if (body->kind() != core::BodyKind::SpringNetwork) continue;
      const auto& spring_body = static_cast<const core::SpringNetworkBody&>(*body);
      // Every body built with a surface, also one whose triangles all tore away: its empty mesh
      // replaces the last one it had.
      if (spring_body.definition().triangles.empty()) continue;
      sends_.push_back(
          sendOf(meshes_pub_, boost::make_shared<ClothMesh>(buildClothMesh(spring_body, stamp, settings_.frame_id))));
    }
  }
  // Every body's particles as one point cloud.
  if (points_wanted)
    sends_.push_back(sendOf(points_pub_, boost::make_shared<sensor_msgs::PointCloud2>(buildPointCloud(
                                             *world_, stamp, settings_.frame_id, settings_.points_surface_only))));
  // Markers: the emitters' particles (up to ~max_marker_points of them) come from the tick's last
  // step, and their points and colours are written by the thread that sends them, off the physics
  // thread. The other set of samples is free for the next tick.
  if (markers_wanted)
  {
    MarkerSamples& samples = marker_samples_[free_samples_];
    free_samples_ = 1 - free_samples_;
    auto markers = boost::make_shared<visualization_msgs::MarkerArray>(
        buildMarkersDeferred(*world_, stamp, style_, delete_all_pending_, removed_bodies_, samples));
    sends_.push_back([publisher = markers_pub_, markers, samples = &samples] {
      finishMarkers(*samples, *markers);
      publisher.publish(markers);
    });
    delete_all_pending_ = false;
    removed_bodies_.clear();
  }

  if (settings_.publishing_thread)
  {
    publishing_.submit(sends_);
    return;
  }
  for (const PublishingThread::Send& send : sends_)
    send();
  sends_.clear();
}

void SimNode::publishPinWrenches(const ros::Time& stamp)
{
  for (const auto& body : world_->bodies())
  {
    if (body->kind() != core::BodyKind::SpringNetwork) continue;
    const auto& spring_body = static_cast<const core::SpringNetworkBody&>(*body);
    auto publisher = pin_wrench_pubs_.find(body->name());
    if (publisher == pin_wrench_pubs_.end())
    {
      // Advertised once the body has a pin; a topic another body's name already maps to is left
      // to that body (README "Pin wrenches").
      if (spring_body.pinnedCount() == 0) continue;
      const std::string topic = pinWrenchTopic(body->name());
      const auto [owner, first] = pin_wrench_topic_owner_.emplace(topic, body->name());
      if (!first)
      {
        if (owner->second != body->name())
          ROS_WARN_ONCE_NAMED("topics", "body %s has no ~%s: body %s publishes there", quoteName(body->name()).c_str(),
                              topic.c_str(), quoteName(owner->second).c_str());
        continue;
      }
      publisher =
          pin_wrench_pubs_.emplace(body->name(), private_node_.advertise<geometry_msgs::WrenchStamped>(topic, 10))
              .first;
    }
    if (publisher->second.getNumSubscribers() == 0) continue;
    publisher->second.publish(
        boost::make_shared<geometry_msgs::WrenchStamped>(buildPinWrench(spring_body, stamp, settings_.frame_id)));
  }
}

void SimNode::printStatus()
{
  const double sim_time = world_->simTime();
  const double wall_elapsed = secondsSince(status_window_.start);
  const double rtf = wall_elapsed > 0.0 ? (sim_time - status_window_.sim_time_at_start) / wall_elapsed : 0.0;
  const double step_us =
      status_window_.steps ? 1e6 * status_window_.step_seconds / static_cast<double>(status_window_.steps) : 0.0;
  ROS_INFO_NAMED("status", "%s", statusLine(*world_, rtf, step_us, paused_).c_str());
  status_window_.restart(sim_time, paused_);
}

bool SimNode::spawnEmitter(SpawnEmitter::Request& req, SpawnEmitter::Response& res)
{
  // The request becomes the same EmitterDef a scene file builds, checked by the same validate().
  core::EmitterDef def;
  if (core::Status s = toEmitterDef(req, world_->definition().seed, def); !s) return answer(res, s);
  core::Status status = inRequestTerms(SpawnRequest::Emitter, world_->addEmitter(def));
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
  if (core::Status s = toRopeDef(req, default_integrator_, def, settings_.rope_material); !s) return answer(res, s);
  core::Status status = inRequestTerms(SpawnRequest::Rope, world_->addRope(def));
  if (status)
  {
    status.message = "spawned rope " + quoteName(def.name) + " with " + std::to_string(def.particles) + " particles, " +
                     core::toString(world_->findSpringBody(def.name)->integrator().type) +
                     (def.material ? ", " + materialText(def.material->name) : "");
    if (def.material) body_materials_[def.name] = def.material->name;
  }
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
  PinSpec spec;
  if (core::Status s = toPinSpec(req, *body, spec); !s) return answer(res, s);

  std::string what;
  switch (spec.target)
  {
    case PinTarget::Current:
      what = "where it is";
      break;
    case PinTarget::Point:
      what = "at the given point";
      break;
    case PinTarget::Frame: {
      // Answered at once from what tf knows (it has listened since the start): never wait here,
      // the loop would stall.
      std::string error;
      ros::Time stamp;
      if (!frame_followers_.lookup(spec.frame, spec.offset, spec.point, stamp, error))
        return answer(res,
                      core::Status::failure("frame = " + quoteName(spec.frame) + " is unknown to tf: no transform to " +
                                            quoteName(settings_.frame_id) + " (" + error + ")"));
      what = "to frame " + quoteName(spec.frame);
      break;
    }
  }
  core::Status status = body->pin(spec.index, spec.point);
  if (!status) return answer(res, status);
  grasps_.forgetParticle(req.body, spec.index);  // held by this pin now, not by a grasp

  // A particle follows at most one frame: this one, or none any more.
  const int index = spec.index;
  if (spec.target == PinTarget::Frame)
    frame_followers_.follow(req.body, index, spec.frame, spec.offset);
  else
    frame_followers_.unfollow(req.body, index);
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
  if (status) grasps_.forgetParticle(req.body, req.index);
  if (status) status.message = "released particle " + std::to_string(req.index) + " of " + quoteName(req.body);
  return answer(res, status);
}

bool SimNode::setSpringConstants(SetSpringConstants::Request& req, SetSpringConstants::Response& res)
{
  const core::Status status = applySpringConstants(*world_, req.body, req.spring_class, req.stiffness, req.damping);
  // dynamic_reconfigure (rqt) shows the body just changed.
  if (status) reconfigure_->showSpringConstants(req.body, req.spring_class, req.stiffness, req.damping);
  return answer(res, status);
}

bool SimNode::spawnCloth(SpawnCloth::Request& req, SpawnCloth::Response& res)
{
  core::ClothGridDef def;
  if (core::Status s = toClothGridDef(req, default_integrator_, def, settings_.cloth_material); !s)
    return answer(res, s);
  core::Status status = inRequestTerms(SpawnRequest::Cloth, world_->addClothGrid(def));
  if (status)
  {
    status.message = "spawned " + std::string(core::toString(def.model)) + " cloth " + quoteName(def.name) + " of " +
                     std::to_string(def.nu) + " x " + std::to_string(def.nv) + " particles" +
                     (def.material ? ", " + materialText(def.material->name) : "");
    if (def.material) body_materials_[def.name] = def.material->name;
  }
  else
    ROS_WARN_NAMED("services", "spawn_cloth refused: %s", toMessageText(status.message).c_str());
  return answer(res, status);
}

bool SimNode::spawnJelly(SpawnJelly::Request& req, SpawnJelly::Response& res)
{
  core::JellyDef def;
  if (core::Status s = toJellyDef(req, default_integrator_, def); !s) return answer(res, s);
  core::Status status = inRequestTerms(SpawnRequest::Jelly, world_->addJelly(def));
  if (status)
    status.message =
        "spawned jelly " + quoteName(def.name) + " of " + std::to_string(def.nx * def.ny * def.nz) + " particles";
  else
    ROS_WARN_NAMED("services", "spawn_jelly refused: %s", toMessageText(status.message).c_str());
  return answer(res, status);
}

bool SimNode::setWind(SetWind::Request& req, SetWind::Response& res)
{
  const Eigen::Vector3d wind = toWind(req);
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

bool SimNode::spawnCollider(SpawnCollider::Request& req, SpawnCollider::Response& res)
{
  bool is_box = true;
  core::BoxColliderDef box;
  core::CapsuleColliderDef capsule;
  core::Status status = toColliderDef(req, is_box, box, capsule);
  if (status) status = is_box ? world_->addCollider(box) : world_->addCollider(capsule);
  if (!status)
  {
    ROS_WARN_NAMED("services", "spawn_collider refused: %s", toMessageText(status.message).c_str());
    return answer(res, status);
  }
  // It follows its tf frame as a scene's collider does (FrameFollowers reads the scene each tick).
  if (!req.frame.empty()) scene_.frame_colliders.push_back({req.name, req.frame});
  status.message = "spawned " + req.shape + " " + quoteName(req.name) +
                   (req.frame.empty() ? std::string() : " following frame " + quoteName(req.frame));
  return answer(res, status);
}

bool SimNode::removeCollider(RemoveCollider::Request& req, RemoveCollider::Response& res)
{
  core::Status status = world_->removeCollider(req.name);
  if (!status) return answer(res, status);
  auto& followers = scene_.frame_colliders;
  followers.erase(std::remove_if(followers.begin(), followers.end(),
                                 [&](const scene::FrameColliderDef& f) { return f.collider == req.name; }),
                  followers.end());
  auto& spheres = scene_.frame_spheres;
  spheres.erase(std::remove_if(spheres.begin(), spheres.end(),
                               [&](const scene::FrameSphereDef& f) { return f.sphere == req.name; }),
                spheres.end());
  // The colliders' marker ids are their places in the list: the next array starts afresh.
  delete_all_pending_ = true;
  status.message = "removed collider " + quoteName(req.name);
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
  body_materials_.erase(name);
  reported_auto_.erase(name);
  frame_followers_.forgetBody(name);
  pin_wrench_pubs_.erase(name);
  if (drag_markers_) drag_markers_->forgetBody(name);
  grasps_.forgetBody(name);  // a grasp left holding nothing is gone, with its topic
  for (auto topic = grasp_wrench_pubs_.begin(); topic != grasp_wrench_pubs_.end();)
    topic = grasps_.find(topic->first) ? std::next(topic) : grasp_wrench_pubs_.erase(topic);
  for (auto topic = pin_wrench_topic_owner_.begin(); topic != pin_wrench_topic_owner_.end();)
    topic = topic->second == name ? pin_wrench_topic_owner_.erase(topic) : std::next(topic);
  // dynamic_reconfigure shows another body (or none) instead of the removed one.
  reconfigure_->forgetBody(name);
}

bool SimNode::reset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res)
{
  world_->reset();
  if (drag_markers_) drag_markers_->forgetAll();
  grasps_.clear();  // the bodies are as built: nothing is held (the frame followers drop the pins reset undid)
  grasp_wrench_pubs_.clear();
  delete_all_pending_ = true;
  reconfigure_->showWorld();  // spring constants are back to the built ones
  std::ostringstream message;
  message << "reset every body; sim time goes on from " << world_->simTime() << " s";
  return answer(res, core::Status::success(message.str()));
}

bool SimNode::grasp(Grasp::Request& req, Grasp::Response& res)
{
  res.captured = 0;
  GraspSpec spec;
  if (core::Status s = toGraspSpec(req, spec); !s) return answer(res, s);
  // The gripper's pose now, from what tf knows (never waiting: the loop would stall).
  Eigen::Isometry3d pose;
  ros::Time stamp;
  std::string error;
  if (!frame_followers_.lookupPose(spec.frame, pose, stamp, error))
    return answer(res,
                  core::Status::failure("frame = " + quoteName(spec.frame) + " is unknown to tf: no transform to " +
                                        quoteName(settings_.frame_id) + " (" + error + ")"));
  if (core::Status s = grasps_.grasp(*world_, spec, pose); !s) return answer(res, s);

  // The caught particles follow the frame at their places in it: rigidly, orientation included.
  const GraspState& held = *grasps_.find(spec.name);
  std::string bodies;
  for (const GraspState::Hold& hold : held.holds)
  {
    for (const core::CapturedParticle& particle : hold.particles)
      frame_followers_.follow(hold.body, particle.index, spec.frame, particle.offset);
    bodies += (bodies.empty() ? "" : ", ") + quoteName(hold.body);
  }
  grasp_wrench_pubs_[spec.name] =
      private_node_.advertise<geometry_msgs::WrenchStamped>(graspWrenchTopic(spec.name), 10);
  res.captured = static_cast<std::uint32_t>(held.particleCount());
  return answer(res, core::Status::success("grasp " + quoteName(spec.name) + " holds " + std::to_string(res.captured) +
                                           " particles of " + bodies + " in frame " + quoteName(spec.frame)));
}

bool SimNode::release(Release::Request& req, Release::Response& res)
{
  std::vector<HeldParticle> let_go;
  const core::Status status = grasps_.release(*world_, req.name, let_go);
  unfollow(let_go);
  if (status) grasp_wrench_pubs_.erase(req.name);
  res.released = static_cast<std::uint32_t>(let_go.size());
  return answer(res, status);
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
    step_job_.events_before = stabilityEventCount(*world_);
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
  stepPhysics(chunk, ServeRequests::AfterTick);
  step_job_.remaining -= chunk;
}

void SimNode::finishStepJob()
{
  // Stability events and freezes during these steps are part of the answer.
  Step::Response res;
  const long long events = stabilityEventCount(*world_) - step_job_.events_before;
  step_job_.active = false;
  res.success = true;
  res.message = stepReport(*world_, step_job_.requested, events);
  res.sim_time = world_->simTime();
  deliverStepAnswer(res);
}

void SimNode::produceDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& stat)
{
  const Window& w = diagnostics_window_;
  const double wall = secondsSince(w.start);
  LoopFigures loop;
  loop.real_time_factor = wall > 0.0 ? (world_->simTime() - w.sim_time_at_start) / wall : 0.0;
  loop.target_real_time_factor = settings_.real_time_factor;
  loop.step_time_us = w.steps ? 1e6 * w.step_seconds / static_cast<double>(w.steps) : 0.0;
  loop.steps_per_tick = substeps_;
  loop.paused = paused_;
  loop.paused_in_window = w.paused;
  loop.stability_events = events_since_diagnostics_;
  loop.ticks_sent = w.ticks_sent;
  loop.ticks_skipped = w.ticks_skipped;
  loop.lag_dropped = w.lag_dropped;
  buildDiagnostics(*world_, loop, settings_.diagnostic_max_strain, stat);
  events_since_diagnostics_ = 0;
}

}  // namespace ros_interface
}  // namespace particle_sim
