// What a scene does while it runs: its scripted frames move, what follows them moves along, and
// the one step every front-end shares (stepScene).

#include <cmath>
#include <type_traits>

#include "particle_sim/scene/scene.h"

namespace particle_sim
{
namespace scene
{
Eigen::Vector3d ScriptedFrameDef::position(double t) const
{
  // Waypoints: between w_k and w_k+1, x = x_k + (x_k+1 − x_k) s(u), u = (t − t_k) / (t_k+1 − t_k),
  // with the minimum-jerk profile s(u) = 10 u³ − 15 u⁴ + 6 u⁵ (s' = s'' = 0 at both ends).
  if (!waypoints.empty())
  {
    if (t <= waypoints.front().t) return waypoints.front().position;
    for (std::size_t k = 0; k + 1 < waypoints.size(); ++k)
    {
      const Waypoint& a = waypoints[k];
      const Waypoint& b = waypoints[k + 1];
      if (t > b.t) continue;
      const double u = (t - a.t) / (b.t - a.t);
      const double s = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
      return a.position + s * (b.position - a.position);
    }
    return waypoints.back().position;
  }
  const double angle = 2.0 * M_PI * t / period + phase;
  return center + radius * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
}

const ScriptedFrameDef* findFrame(const SceneDef& scene, const std::string& name)
{
  for (const ScriptedFrameDef& frame : scene.frames)
  {
    if (frame.name == name) return &frame;
  }
  return nullptr;
}

core::Status applyScriptedFrames(const SceneDef& scene, double t, core::World& world, double h)
{
  for (const FramePinDef& pin : scene.frame_pins)
  {
    const ScriptedFrameDef* frame = findFrame(scene, pin.frame);
    core::SpringNetworkBody* body = world.findSpringBody(pin.body);
    if (!frame || !body || !body->isPinned(pin.index)) continue;
    if (core::Status s = body->setPinTarget(pin.index, frame->position(t) + pin.offset); !s) return s;
  }
  for (const FrameSphereDef& follower : scene.frame_spheres)
  {
    if (const ScriptedFrameDef* frame = findFrame(scene, follower.frame))
    {
      if (core::Status s = world.setSphereCenter(follower.sphere, frame->position(t)); !s) return s;
    }
  }
  for (const FrameColliderDef& follower : scene.frame_colliders)
  {
    const ScriptedFrameDef* frame = findFrame(scene, follower.frame);
    Eigen::Vector3d center;
    Eigen::Quaterniond orientation;
    if (!frame || !world.colliderPose(follower.collider, center, orientation)) continue;
    if (core::Status s = world.setColliderPose(follower.collider, frame->position(t), orientation, h); !s) return s;
  }
  return core::Status::success();
}

core::Status stepScene(const SceneDef& scene, core::World& world)
{
  // Pins and spheres that follow scripted frames go where the frames are at the end of the step.
  const core::Status moved = applyScriptedFrames(scene, world.simTime() + world.dt(), world, world.dt());
  world.step();
  return moved;
}

namespace
{
// Makes `body` give `wanted` over `defaults`: it sets each field where they differ, and keeps
// what it set already (equal fields it does not set stay the world's).
void setWhereDifferent(core::BodyIntegratorDef& body, const core::IntegratorDef& wanted,
                       const core::IntegratorDef& defaults)
{
  auto set = [](auto& field, const auto& want, const auto& fallback) {
    if (field || want != fallback) field = want;
  };
  set(body.type, wanted.type, defaults.type);
  set(body.verlet_damping, wanted.verlet_damping, defaults.verlet_damping);
  set(body.cg_tolerance, wanted.cg_tolerance, defaults.cg_tolerance);
  set(body.cg_velocity_tolerance, wanted.cg_velocity_tolerance, defaults.cg_velocity_tolerance);
  set(body.cg_max_iterations, wanted.cg_max_iterations, defaults.cg_max_iterations);
  set(body.max_substeps, wanted.max_substeps, defaults.max_substeps);
  set(body.linear_solver, wanted.linear_solver, defaults.linear_solver);
}
}  // namespace

void editIntegrators(SceneDef& scene, const std::function<void(core::IntegratorDef&)>& edit)
{
  edit(scene.world.integrator);
  for (BodyDef& body : scene.bodies)
  {
    std::visit(
        [&](auto& def) {
          if constexpr (!std::is_same_v<std::decay_t<decltype(def)>, core::EmitterDef>)
          {
            // The body's settings as the world will give them, edited.
            core::IntegratorDef settings = core::resolve(def.integrator, scene.world.integrator);
            edit(settings);
            setWhereDifferent(def.integrator, settings, scene.world.integrator);
          }
        },
        body);
  }
}

}  // namespace scene
}  // namespace particle_sim
