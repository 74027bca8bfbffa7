#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/transform_broadcaster.h>

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "particle_sim/Grasp.h"
#include "particle_sim/PinParticle.h"
#include "particle_sim/Release.h"
#include "particle_sim/RemoveBody.h"
#include "particle_sim/RemoveCollider.h"
#include "particle_sim/SetSpringConstants.h"
#include "particle_sim/SetWind.h"
#include "particle_sim/SimStatus.h"
#include "particle_sim/SpawnCloth.h"
#include "particle_sim/SpawnCollider.h"
#include "particle_sim/SpawnEmitter.h"
#include "particle_sim/SpawnJelly.h"
#include "particle_sim/SpawnRope.h"
#include "particle_sim/Step.h"
#include "particle_sim/UnpinParticle.h"
#include "particle_sim/core/world.h"
#include "particle_sim/ros/drag_markers.h"
#include "particle_sim/ros/frame_followers.h"
#include "particle_sim/ros/grasps.h"
#include "particle_sim/ros/marker_builder.h"
#include "particle_sim/ros/master_link.h"
#include "particle_sim/ros/parameters.h"
#include "particle_sim/ros/publishing_thread.h"
#include "particle_sim/ros/reconfigure.h"
#include "particle_sim/ros/status_report.h"
#include "particle_sim/scene/scene.h"

namespace particle_sim
{
namespace ros_interface
{
/// Most steps one ~step call may ask for (README "Services"): a longer run is several calls.
constexpr std::uint32_t kMaxStepsPerCall = 100000;
/// Removed bodies remembered for DELETE markers; beyond this (or with no marker subscriber) the
/// next array starts with a DELETEALL instead.
constexpr std::size_t kMaxRemovedBodiesTracked = 64;

/// The simulator: owns a core::World, steps it at a fixed rate on steady (wall) time, serves its
/// services, dynamic_reconfigure and diagnostics between steps and publishes markers, meshes,
/// status, tf and /clock. Used by the node's main() and by the nodelet (SimNodelet), which runs
/// run() in a thread of its own.
///
/// This class is the loop and the wiring; each concern lives in its own unit: parameters
/// (parameters.h), service requests to core definitions (request_conversions.h), ~status,
/// /diagnostics and answers built from a const world (status_report.h), dynamic_reconfigure
/// (reconfigure.h), what follows tf frames (frame_followers.h), markers and meshes
/// (marker_builder.h, mesh_builder.h).
///
/// Every callback of the simulator (services, dynamic_reconfigure) goes to the simulator's own
/// callback queue, served by run() between ticks: the world is only ever touched by one thread,
/// whether it runs in a node or in a nodelet manager with many threads.
class SimNode
{
public:
  /// `node` for /clock, `private_node` for every other name; `name` is the node's (or nodelet's)
  /// name, used as the diagnostics' hardware id and in their name.
  SimNode(ros::NodeHandle node, ros::NodeHandle private_node, const std::string& name);
  /// Stops the helper threads if run() did not (initialized but never run).
  ~SimNode();
  SimNode(const SimNode&) = delete;
  SimNode& operator=(const SimNode&) = delete;

  /// Reads parameters and loads the scene; false (after logging why) when they are unusable.
  bool initialize();

  /// Runs until ROS shuts down or stop() is called: serve callbacks, step, publish, wait for the
  /// next tick (serving callbacks as they arrive).
  void run();
  /// Makes run() return after its current tick (thread-safe).
  void stop() { stop_requested_ = true; }

private:
  // One tick: `substeps_` physics steps unless paused (or a slice of a running ~step), then publish.
  void tick();
  // Until `next_tick` (steady clock): serves our callback queue as requests arrive.
  void waitForTick(std::chrono::steady_clock::time_point next_tick);
  // Publishers, services, dynamic_reconfigure, diagnostics and the tf listener: created once by
  // initialize() and released at the end of run(), in the loop's thread.
  void advertiseInterfaces();
  void releaseInterfaces();
  // ~step runs in slices on the loop: the service waits in a thread of its own (step_thread_)
  // for the loop's answer, while the loop keeps serving callbacks and publishing between slices.
  void acceptStepRequest();
  void runStepSlice();
  void finishStepJob();
  void deliverStepAnswer(const Step::Response& answer);
  // When requests are served during a tick: only after it (its steps run whatever arrives), or
  // also between two of its steps (a pause among them ends the tick early).
  enum class ServeRequests
  {
    AfterTick,
    BetweenSteps
  };
  // Runs `steps` physics steps (fewer when a pause served between them ends the tick); returns how
  // many ran.
  std::uint64_t stepPhysics(std::uint64_t steps, ServeRequests serve);
  void publish();
  // Markers, meshes and point clouds: built here (the emitters' marker points by the publishing
  // thread, from a copy of their particles), sent by the publishing thread.
  void publishHeavyMessages(const ros::Time& stamp);
  // ~pin_wrench/<body> of every body that has pins, each built only while subscribed.
  void publishPinWrenches(const ros::Time& stamp);
  void printStatus();

  // Forgets everything the node keeps about a body that is gone.
  void forgetBody(const std::string& name);

