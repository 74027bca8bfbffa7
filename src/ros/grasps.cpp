#include "particle_sim/ros/grasps.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "particle_sim/core/limits.h"
#include "particle_sim/core/names.h"
#include "particle_sim/core/validation.h"
#include "particle_sim/ros/eigen_messages.h"
#include "particle_sim/ros/message_text.h"

namespace particle_sim
{
namespace ros_interface
{
core::Status toGraspSpec(const Grasp::Request& req, GraspSpec& spec)
{
  namespace limits = core::limits;
  if (core::Status s = core::validateBodyName(req.name); !s) return s;
  if (req.frame.empty()) return core::Status::failure("frame is empty: name the gripper's tf frame");
  spec.name = req.name;
  spec.body = req.body;
  spec.frame = req.frame;
  spec.region.center = toEigen(req.offset);
  if (core::Status s = core::checkRange("offset", spec.region.center, limits::kGraspOffset); !s) return s;
  switch (req.region)
  {
    case Grasp::Request::REGION_SPHERE:
      spec.region.shape = core::CaptureRegion::Shape::Sphere;
      spec.region.radius = req.radius;
      if (core::Status s = core::checkRange("radius", req.radius, limits::kGraspSize); !s) return s;
      break;
    case Grasp::Request::REGION_BOX:
      spec.region.shape = core::CaptureRegion::Shape::Box;
      spec.region.half_extents = toEigen(req.half_extents);
      if (core::Status s = core::checkRange("half_extents", spec.region.half_extents, limits::kGraspSize); !s) return s;
      break;
    case Grasp::Request::REGION_NEAREST:
      spec.region.shape = core::CaptureRegion::Shape::Nearest;
      if (core::Status s = core::checkRange("count", req.count, limits::kGraspCount); !s) return s;
      spec.region.count = static_cast<int>(req.count);
      break;
    default:
      return core::Status::failure("region = " + std::to_string(req.region) +
                                   " is out of range: 0 (sphere), 1 (box) or 2 (nearest)");
  }
  spec.breakaway_force = req.breakaway_force;
  return core::checkRange("breakaway_force", req.breakaway_force, limits::kBreakawayForce);
}

int GraspState::particleCount() const
{
  int count = 0;
  for (const Hold& hold : holds)
    count += static_cast<int>(hold.particles.size());
  return count;
}

const GraspState* Grasps::find(const std::string& name) const
{
  for (const GraspState& grasp : grasps_)
    if (grasp.spec.name == name) return &grasp;
  return nullptr;
}

namespace
{
// Keeps the region's `count` particles nearest its centre over all of `state`'s holds (ties: the
// earlier body, then the lower index); holds left empty go.
void keepNearest(GraspState& state)
{
  struct Candidate
  {
    double distance;
    std::size_t hold;
    std::size_t at;
  };
  std::vector<Candidate> candidates;
  for (std::size_t h = 0; h < state.holds.size(); ++h)
    for (std::size_t k = 0; k < state.holds[h].particles.size(); ++k)
      candidates.push_back({(state.holds[h].particles[k].offset - state.spec.region.center).norm(), h, k});
  const std::size_t keep = std::min(candidates.size(), static_cast<std::size_t>(state.spec.region.count));
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.distance < b.distance; });
  std::vector<std::vector<bool>> kept(state.holds.size());
  for (std::size_t h = 0; h < state.holds.size(); ++h)
    kept[h].assign(state.holds[h].particles.size(), false);
  for (std::size_t c = 0; c < keep; ++c)
    kept[candidates[c].hold][candidates[c].at] = true;
  for (std::size_t h = 0; h < state.holds.size(); ++h)
  {
    std::vector<core::CapturedParticle> particles;
    for (std::size_t k = 0; k < state.holds[h].particles.size(); ++k)
      if (kept[h][k]) particles.push_back(state.holds[h].particles[k]);
    state.holds[h].particles = std::move(particles);
  }
  state.holds.erase(std::remove_if(state.holds.begin(), state.holds.end(),
                                   [](const GraspState::Hold& hold) { return hold.particles.empty(); }),
                    state.holds.end());
}
}  // namespace

