#pragma once

#include <ros/time.h>
#include <visualization_msgs/MarkerArray.h>

#include <string>
#include <vector>

#include "particle_sim/core/emitter.h"
#include "particle_sim/core/world.h"

namespace particle_sim
{
namespace ros_interface
{
/// How markers look.
struct MarkerStyle
{
  std::string frame_id = "world";
  double particle_size = 0.05;    ///< [m] side of a POINTS square, diameter of a spring body's particle
  double line_width = 0.02;       ///< [m] rope and spring lines
  bool color_by_strain = false;   ///< colour cloth and jelly surfaces by strain instead of shading them
  double strain_color_max = 0.1;  ///< [-] strain drawn fully red (0 is blue)
  /// Most points of all particle markers of one array together (emitters' POINTS, networks' free
  /// particles), shared by decimationStrides(): a body over its share is drawn by every k-th of its
  /// particles (evenly in index order, the same particles every tick while the counts hold).
  int max_points = 200000;
};

/// Turns the world's state into one MarkerArray: one namespace per body (the body name) with
/// stable ids, so each array overwrites the last in place.
///   - `delete_all`: a DELETEALL (ns "") goes first, as at start and after reset;
///   - `removed`: bodies removed since the last array get a DELETE for each of their ids;
///   - spring bodies: free particles as a SPHERE_LIST, a rope as a LINE_STRIP (once it has torn, a
///     LINE_LIST of the stretch springs left) and a network's springs as a LINE_LIST, pinned
///     particles as a separate, larger SPHERE_LIST (DELETE if none);
///   - cloth and jelly: their current surface (SpringNetworkBody::surfaceTriangles(): without the
///     triangles a tear cut out) as a TRIANGLE_LIST, one colour per vertex, shaded by the
///     vertex normal (or coloured by strain when style.color_by_strain); rviz draws triangle lists
///     from both sides; and their pins;
///   - an emitter with no live particle gets a DELETE instead of an empty POINTS list;
///   - the particle markers together hold at most style.max_points points (decimated evenly, at
///     least one point per body that has particles);
///   - colliders are drawn in the namespace "_colliders": spheres, boxes (CUBE), and capsules as a
///     CYLINDER (ids in that order) between two SPHEREs.
/// Every marker passes rviz's checks: unit quaternion, non-zero scale, alpha > 0, one colour per
/// point, finite values (non-finite particles are left out).
visualization_msgs::MarkerArray buildMarkers(const core::World& world, const ros::Time& stamp, const MarkerStyle& style,
                                             bool delete_all, const std::vector<std::string>& removed);

/// The particles an emitter's marker draws (every k-th live one, decimationStrides()), copied out of
/// the world so that the marker's points and colours can be written on another thread.
struct EmitterMarkerSample
{
  std::size_t marker = 0;               ///< the index of the emitter's marker in its array
  double lifetime = 1.0;                ///< [s] the emitter's, for the colours by age
  core::ParticleSnapshot particles;     ///< the drawn particles' positions and ages
  const core::Body* emitter = nullptr;  ///< the emitter snapshotNextStep() asked
};

/// The emitters' samples of one array, in the order of the world's bodies. Kept from array to
/// array, its vectors keep their capacity.
struct MarkerSamples
{
  std::vector<EmitterMarkerSample> emitters;
  std::size_t used = 0;  ///< emitters[0, used) belong to the last array
  bool asked = false;    ///< snapshotNextStep() asked the emitters for this array's particles
};

/// Asks each emitter's next step for the particles its marker will draw (at the strides their
/// counts give now), into `samples` (core::EmitterBody::snapshotNextStep(): copied as the step has
/// them in the cache). buildMarkersDeferred() takes a snapshot where the emitter's step took one at
/// the stride that still holds, and copies the particles out of the world where it did not (no step
/// ran, the count moved to another stride). Call forgetSnapshotRequests() after the step.
void snapshotNextStep(core::World& world, const MarkerStyle& style, MarkerSamples& samples);
/// Takes back the requests of snapshotNextStep() that no step took.
void forgetSnapshotRequests(core::World& world);

/// buildMarkers() in two halves, so that the heavy half runs off the physics thread: this one, with
/// the world at hand, builds every marker but leaves the emitters' without points, their particles
/// copied into `samples` instead (a copy of the few numbers each point needs, into vectors reused
/// from tick to tick); finishMarkers() then writes those markers' points and colours, anywhere, as
/// long as nothing else touches the array and `samples` meanwhile. Together: buildMarkers()'s array.
visualization_msgs::MarkerArray buildMarkersDeferred(const core::World& world, const ros::Time& stamp,
                                                     const MarkerStyle& style, bool delete_all,
                                                     const std::vector<std::string>& removed, MarkerSamples& samples);
/// The second half of buildMarkersDeferred(): the emitters' points and colours (by age) from `samples`;
/// an emitter with no finite particle gets a DELETE.
void finishMarkers(const MarkerSamples& samples, visualization_msgs::MarkerArray& markers);

/// Every k-th of `count` particles keeps a drawing within `max_points`: k = ⌈count / max_points⌉
/// (1 when they fit).
int decimationStride(int count, int max_points);

/// Strides that draw bodies of `counts` particles within `max_points` together, fairly to the
/// smallest: from the smallest count up, each body gets an equal part of the points the smaller
/// ones left, and is drawn whole when it fits in it (so a rope beside a million-particle fountain
/// keeps all its particles). Each stride is decimationStride(count, share) with share ≥ 1; a body
/// with no particles gets 1.
std::vector<int> decimationStrides(const std::vector<int>& counts, int max_points);

/// Colour of a strain (l − L)/L: blue at 0 (or compressed), through green, to red at `max`.
std_msgs::ColorRGBA strainColor(double strain, double max);

/// Marker ids used inside a body's namespace.
constexpr int kParticlesMarkerId = 0;  ///< POINTS (emitters) or SPHERE_LIST (free particles of spring bodies)
constexpr int kLinesMarkerId = 1;      ///< LINE_STRIP (ropes; torn: LINE_LIST), LINE_LIST (networks) or TRIANGLE_LIST
constexpr int kPinsMarkerId = 2;       ///< SPHERE_LIST of pinned particles, drawn apart
constexpr int kMarkerIdsPerBody = 3;
/// Namespace of the collider markers (one SPHERE per sphere collider, id = its index). Body names
/// cannot start with '_', so no body takes it.
constexpr const char* kCollidersNamespace = "_colliders";

}  // namespace ros_interface
}  // namespace particle_sim
