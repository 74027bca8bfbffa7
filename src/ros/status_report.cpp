#include "particle_sim/ros/status_report.h"

#include <diagnostic_msgs/DiagnosticStatus.h>

#include <algorithm>
#include <cstdio>
#include <numeric>
#include <sstream>
#include <utility>
#include <vector>

#include "particle_sim/core/cloth_model.h"
#include "particle_sim/core/emitter.h"
#include "particle_sim/core/integrators/implicit_euler_solver.h"
#include "particle_sim/ros/eigen_messages.h"
#include "particle_sim/ros/message_text.h"

namespace particle_sim
{
namespace ros_interface
{
core::IntegratorType integratorThatRan(const core::SpringNetworkBody& body)
{
  return body.integrator().type == core::kAutoIntegrator ? body.lastIntegrator() : body.integrator().type;
}

SimStatus buildSimStatus(const core::World& world, const ros::Time& stamp, const std::string& frame_id, bool paused,
                         double real_time_factor, const BodyMaterials& materials)
{
  SimStatus status;
  status.header.stamp = stamp;
  status.header.frame_id = frame_id;
  status.sim_time = world.simTime();
  status.step_count = world.stepCount();
  status.paused = paused;
  status.real_time_factor = real_time_factor;
  const core::Environment& env = world.environment();
  status.gravity = toVector3(env.gravity);
  status.global_damping = env.damping;
  status.wind = toVector3(env.air.wind);
  status.bodies.reserve(world.bodies().size());
  const std::vector<core::CollisionCounts>& collisions = world.lastCollisions().bodies;
  for (std::size_t i = 0; i < world.bodies().size(); ++i)
  {
    const auto& body = world.bodies()[i];
    BodyStatus b;
    b.name = body->name();
    b.particle_count = static_cast<std::uint32_t>(body->particles().size());
    b.kinetic_energy = body->kineticEnergy();
    b.potential_energy = body->potentialEnergy(env.gravity);
    // The last step's collisions between surfaces (zero for a body without self_collision).
    if (i < collisions.size())
    {
      b.proximity_pairs = collisions[i].proximity_pairs;
      b.collisions = collisions[i].collisions;
      b.impact_zone_particles = collisions[i].impact_zone_particles;
    }
    if (body->kind() == core::BodyKind::Emitter)
    {
      const auto& emitter = static_cast<const core::EmitterBody&>(*body);
      b.type = "emitter";
      b.model = core::toString(emitter.definition().type);
      b.mass = emitter.definition().particle_mass * static_cast<double>(b.particle_count);
    }
    else if (body->kind() == core::BodyKind::SpringNetwork)
    {
      const auto& spring_body = static_cast<const core::SpringNetworkBody&>(*body);
      b.type = core::toString(spring_body.shape());
      b.model = core::toString(spring_body.clothModel());
      const std::vector<double>& masses = spring_body.definition().masses;
      b.mass = std::accumulate(masses.begin(), masses.end(), 0.0);
      b.integrator = core::toString(spring_body.integrator().type);
      b.last_integrator = core::toString(integratorThatRan(spring_body));
      b.auto_choice = spring_body.autoChoice();
      b.substeps = static_cast<std::uint32_t>(spring_body.lastSubsteps());
      b.stability_events = static_cast<std::uint64_t>(spring_body.stabilityEvents());
      b.last_stability_event = spring_body.lastStabilityEvent();
      b.max_strain = spring_body.maxStrain();
      b.torn_springs = static_cast<std::uint64_t>(spring_body.tornSprings());
      b.torn_triangles = static_cast<std::uint64_t>(spring_body.tornTriangles());
      b.split_particles = static_cast<std::uint64_t>(spring_body.splitParticles());
      b.pinned_count = static_cast<std::uint32_t>(spring_body.pinnedCount());
      if (b.pinned_count > 0)
      {
        b.pin_force = toVector3(spring_body.pinLoad({}, Eigen::Vector3d::Zero()).force);
      }
      if (core::isImplicit(integratorThatRan(spring_body)))
        b.linear_solver = spring_body.lastSolve().direct      ? "direct"
                          : spring_body.lastSolve().multigrid ? "multigrid"
                                                              : "cg";
      b.solver_iterations = static_cast<std::uint32_t>(std::max(0, spring_body.lastSolve().iterations));
      b.solver_residual = spring_body.lastSolve().relative_residual;
      b.solver_velocity_error = spring_body.lastSolve().velocity_error;
      b.frozen = spring_body.frozen();
      b.frozen_reason = spring_body.frozenReason();
      if (const auto material = materials.find(b.name); material != materials.end())
        b.material = material->second.empty() ? "by value" : material->second;
    }
    status.bodies.push_back(std::move(b));
  }
  return status;
}

namespace
{
// The spring bodies that enable self_collision, with their places in world.bodies() (and so in
// world.lastCollisions().bodies).
std::vector<std::pair<std::size_t, const core::SpringNetworkBody*>> collidingBodies(const core::World& world)
{
  std::vector<std::pair<std::size_t, const core::SpringNetworkBody*>> colliding;
  for (std::size_t i = 0; i < world.bodies().size(); ++i)
  {
    const auto& body = world.bodies()[i];
    if (body->kind() != core::BodyKind::SpringNetwork) continue;
    const auto& spring_body = static_cast<const core::SpringNetworkBody&>(*body);
    if (spring_body.definition().self_collision.enabled) colliding.emplace_back(i, &spring_body);
  }
  return colliding;
}

// The last step's counts of world body `i` (zero before the first step).
core::CollisionCounts lastCollisionsOf(const core::World& world, std::size_t i)
{
  const std::vector<core::CollisionCounts>& bodies = world.lastCollisions().bodies;
  return i < bodies.size() ? bodies[i] : core::CollisionCounts{};
}

// The collision pass of the last step, only when some body enables self_collision: its passes and
// impact zones, and the contacts (proximity pairs) and collisions of each such body.
void addCollisionFigures(const core::World& world, diagnostic_updater::DiagnosticStatusWrapper& stat)
{
  const auto colliding = collidingBodies(world);
  if (colliding.empty()) return;
  stat.add("collision passes (last step)", world.lastCollisions().passes);
  stat.add("impact zones (last step)", world.lastCollisions().impact_zones);
  for (const auto& [i, body] : colliding)
  {
    const core::CollisionCounts counts = lastCollisionsOf(world, i);
    const std::string name = quoteName(body->name());
    stat.add("contacts of " + name + " (last step)", counts.proximity_pairs);
    stat.add("collisions of " + name + " (last step)", counts.collisions);
  }
}

// The last implicit solves of the spring bodies: how many, how many of them direct and by the
// multigrid, how many short of their tolerance, the most CG iterations and the worst relative
// residual and velocity error.
struct ImplicitSolves
{
  int solves = 0, direct = 0, multigrid = 0, not_converged = 0, iterations = 0;
  double residual = 0.0, velocity_error = 0.0;