core::Status Grasps::grasp(core::World& world, const GraspSpec& spec, const Eigen::Isometry3d& frame_pose)
{
  const GraspState* same_name = find(spec.name);
  if (same_name && !same_name->released)
    return core::Status::failure("name = " + quoteName(spec.name) + " is held by an active grasp: release it first");
  if (!spec.body.empty() && !world.findSpringBody(spec.body))
    return core::Status::failure("body = " + quoteName(spec.body) +
                                 ": no rope, cloth, jelly or spring network has that name");

  // Capture in every named body (or all of them); nothing changes until something is caught.
  GraspState state;
  state.spec = spec;
  state.frame_pose = frame_pose;
  int pinned_skipped = 0;
  for (const auto& body : world.bodies())
  {
    if (body->kind() != core::BodyKind::SpringNetwork) continue;
    if (!spec.body.empty() && body->name() != spec.body) continue;
    const auto& spring_body = static_cast<const core::SpringNetworkBody&>(*body);
    int skipped = 0;
    std::vector<core::CapturedParticle> caught = core::captureParticles(spring_body, frame_pose, spec.region, skipped);
    pinned_skipped += skipped;
    if (!caught.empty()) state.holds.push_back({body->name(), std::move(caught)});
  }
  // Nearest counts over every grasped body: each gave its `count` nearest, keep the overall nearest.
  if (spec.region.shape == core::CaptureRegion::Shape::Nearest && state.holds.size() > 1) keepNearest(state);
  if (state.holds.empty())
  {
    const Eigen::Vector3d center = frame_pose * spec.region.center;
    char where[160];
    std::snprintf(where, sizeof(where), "the region around [%.4g, %.4g, %.4g] m (sim frame)", center.x(), center.y(),
                  center.z());
    return core::Status::failure(
        "the grasp captured nothing: no free particle of " +
        (spec.body.empty() ? std::string("any body") : quoteName(spec.body)) + " in " + where +
        (pinned_skipped ? " (" + std::to_string(pinned_skipped) + " pinned particles there are held already)" : ""));
  }
  for (const GraspState::Hold& hold : state.holds)
  {
    core::SpringNetworkBody& body = *world.findSpringBody(hold.body);
    for (const core::CapturedParticle& particle : hold.particles)
      body.pin(particle.index, body.particles().position.col(particle.index));
  }
  grasps_.erase(
      std::remove_if(grasps_.begin(), grasps_.end(), [&](const GraspState& g) { return g.spec.name == spec.name; }),
      grasps_.end());
  grasps_.push_back(std::move(state));
  return core::Status::success();
}

namespace
{
// Unpins what `grasp` holds (each particle listed in `let_go`) and empties it.
void letGo(core::World& world, GraspState& grasp, std::vector<HeldParticle>& let_go)
{
  for (const GraspState::Hold& hold : grasp.holds)
  {
    core::SpringNetworkBody* body = world.findSpringBody(hold.body);
    if (!body) continue;
    for (const core::CapturedParticle& particle : hold.particles)
    {
      body->unpin(particle.index);
      let_go.emplace_back(hold.body, particle.index);
    }
  }
  grasp.holds.clear();
}
}  // namespace

core::Status Grasps::release(core::World& world, const std::string& name, std::vector<HeldParticle>& let_go)
{
  auto grasp = std::find_if(grasps_.begin(), grasps_.end(), [&](const GraspState& g) { return g.spec.name == name; });
  if (grasp == grasps_.end())
  {
    std::string names;
    for (const GraspState& g : grasps_)
      names += (names.empty() ? "" : ", ") + quoteName(g.spec.name);
    return core::Status::failure("name = " + quoteName(name) +
                                 ": no grasp has that name (grasps: " + (names.empty() ? "none" : names) + ")");
  }
  const bool broke_away = grasp->released;
  const int count = grasp->particleCount();
  letGo(world, *grasp, let_go);
  std::string message = "released grasp " + quoteName(name);
  if (broke_away)
    message += ", which had broken away at sim time " + core::formatValue(grasp->released_at) + " s";
  else
    message += ": let go of " + std::to_string(count) + " particles";
  grasps_.erase(grasp);
  return core::Status::success(message);
}

