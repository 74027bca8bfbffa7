#pragma once

#include <functional>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/builders/jelly.h"
#include "particle_sim/core/builders/mesh_cloth.h"
#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/emitter.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/status.h"
#include "particle_sim/core/world.h"

namespace particle_sim
{
namespace scene
{
/// One body entry of a scene file, as the core definition it builds.
using BodyDef = std::variant<core::EmitterDef, core::RopeDef, core::SpringNetworkDef, core::ClothGridDef,
                             core::MeshClothDef, core::JellyDef>;

/// A frame the scene moves by itself (a stand-in for a robot's gripper or tool): it goes round a
/// horizontal circle, or through a list of waypoints. The node broadcasts it on tf; pins, grasps
/// and colliders can follow it.
struct ScriptedFrameDef
{
  /// Where the frame is at sim time `t`.
  struct Waypoint
  {
    double t = 0.0;                                      ///< [s]
    Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< [m] in the sim frame
  };

  std::string name;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< [m] in the sim frame
  double radius = 0.5;                               ///< [m] >= 0
  double period = 4.0;                               ///< [s] > 0, one turn
  double phase = 0.0;                                ///< [rad] angle at t = 0
  /// When not empty, the frame goes through these instead of the circle (times strictly increasing):
  /// from each to the next along the straight line with a minimum-jerk profile (it stops at every
  /// waypoint, with no jump in velocity or acceleration); before the first and after the last it
  /// stays there.
  std::vector<Waypoint> waypoints;

  /// Position [m] at sim time t [s]: on the waypoints' path, or on the circle center + radius
  /// (cos(2πt/period + phase), sin(...), 0).
  Eigen::Vector3d position(double t) const;
};

/// A pinned particle that follows a frame (scripted, or any tf frame in the node) at an offset.
struct FramePinDef
{
  std::string body;
  int index = 0;
  std::string frame;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< [m] in the frame
};

/// A sphere collider that follows a frame (its centre is the frame's origin).
struct FrameSphereDef
{
  std::string sphere;
  std::string frame;
};

/// A box or capsule collider that follows a frame: its centre is the frame's origin; a tf frame
/// also gives its orientation (a scripted frame has none: the collider keeps its own).
struct FrameColliderDef
{
  std::string collider;
  std::string frame;
};

/// A whole scene: world settings, named bodies in file order, and what follows frames.
struct SceneDef
{
  core::WorldDef world;
  std::vector<BodyDef> bodies;
  std::vector<ScriptedFrameDef> frames;
  std::vector<FramePinDef> frame_pins;
  std::vector<FrameSphereDef> frame_spheres;
  std::vector<FrameColliderDef> frame_colliders;
};

/// The scripted frame called `name`, or null.
const ScriptedFrameDef* findFrame(const SceneDef& scene, const std::string& name);

/// Moves everything that follows a scripted frame to where the frame is at sim time `t`: pin
/// targets (frame position + offset), sphere centres, and box and capsule centres, which move
/// there over the next `h` [s] (their velocity in contacts; 0 places them at rest). Frames that are
/// not scripted are left to the caller (the node looks them up on tf).
core::Status applyScriptedFrames(const SceneDef& scene, double t, core::World& world, double h = 0.0);

/// The one step every front-end shares (the node, the nodelet, particle_sim_run, particle_sim_bench,
/// the golden test): moves what follows scripted frames to where the frames are at the end of the
/// step (sim time + dt), then advances the world by one step of dt. The world steps even when a
/// follower could not be moved; the status says why. Frames that only tf provides are the node's to
/// move before calling this.
core::Status stepScene(const SceneDef& scene, core::World& world);

/// Applies `edit` to the world's default integrator and to the integrator of every spring body of
/// `scene` (rope, spring network, grid and mesh cloth, jelly; emitters have none), before the world
/// is built: what `particle_sim_run --integrator` and the bench mean by "this integrator". A body
/// is edited as it would integrate (its settings over the edited world's), and then sets the
/// fields where that differs from the world's.
void editIntegrators(SceneDef& scene, const std::function<void(core::IntegratorDef&)>& edit);

/// Parses scene YAML text. Unknown keys, wrong types and out-of-range or non-finite values are
/// refused with a message that starts with `source:line:` and names the key, the value and what is
/// allowed. Values are checked by the same core validate() functions the node's services use.
core::Status parseScene(const std::string& yaml_text, const std::string& source, SceneDef& scene);

/// Reads and parses a scene file.
core::Status loadSceneFile(const std::string& path, SceneDef& scene);

/// Builds a world with every body of `scene`.
core::Status buildWorld(const SceneDef& scene, std::unique_ptr<core::World>& world);

/// Adds one body definition to a world (used by buildWorld and by the node's spawn services).
core::Status addBody(const BodyDef& body, core::World& world);

/// Writes `scene` back as YAML that parseScene() reads into the same definitions.
std::string toYaml(const SceneDef& scene);

}  // namespace scene
}  // namespace particle_sim