  bool spawnEmitter(SpawnEmitter::Request& req, SpawnEmitter::Response& res);
  bool spawnRope(SpawnRope::Request& req, SpawnRope::Response& res);
  bool pinParticle(PinParticle::Request& req, PinParticle::Response& res);
  bool unpinParticle(UnpinParticle::Request& req, UnpinParticle::Response& res);
  bool setSpringConstants(SetSpringConstants::Request& req, SetSpringConstants::Response& res);
  bool spawnCloth(SpawnCloth::Request& req, SpawnCloth::Response& res);
  bool spawnJelly(SpawnJelly::Request& req, SpawnJelly::Response& res);
  bool setWind(SetWind::Request& req, SetWind::Response& res);
  bool grasp(Grasp::Request& req, Grasp::Response& res);
  bool release(Release::Request& req, Release::Response& res);
  // After a tick's steps: the grasps' forces, and those above their breakaway force let go.
  void updateGrasps();
  // The frame followers drop particles a grasp let go.
  void unfollow(const std::vector<HeldParticle>& let_go);
  bool removeBody(RemoveBody::Request& req, RemoveBody::Response& res);
  bool spawnCollider(SpawnCollider::Request& req, SpawnCollider::Response& res);
  bool removeCollider(RemoveCollider::Request& req, RemoveCollider::Response& res);
  bool reset(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  bool pausePhysics(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  bool unpausePhysics(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  bool step(Step::Request& req, Step::Response& res);

  // The loop's timing after a change of ~rate or ~real_time_factor.
  void updateSubsteps();

  // /diagnostics.
  void produceDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& stat);

  // Wall time and physics time over a window (status line, diagnostics).
  struct Window
  {
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
    double sim_time_at_start = 0.0;
    std::uint64_t steps = 0;
    double step_seconds = 0.0;
    bool paused = false;          // paused or stepped by ~step at some time in the window
    long long ticks_sent = 0;     // ticks whose markers, meshes and clouds were sent
    long long ticks_skipped = 0;  // ticks that skipped them: the publishing thread was busy
    double lag_dropped = 0.0;     // [s] wall time the loop fell behind beyond ~max_lag and did not make up
    void restart(double sim_time, bool is_paused)
    {
      start = std::chrono::steady_clock::now();
      sim_time_at_start = sim_time;
      steps = 0;
      step_seconds = 0.0;
      paused = is_paused;
      ticks_sent = ticks_skipped = 0;
      lag_dropped = 0.0;
    }
  };

  ros::CallbackQueue callback_queue_;  // before the node handles that use it
  ros::NodeHandle node_;
  ros::NodeHandle private_node_;
  std::string name_;
  std::atomic<bool> stop_requested_{false};
  NodeSettings settings_;
  MarkerStyle style_;
  scene::SceneDef scene_;  // as loaded: scripted frames and what follows frames
  std::unique_ptr<core::World> world_;
  int substeps_ = 1;
  bool paused_ = false;

  ros::Publisher markers_pub_;
  ros::Publisher meshes_pub_;
  ros::Publisher points_pub_;
  // Per body that has had pins: its ~pin_wrench topic's publisher (advertised when the body first
  // has a pin, dropped with the body); and which body publishes on which topic.
  std::map<std::string, ros::Publisher> pin_wrench_pubs_;
  std::map<std::string, std::string> pin_wrench_topic_owner_;
  ros::Publisher clock_pub_;
  ros::Publisher status_pub_;
  // The emitters' particles that markers draw, copied by the tick's last step (snapshotNextStep());
  // the publishing thread writes the markers' points from them (buildMarkersDeferred()). Two sets:
  // the loop fills marker_samples_[free_samples_] while the thread may still read the other, the
  // set of the last markers sent. Before the thread, so that they outlive it.
  std::array<MarkerSamples, 2> marker_samples_;
  int free_samples_ = 0;
  // Sends markers, meshes and clouds (~publishing_thread); after the publishers, so that it stops
  // before they go. sends_ is the batch being built, its capacity kept from tick to tick.
  PublishingThread publishing_;
  std::vector<PublishingThread::Send> sends_;
  core::IntegratorDef default_integrator_;  // of bodies spawned by services (dynamic_reconfigure "integrator")
  BodyMaterials body_materials_;            // ~status: the material of each body built of one

  std::unique_ptr<ReconfigureHandler> reconfigure_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  std::vector<ros::ServiceServer> services_;

  FrameFollowers frame_followers_;                           // tf pins and spheres that follow tf frames
  Grasps grasps_;                                            // ~grasp: captured particles that follow gripper frames
  std::unique_ptr<DragMarkers> drag_markers_;                // ~drag: particles dragged in rviz (~drag_markers)
  std::map<std::string, ros::Publisher> grasp_wrench_pubs_;  // per grasp: ~grasp_wrench/<name>

  std::set<std::string> reported_frozen_;             // frozen bodies already logged
  std::map<std::string, long long> reported_events_;  // per body, stability events already logged
  std::map<std::string, std::string> reported_auto_;  // per body, auto's choice already logged
  long long events_since_diagnostics_ = 0;

  bool delete_all_pending_ = true;
  std::vector<std::string> removed_bodies_;
  double last_tf_time_ = -1.0;
  double last_clock_time_ = -1.0;

  // Measurements for the status line and for diagnostics.
  Window status_window_;
  Window diagnostics_window_;

  // ~step: its service has a queue and a thread of their own; the request and the answer pass
  // through step_mutex_. The job itself (step_job_) is only touched by the loop.
  ros::CallbackQueue step_queue_;
  ros::ServiceServer step_service_;
  std::thread step_thread_;
  std::atomic<bool> step_thread_running_{false};
  std::mutex step_mutex_;
  std::condition_variable step_answered_;
  bool step_requested_ = false;  // a request waits for the loop
  std::uint32_t step_request_steps_ = 0;
  bool step_answer_ready_ = false;
  bool step_service_closing_ = false;  // answer at once: the node is stopping
  Step::Response step_answer_;
  struct StepJob
  {
    bool active = false;
    std::uint64_t requested = 0;
    std::uint64_t remaining = 0;
    long long events_before = 0;
  } step_job_;

  MasterLink master_link_;  // re-registers with a restarted master
};

}  // namespace ros_interface
}  // namespace particle_sim
