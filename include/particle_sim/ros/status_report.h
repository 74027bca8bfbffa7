#pragma once

#include <diagnostic_updater/DiagnosticStatusWrapper.h>
#include <ros/time.h>

#include <cstdint>
#include <map>
#include <string>

#include "particle_sim/SimStatus.h"
#include "particle_sim/core/integrator.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/world.h"

namespace particle_sim
{
namespace ros_interface
{
// What the node shows about the simulation (~status, /diagnostics, the status line, the answers
// of ~step and ~set_spring_constants), built from a const world and the figures only the node's
// loop knows, passed in. No node handle, no master.

/// Diagnostic thresholds (README "Diagnostics").
constexpr double kRealTimeFactorWarnRatio =
    0.9;  ///< WARN when the measured real-time factor is below 90 % of the target

/// The integrator the body's last step ran: its own, or what auto chose (the core records the
/// latter only for completed steps, so a body that froze in its first step would otherwise show
/// the default).
core::IntegratorType integratorThatRan(const core::SpringNetworkBody& body);

/// The material each body was built of, by body name (the node knows it from the scene and the
/// spawn requests; the built body keeps only masses and constants): the preset's name, or empty
/// for a material given by value. Bodies built from spring constants are not listed.
using BodyMaterials = std::map<std::string, std::string>;

/// ~status: the world's time, environment and every body's figures (mass [kg], energies [J],
/// strain, solver, stability, material, the last step's collisions between surfaces), stamped `stamp` in `frame_id`;
/// `paused` and `real_time_factor` [-] (the target) come from the node.
SimStatus buildSimStatus(const core::World& world, const ros::Time& stamp, const std::string& frame_id, bool paused,
                         double real_time_factor, const BodyMaterials& materials = {});

/// The node's loop over one diagnostics window.
struct LoopFigures
{
  double real_time_factor = 0.0;         ///< [-] measured: sim time over wall time
  double target_real_time_factor = 1.0;  ///< [-] ~real_time_factor; 0 = as fast as possible
  double step_time_us = 0.0;             ///< [µs] mean wall time of one physics step
  int steps_per_tick = 1;                ///< physics steps per publish period
  bool paused = false;                   ///< paused now
  bool paused_in_window = false;         ///< paused, or stepped by ~step, at some time in the window
  long long stability_events = 0;        ///< stability events of every body since the last report
  /// Ticks since the last report whose markers, meshes and clouds were sent, and ticks that had a
  /// subscriber for them but skipped them because the publishing thread was still sending.
  long long ticks_sent = 0;
  long long ticks_skipped = 0;
  /// [s] wall time the loop fell behind its schedule beyond ~max_lag since the last report: sim
  /// time lost against the wall clock (times the target real-time factor), not made up.
  double lag_dropped = 0.0;
};

/// /diagnostics' "simulation" status: OK "running" or "paused"; ERROR naming frozen bodies; WARN
/// for a real-time factor below kRealTimeFactorWarnRatio of a non-zero target (while running),
/// implicit solves short of their tolerance, stability events, and a strain above `max_strain`.
/// When some body enables self_collision, also the last step's collision passes and impact zones,
/// and the contacts and collisions of each such body (nothing of the kind for the others).
void buildDiagnostics(const core::World& world, const LoopFigures& loop, double max_strain,
                      diagnostic_updater::DiagnosticStatusWrapper& stat);

/// The periodic status line: sim time [s], measured real-time factor, live particles, mean step
/// time [µs], the last implicit solves (most CG iterations, worst residual), the springs (and
/// Baraff–Witkin triangles) torn of each body that can tear (tear_strain > 0; nothing for the others),
/// the last step's contacts and collisions of each body that enables self_collision (nothing for
/// the others) and whether paused.
std::string statusLine(const core::World& world, double real_time_factor, double step_time_us, bool paused);

/// Stability events of every spring body so far.
long long stabilityEventCount(const core::World& world);

/// ~step's answer after `requested` steps during which `events` stability events happened: the
/// last event and every frozen body with its reason.
std::string stepReport(const core::World& world, std::uint64_t requested, long long events);

/// ~set_spring_constants' answer once `body` (of `world`)'s `class_name` springs were set: the new
/// frequency bound and what it means for the next step of the world's dt [s], as the core plans it
/// (SpringNetworkBody::planStep(): substeps of an explicit integrator, or auto's choice).
std::string springConstantsReport(const core::SpringNetworkBody& body, const std::string& body_name,
                                  const std::string& class_name, double stiffness, double damping,
                                  const core::World& world);

}  // namespace ros_interface
}  // namespace particle_sim