std::vector<std::string> Grasps::update(core::World& world,
                                        const std::function<bool(const std::string&, Eigen::Isometry3d&)>& pose_of,
                                        double sim_time, std::vector<HeldParticle>& let_go)
{
  std::vector<std::string> broke_away;
  for (GraspState& grasp : grasps_)
  {
    if (grasp.released) continue;
    Eigen::Isometry3d pose;
    if (pose_of(grasp.spec.frame, pose)) grasp.frame_pose = pose;
    // What holding the particles takes: their pin reactions summed, and their torque about the
    // gripper frame's origin.
    const Eigen::Vector3d origin = grasp.frame_pose.translation();
    grasp.force.setZero();
    grasp.torque.setZero();
    std::vector<int> indices;
    for (const GraspState::Hold& hold : grasp.holds)
    {
      const core::SpringNetworkBody* body = world.findSpringBody(hold.body);
      if (!body || hold.particles.empty()) continue;  // (pinLoad of no indices would be every pin's)
      indices.clear();
      for (const core::CapturedParticle& particle : hold.particles)
        indices.push_back(particle.index);
      const core::SpringNetworkBody::PinLoad load = body->pinLoad(indices, origin);
      grasp.force += load.force;
      grasp.torque += load.torque;
    }
    const double force = grasp.force.norm();
    if (grasp.spec.breakaway_force > 0.0 && force > grasp.spec.breakaway_force)
    {
      char reason[160];
      std::snprintf(reason, sizeof(reason), "the force %.4g N exceeded the breakaway force %.4g N", force,
                    grasp.spec.breakaway_force);
      grasp.released = true;
      grasp.released_at = sim_time;
      grasp.release_reason = reason;
      letGo(world, grasp, let_go);
      broke_away.push_back(grasp.spec.name);
    }
  }
  return broke_away;
}

void Grasps::forgetParticle(const std::string& body, int index)
{
  for (GraspState& grasp : grasps_)
    for (GraspState::Hold& hold : grasp.holds)
      if (hold.body == body)
        hold.particles.erase(std::remove_if(hold.particles.begin(), hold.particles.end(),
                                            [&](const core::CapturedParticle& p) { return p.index == index; }),
                             hold.particles.end());
}

void Grasps::forgetBody(const std::string& body)
{
  for (GraspState& grasp : grasps_)
    grasp.holds.erase(std::remove_if(grasp.holds.begin(), grasp.holds.end(),
                                     [&](const GraspState::Hold& hold) { return hold.body == body; }),
                      grasp.holds.end());
  grasps_.erase(std::remove_if(grasps_.begin(), grasps_.end(),
                               [](const GraspState& g) { return !g.released && g.holds.empty(); }),
                grasps_.end());
}

GraspStatus toGraspStatus(const GraspState& grasp)
{
  GraspStatus status;
  status.name = grasp.spec.name;
  status.frame = grasp.spec.frame;
  for (const GraspState::Hold& hold : grasp.holds)
    status.bodies.push_back(hold.body);
  status.particle_count = static_cast<std::uint32_t>(grasp.particleCount());
  status.force = toVector3(grasp.force);
  status.torque = toVector3(grasp.torque);
  status.breakaway_force = grasp.spec.breakaway_force;
  status.released = grasp.released;
  status.released_at = grasp.released_at;
  status.release_reason = grasp.release_reason;
  return status;
}

geometry_msgs::WrenchStamped buildGraspWrench(const GraspState& grasp, const ros::Time& stamp)
{
  const Eigen::Matrix3d to_gripper = grasp.frame_pose.rotation().transpose();
  geometry_msgs::WrenchStamped wrench;
  wrench.header.stamp = stamp;
  wrench.header.frame_id = grasp.spec.frame;
  wrench.wrench.force = toVector3(to_gripper * grasp.force);
  wrench.wrench.torque = toVector3(to_gripper * grasp.torque);
  return wrench;
}

}  // namespace ros_interface
}  // namespace particle_sim
