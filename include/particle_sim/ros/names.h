#pragma once

// Every topic, service and parameter name of the node, in one place. All are private (~) or
// relative, so namespaces and remapping work; /clock is global by ROS convention.

namespace particle_sim
{
namespace names
{
// Topics
constexpr const char* kMarkersTopic = "markers";           // ~markers, visualization_msgs/MarkerArray
constexpr const char* kClockTopic = "/clock";              // rosgraph_msgs/Clock
constexpr const char* kMeshesTopic = "meshes";             // ~meshes, particle_sim/ClothMesh
constexpr const char* kStatusTopic = "status";             // ~status, particle_sim/SimStatus
constexpr const char* kPointsTopic = "points";             // ~points, sensor_msgs/PointCloud2
constexpr const char* kDiagnosticsTopic = "/diagnostics";  // diagnostic_msgs/DiagnosticArray (diagnostic_updater)
// dynamic_reconfigure's own, under the node's private namespace: ~set_parameters (service),
// ~parameter_descriptions and ~parameter_updates (latched topics).

// Services
constexpr const char* kSpawnEmitter = "spawn_emitter";
constexpr const char* kRemoveBody = "remove_body";
constexpr const char* kReset = "reset";
constexpr const char* kPausePhysics = "pause_physics";
constexpr const char* kUnpausePhysics = "unpause_physics";
constexpr const char* kStep = "step";
constexpr const char* kSpawnRope = "spawn_rope";
constexpr const char* kPinParticle = "pin_particle";
constexpr const char* kUnpinParticle = "unpin_particle";
constexpr const char* kSetSpringConstants = "set_spring_constants";
constexpr const char* kSpawnCloth = "spawn_cloth";
constexpr const char* kSpawnJelly = "spawn_jelly";
constexpr const char* kSetWind = "set_wind";
constexpr const char* kGrasp = "grasp";
constexpr const char* kRelease = "release";
constexpr const char* kSpawnCollider = "spawn_collider";
constexpr const char* kRemoveCollider = "remove_collider";

// Parameters
constexpr const char* kSceneParam = "scene";
constexpr const char* kRateParam = "rate";
constexpr const char* kDtParam = "dt";
constexpr const char* kRealTimeFactorParam = "real_time_factor";
constexpr const char* kPausedParam = "paused";
constexpr const char* kFrameIdParam = "frame_id";
constexpr const char* kParentFrameIdParam = "parent_frame_id";
constexpr const char* kFrameOffsetParam = "frame_offset";
constexpr const char* kPublishClockParam = "publish_clock";
constexpr const char* kParticleSizeParam = "particle_size";
constexpr const char* kMaxMarkerPointsParam = "max_marker_points";
constexpr const char* kPublishingThreadParam = "publishing_thread";
constexpr const char* kPointsSurfaceOnlyParam = "points_surface_only";
constexpr const char* kDragMarkersParam = "drag_markers";
constexpr const char* kMaxParticlesParam = "max_particles_per_body";
constexpr const char* kMaxWorldParticlesParam = "max_particles_per_world";
constexpr const char* kThreadsParam = "threads";
constexpr const char* kStatusPeriodParam = "status_period";
constexpr const char* kMaxLagParam = "max_lag";
constexpr const char* kColorByStrainParam = "color_by_strain";
constexpr const char* kStrainColorMaxParam = "strain_color_max";
constexpr const char* kDiagnosticPeriodParam = "diagnostic_period";  // also read by diagnostic_updater
constexpr const char* kDiagnosticMaxStrainParam = "diagnostic_max_strain";
constexpr const char* kRopeMaterialParam = "rope_material";    // also live (dynamic_reconfigure)
constexpr const char* kClothMaterialParam = "cloth_material";  // also live (dynamic_reconfigure)
// Live (dynamic_reconfigure, config/Sim.cfg) and also read at start from the parameter server:
// rate, real_time_factor, rope_material and cloth_material above, and gravity_x/y/z,
// global_damping, wind_x/y/z, integrator, body, spring_class, stiffness, damping, whose start values
// come from the scene.
}  // namespace names
}  // namespace particle_sim
