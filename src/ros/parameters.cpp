#include "particle_sim/ros/parameters.h"

#include <algorithm>
#include <cmath>

#include "particle_sim/core/limits.h"
#include "particle_sim/ros/material_conversions.h"
#include "particle_sim/ros/message_text.h"
#include "particle_sim/ros/names.h"

namespace particle_sim
{
namespace ros_interface
{
namespace
{
// "field = value is out of range: must be in [min, max] unit" for a node parameter, the value as
// received.
std::string outOfRange(const std::string& field, double value, const core::limits::Range& range)
{
  return field + " = " + formatReceived(value) + " is out of range: must be in [" + formatReceived(range.min) + ", " +
         formatReceived(range.max) + "] " + range.unit;
}
}  // namespace

NodeSettings readNodeSettings(const ros::NodeHandle& private_node)
{
  NodeSettings s;
  private_node.param(names::kSceneParam, s.scene_path, s.scene_path);
  private_node.param(names::kRateParam, s.rate, s.rate);
  private_node.param(names::kDtParam, s.dt, s.dt);
  private_node.param(names::kRealTimeFactorParam, s.real_time_factor, s.real_time_factor);
  private_node.param(names::kMaxLagParam, s.max_lag, s.max_lag);
  private_node.param(names::kPausedParam, s.paused, s.paused);
  private_node.param(names::kFrameIdParam, s.frame_id, s.frame_id);
  private_node.param(names::kParentFrameIdParam, s.parent_frame_id, s.parent_frame_id);
  private_node.param(names::kFrameOffsetParam, s.frame_offset, s.frame_offset);
  private_node.param(names::kPublishClockParam, s.publish_clock, s.publish_clock);
  private_node.param(names::kParticleSizeParam, s.particle_size, s.particle_size);
  private_node.param(names::kMaxMarkerPointsParam, s.max_marker_points, s.max_marker_points);
  private_node.param(names::kPublishingThreadParam, s.publishing_thread, s.publishing_thread);
  private_node.param(names::kPointsSurfaceOnlyParam, s.points_surface_only, s.points_surface_only);
  private_node.param(names::kDragMarkersParam, s.drag_markers, s.drag_markers);
  private_node.param(names::kMaxParticlesParam, s.max_particles_per_body, s.max_particles_per_body);
  private_node.param(names::kMaxWorldParticlesParam, s.max_particles_per_world, s.max_particles_per_world);
  private_node.param(names::kThreadsParam, s.threads, s.threads);
  private_node.param(names::kStatusPeriodParam, s.status_period, s.status_period);
  private_node.param(names::kColorByStrainParam, s.color_by_strain, s.color_by_strain);
  private_node.param(names::kStrainColorMaxParam, s.strain_color_max, s.strain_color_max);
  private_node.param(names::kDiagnosticPeriodParam, s.diagnostic_period, s.diagnostic_period);
  private_node.param(names::kDiagnosticMaxStrainParam, s.diagnostic_max_strain, s.diagnostic_max_strain);
  private_node.param(names::kRopeMaterialParam, s.rope_material, s.rope_material);
  private_node.param(names::kClothMaterialParam, s.cloth_material, s.cloth_material);
  return s;
}

core::Status validate(const NodeSettings& s)
{
  using core::Status;
  using core::limits::kPublishRate;
  using core::limits::kRealTimeFactor;
  if (!(s.rate >= kPublishRate.min && s.rate <= kPublishRate.max))
    return Status::failure(outOfRange("~rate", s.rate, kPublishRate));
  if (!(s.real_time_factor >= kRealTimeFactor.min && s.real_time_factor <= kRealTimeFactor.max))
    return Status::failure(outOfRange("~real_time_factor", s.real_time_factor, kRealTimeFactor) +
                           " (0 = as fast as possible; negative values have no meaning)");
  if (!(s.max_lag >= core::limits::kMaxLag.min && s.max_lag <= core::limits::kMaxLag.max))
    return Status::failure(outOfRange("~max_lag", s.max_lag, core::limits::kMaxLag) +
                           " (0 = never make up a late tick)");
  if (!(s.particle_size > 0.0 && std::isfinite(s.particle_size)))
    return Status::failure("~particle_size = " + formatReceived(s.particle_size) + " must be > 0 m");
  if (!(s.max_marker_points >= core::limits::kMarkerPoints.min &&
        s.max_marker_points <= core::limits::kMarkerPoints.max))
    return Status::failure(outOfRange("~max_marker_points", s.max_marker_points, core::limits::kMarkerPoints));
  if (s.frame_id.empty()) return Status::failure("~frame_id is empty");
  if (s.parent_frame_id.empty() || s.parent_frame_id == s.frame_id)
    return Status::failure("~parent_frame_id = " + quoteName(s.parent_frame_id) +
                           " must be set and differ from ~frame_id");
  if (s.frame_offset.size() != 3 ||
      !std::all_of(s.frame_offset.begin(), s.frame_offset.end(), [](double v) { return std::isfinite(v); }))
    return Status::failure("~frame_offset must be a list of 3 finite numbers [x, y, z] in m");

  if (s.threads != -1 && !(s.threads >= core::limits::kThreads.min && s.threads <= core::limits::kThreads.max))
    return Status::failure(outOfRange("~threads", s.threads, core::limits::kThreads) +
                           " (0 = one per core; -1 = the scene's world.threads)");
  if (!(s.strain_color_max > 0.0 && std::isfinite(s.strain_color_max)))
    return Status::failure("~strain_color_max = " + formatReceived(s.strain_color_max) + " must be > 0");
  if (!(s.diagnostic_period > 0.0 && std::isfinite(s.diagnostic_period)))
    return Status::failure("~diagnostic_period = " + formatReceived(s.diagnostic_period) + " must be > 0 s");
  if (!(s.diagnostic_max_strain > 0.0 && std::isfinite(s.diagnostic_max_strain)))
    return Status::failure("~diagnostic_max_strain = " + formatReceived(s.diagnostic_max_strain) + " must be > 0");
  if (Status status = checkRopePresetName("~rope_material", s.rope_material); !status) return status;
  if (Status status = checkClothPresetName("~cloth_material", s.cloth_material); !status) return status;
  return Status::success();
}

}  // namespace ros_interface
}  // namespace particle_sim
