#pragma once

#include <cstddef>

namespace particle_sim
{
namespace core
{
/// The one allowed range of every user-settable quantity, with its unit. Scene files, services,
/// dynamic_reconfigure (config/Sim.cfg reads this file) and particle_sim_run all check against
/// these, so a value is accepted or refused the same way wherever it comes from.
///
/// Keep each entry on one line of the form `constexpr Range kName{min, max, "unit"};`:
/// config/Sim.cfg parses them.
namespace limits
{
struct Range
{
  double min;        ///< smallest allowed value (inclusive)
  double max;        ///< largest allowed value (inclusive)
  const char* unit;  ///< SI unit, as printed in messages ("-" for none)
};

// clang-format off
constexpr Range kStiffness{0.0, 1e9, "N/m"};           // spring stiffness k_e (Baraff–Witkin: per unit area)
constexpr Range kDamping{0.0, 1e6, "N·s/m"};           // spring damping k_d
constexpr Range kGravityComponent{-100.0, 100.0, "m/s^2"};
constexpr Range kWindComponent{-100.0, 100.0, "m/s"};
constexpr Range kSolverVelocityTolerance{0.0, 1.0, "m/s"};  // cg_velocity_tolerance; 0 = off
constexpr Range kGlobalDamping{0.0, 100.0, "1/s"};
constexpr Range kRealTimeFactor{0.0, 1000.0, "-"};     // 0 = as fast as possible
constexpr Range kPublishRate{0.1, 1000.0, "Hz"};
constexpr Range kMaxLag{0.0, 60.0, "s"};           // ~max_lag: wall time the node's loop makes up when late
constexpr Range kMarkerPoints{1, 1e7, "points"};       // points of all particle markers of a tick (~max_marker_points)
constexpr Range kContactThickness{0.0, 1.0, "m"};      // distance a body keeps from ground and spheres
constexpr Range kTearStrain{0.0, 100.0, "-"};          // tear_strain: a spring stretched past it breaks; 0 = never
constexpr Range kSelfCollisionThickness{1e-4, 0.5, "m"};  // self_collision.thickness: distance kept between surfaces
constexpr Range kGraspSize{1e-6, 100.0, "m"};          // grasp region: sphere radius, box half-extents
constexpr Range kGraspOffset{-1e4, 1e4, "m"};          // grasp region centre in the gripper frame, each component
constexpr Range kGraspCount{1, 1e6, "particles"};      // grasp region: the N particles nearest its centre
constexpr Range kBreakawayForce{0.0, 1e9, "N"};       // a grasp lets go above this force; 0 = never
constexpr Range kParticlesPerBody{1, 1e8, "particles"};  // the cap world.max_particles_per_body itself
constexpr Range kParticlesPerWorld{1, 1e9, "particles"};  // the cap world.max_particles_per_world itself
constexpr Range kThreads{0, 256, "threads"};          // world.threads: threads a step may use; 0 = one per core
constexpr Range kDampingRatio{0.0, 10.0, "-"};         // ζ, fraction of critical damping (cloth and rope materials)
constexpr Range kArealDensity{0.001, 10.0, "kg/m^2"};  // cloth material: mass per unit area
constexpr Range kTensileStiffness{1.0, 1e7, "N/m"};    // cloth material: Young's modulus × thickness
constexpr Range kShearStiffness{0.01, 1e6, "N/m"};     // cloth material: shear modulus × thickness
constexpr Range kBendingRigidity{0.0, 1.0, "N·m"};     // cloth material: B, bending moment per width per curvature
constexpr Range kLinearDensity{1e-6, 1e4, "kg/m"};    // rope mass per length μ (sewing thread to heavy chain)
constexpr Range kAxialStiffness{1e-3, 1e12, "N"};     // rope EA (elastic thread to bridge cable)
constexpr Range kBendingStiffness{0.0, 1e6, "N·m²"};  // rope EI (0 = a chain)
// clang-format on

/// Longest body name [characters].
constexpr std::size_t kMaxNameLength = 64;
}  // namespace limits
}  // namespace core
}  // namespace particle_sim