  void add(const core::SolverReport& solve)
  {
    ++solves;
    direct += solve.direct ? 1 : 0;
    multigrid += solve.multigrid ? 1 : 0;
    not_converged += solve.converged ? 0 : 1;
    iterations = std::max(iterations, solve.iterations);
    residual = std::max(residual, solve.relative_residual);
    velocity_error = std::max(velocity_error, solve.velocity_error);
  }
};

// The status line's part on the implicit solves ("" when there were none): all direct; some direct
// and CG; or CG alone, all, some or none of its solves preconditioned by the multigrid.
std::string solverText(const ImplicitSolves& solves)
{
  char text[160] = "";
  if (solves.solves == 0) return text;
  if (solves.direct == solves.solves && solves.iterations == 0)
  {
    std::snprintf(text, sizeof(text), " | direct solve, residual %.1e, %.1e m/s", solves.residual,
                  solves.velocity_error);
    return text;
  }
  if (solves.direct > 0)
  {
    std::snprintf(text, sizeof(text), " | %d of %d solves direct, CG %d iterations, residual %.1e, %.1e m/s",
                  solves.direct, solves.solves, solves.iterations, solves.residual, solves.velocity_error);
    return text;
  }
  const char* preconditioner = "";
  if (solves.multigrid == solves.solves)
    preconditioner = " (multigrid)";
  else if (solves.multigrid > 0)
    preconditioner = " (some multigrid)";
  std::snprintf(text, sizeof(text), " | CG%s %d iterations, residual %.1e, %.1e m/s", preconditioner, solves.iterations,
                solves.residual, solves.velocity_error);
  return text;
}
}  // namespace

void buildDiagnostics(const core::World& world, const LoopFigures& loop, double max_strain_warn,
                      diagnostic_updater::DiagnosticStatusWrapper& stat)
{
  using diagnostic_msgs::DiagnosticStatus;

  // Over the spring bodies: the last implicit solves (how many, how many direct, most CG iterations,
  // worst residual), strain, springs and triangles torn and frozen bodies.
  ImplicitSolves solves;
  double max_strain = 0.0;
  long long torn_springs = 0, torn_triangles = 0, split_particles = 0;
  std::string strained_body;
  std::vector<std::string> frozen;
  for (const auto& body : world.bodies())
  {
    if (body->kind() != core::BodyKind::SpringNetwork) continue;
    const auto& spring_body = static_cast<const core::SpringNetworkBody&>(*body);
    torn_springs += spring_body.tornSprings();
    torn_triangles += spring_body.tornTriangles();
    split_particles += spring_body.splitParticles();
    if (spring_body.frozen())
    {
      frozen.push_back(toMessageText(body->name(), kMaxQuotedBytes) + " (" +
                       core::toString(integratorThatRan(spring_body)) + ": " + spring_body.frozenReason() + ")");
      continue;
    }
    if (core::isImplicit(integratorThatRan(spring_body))) solves.add(spring_body.lastSolve());
    const double strain = spring_body.maxStrain();
    if (strain > max_strain)
    {
      max_strain = strain;
      strained_body = body->name();
    }
  }

  stat.summary(DiagnosticStatus::OK, loop.paused_in_window || loop.paused ? "paused" : "running");
  char text[256];
  // Thresholds: README "Diagnostics".
  if (!frozen.empty())
  {
    std::string names;
    for (const std::string& name : frozen)
      names += (names.empty() ? "" : ", ") + name;
    stat.mergeSummary(DiagnosticStatus::ERROR, "frozen bodies: " + names);
  }
  if (!loop.paused_in_window && !loop.paused && loop.target_real_time_factor > 0.0 &&
      loop.real_time_factor < kRealTimeFactorWarnRatio * loop.target_real_time_factor)
  {
    std::snprintf(text, sizeof(text), "real-time factor %.3g below %.0f %% of the target %.3g", loop.real_time_factor,
                  100.0 * kRealTimeFactorWarnRatio, loop.target_real_time_factor);
    stat.mergeSummary(DiagnosticStatus::WARN, text);
  }
  if (solves.not_converged > 0)
    stat.mergeSummary(DiagnosticStatus::WARN,
                      std::to_string(solves.not_converged) +
                          " implicit solves did not converge in their last step (neither cg_tolerance nor "
                          "cg_velocity_tolerance reached, or "
                          "resting contacts still changing after " +
                          std::to_string(core::ImplicitEulerSolver::kMaxContactSolves) + " solves)");
  if (loop.stability_events > 0)
    stat.mergeSummary(DiagnosticStatus::WARN,
                      std::to_string(loop.stability_events) + " stability events since the last report (see ~status)");
  if (max_strain > max_strain_warn)
  {
    std::snprintf(text, sizeof(text), "max strain %.3g of '%s' above %.3g", max_strain, strained_body.c_str(),
                  max_strain_warn);
    stat.mergeSummary(DiagnosticStatus::WARN, text);
  }

  stat.add("sim time [s]", world.simTime());
  stat.add("paused", loop.paused);
  stat.add("real-time factor", loop.real_time_factor);
  stat.add("target real-time factor", loop.target_real_time_factor);
  stat.add("step time [us]", loop.step_time_us);
  stat.add("steps per tick", loop.steps_per_tick);
  stat.add("live particles", world.particleCount());
  stat.add("bodies", static_cast<int>(world.bodies().size()));
  stat.add("implicit solves (last step)", solves.solves);
  stat.add("direct solves (last step)", solves.direct);
  stat.add("multigrid solves (last step)", solves.multigrid);
  stat.add("solver iterations (max, last step)", solves.iterations);
  stat.add("solver residual (max, last step)", solves.residual);
  stat.add("solver velocity error [m/s] (max, last step)", solves.velocity_error);
  stat.add("max strain", max_strain);
  stat.add("torn springs", torn_springs);
  stat.add("torn triangles", torn_triangles);
  stat.add("split particles", split_particles);
  addCollisionFigures(world, stat);
  stat.add("frozen bodies", static_cast<int>(frozen.size()));
  stat.add("stability events since last report", loop.stability_events);
  stat.add("ticks of markers, meshes and clouds sent since last report", loop.ticks_sent);
  stat.add("ticks of markers, meshes and clouds skipped since last report (publishing thread busy)",
           loop.ticks_skipped);
  stat.add("wall time behind schedule and not made up since last report [s] (beyond ~max_lag)", loop.lag_dropped);
}

std::string statusLine(const core::World& world, double real_time_factor, double step_time_us, bool paused)
{
  // The implicit solves of the last step: how many were direct or by the multigrid, most CG
  // iterations, worst relative residual and worst velocity error.
  ImplicitSolves solves;
  for (const auto& body : world.bodies())
  {
    if (body->kind() != core::BodyKind::SpringNetwork) continue;
    const auto& spring_body = static_cast<const core::SpringNetworkBody&>(*body);
    if (core::isImplicit(integratorThatRan(spring_body))) solves.add(spring_body.lastSolve());
  }
  const std::string solver = solverText(solves);
  // Springs (and Baraff–Witkin triangles) torn since build or reset, of each body that can tear
  // (tear_strain > 0) only.
  std::string torn;
  for (const auto& body : world.bodies())
  {
    if (body->kind() != core::BodyKind::SpringNetwork) continue;
    const auto& spring_body = static_cast<const core::SpringNetworkBody&>(*body);
    if (!(spring_body.definition().tear_strain > 0.0)) continue;
    torn += (torn.empty() ? " | torn: " : ", ") + quoteName(body->name()) + " " +
            std::to_string(spring_body.tornSprings()) + (spring_body.tornSprings() == 1 ? " spring" : " springs");
    if (spring_body.baraffWitkin()) torn += " " + std::to_string(spring_body.tornTriangles()) + " triangles";
  }
  // The last step's contacts (proximity pairs) and collisions, of each body that enables
  // self_collision only.
  std::string contacts;
  for (const auto& [i, body] : collidingBodies(world))
  {
    const core::CollisionCounts counts = lastCollisionsOf(world, i);
    contacts += (contacts.empty() ? " | contacts: " : ", ") + quoteName(body->name()) + " " +
                std::to_string(counts.proximity_pairs) + " (" + std::to_string(counts.collisions) +
                (counts.collisions == 1 ? " collision)" : " collisions)");
  }
  char line[512];
  std::snprintf(line, sizeof(line), "sim time %.3f s | real-time factor %.2f | live particles %d | step %.1f us%s",
                world.simTime(), real_time_factor, world.particleCount(), step_time_us, solver.c_str());
  return line + torn + contacts + (paused ? " | paused" : "");
}

long long stabilityEventCount(const core::World& world)
{
  long long events = 0;
  for (const auto& body : world.bodies())
  {
    if (const auto* spring_body = world.findSpringBody(body->name())) events += spring_body->stabilityEvents();
  }
  return events;
}

std::string stepReport(const core::World& world, std::uint64_t requested, long long events)
{
  // Stability events and freezes during these steps are part of the answer.
  std::string message = "advanced " + std::to_string(requested) + " steps";
  std::string last_event;
  std::vector<std::string> frozen;
  for (const auto& body : world.bodies())
  {
    const auto* spring_body = world.findSpringBody(body->name());
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
  return message;
}

std::string springConstantsReport(const core::SpringNetworkBody& body, const std::string& body_name,
                                  const std::string& class_name, double stiffness, double damping,
                                  const core::World& world)
{
  // Say what the change means for stability: the new frequency bound and what the core plans for
  // the next step: the substeps of an explicit integrator, or the method auto will use.
  std::ostringstream message;
  message << "set " << class_name << " springs of '" << body_name << "' to " << stiffness << " N/m, " << damping
          << " N·s/m; omega_max <= " << body.frequencyBound() << " 1/s";
  const double dt = world.dt();
  const core::SubstepPlan plan = body.planStep(dt, world.environment());
  const core::IntegratorType type = body.integrator().type;
  if (type == core::kAutoIntegrator)
  {
    message << ", so auto will use " << core::toString(plan.method);
  }
  else if (!core::isImplicit(type))
  {
    message << ", so " << core::toString(type) << " takes " << plan.substeps << " substep(s) per step of " << dt
            << " s";
    if (plan.needed_substeps > plan.substeps)
      message << " (it would need " << plan.needed_substeps << ", above max_substeps: expect it to freeze)";
  }
  return message.str();
}

}  // namespace ros_interface
}  // namespace particle_sim
