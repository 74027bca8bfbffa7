#include "particle_sim/ros/marker_builder.h"

#include <algorithm>

#include "particle_sim/core/emitter.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/surface.h"
#include "particle_sim/ros/eigen_messages.h"

namespace particle_sim
{
namespace ros_interface
{
namespace
{
std_msgs::ColorRGBA rgba(float r, float g, float b, float a = 1.0f);
}  // namespace

int decimationStride(int count, int max_points)
{
  return max_points > 0 && count > max_points ? (count + max_points - 1) / max_points : 1;
}

std::vector<int> decimationStrides(const std::vector<int>& counts, int max_points)
{
  // Shares that are fair to the smallest: from the smallest count up, each body may have an equal
  // part of the points still unspent; a body with fewer spends only what it draws, leaving the rest
  // to the larger ones.
  std::vector<int> strides(counts.size(), 1);
  std::vector<std::size_t> order(counts.size());
  for (std::size_t b = 0; b < order.size(); ++b)
    order[b] = b;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return counts[a] < counts[b]; });
  long long unspent = max_points;
  long long bodies_left =
      static_cast<long long>(std::count_if(counts.begin(), counts.end(), [](int c) { return c > 0; }));
  for (const std::size_t b : order)
  {
    if (counts[b] <= 0) continue;
    const int share = static_cast<int>(std::max(1LL, unspent / bodies_left));
    strides[b] = decimationStride(counts[b], share);
    unspent -= (counts[b] + strides[b] - 1) / strides[b];
    --bodies_left;
  }
  return strides;
}

std_msgs::ColorRGBA strainColor(double strain, double max)
{
  // Blue -> green -> red as s goes 0 -> 1/2 -> 1.
  const double s = std::clamp(max > 0.0 ? strain / max : 0.0, 0.0, 1.0);
  const float r = static_cast<float>(std::clamp(2.0 * s - 1.0, 0.0, 1.0));
  const float b = static_cast<float>(std::clamp(1.0 - 2.0 * s, 0.0, 1.0));
  const float g = static_cast<float>(1.0 - r - b);
  return rgba(r, g, b);
}

namespace
{
visualization_msgs::Marker makeMarker(const std::string& ns, int id, const ros::Time& stamp, const MarkerStyle& style)
{
  visualization_msgs::Marker marker;
  marker.header.frame_id = style.frame_id;
  marker.header.stamp = stamp;
  marker.ns = ns;
  marker.id = id;
  marker.pose.orientation.w = 1.0;
  marker.scale.x = marker.scale.y = marker.scale.z = 1.0;
  marker.color.a = 1.0;
  return marker;
}

// Colour of an emitter particle by its age fraction s in [0, 1]: pale yellow when new, through
// orange, to dark red when about to be recycled.
std_msgs::ColorRGBA ageColor(double s)
{
  s = std::clamp(s, 0.0, 1.0);
  std_msgs::ColorRGBA c;
  c.r = static_cast<float>(1.0 - 0.4 * s);
  c.g = static_cast<float>(0.95 * (1.0 - s));
  c.b = static_cast<float>(0.6 * (1.0 - s) * (1.0 - s));
  c.a = 1.0f;
  return c;
}

std_msgs::ColorRGBA rgba(float r, float g, float b, float a)
{
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

// Turns `marker` into a DELETE when it has no points (rviz refuses empty lists).
void deleteIfEmpty(visualization_msgs::Marker& marker)
{
  marker.action = marker.points.empty() ? visualization_msgs::Marker::DELETE : visualization_msgs::Marker::ADD;
}

// A cloth or jelly surface: TRIANGLE_LIST with a colour per vertex. rviz draws triangle lists
// without culling (both sides show) and, given vertex colours, without lighting, so the shading is
// done here: the base colour dimmed by the angle between the vertex normal and a fixed light,
// the same from either side. With style.color_by_strain the colour is the strain's instead. The
// surface is the current one: triangles a tear cut out are gone.
visualization_msgs::Marker surfaceMarker(const core::SpringNetworkBody& body, const ros::Time& stamp,
                                         const MarkerStyle& style)
{
  const core::ParticlePool& p = body.particles();
  const auto& triangles = body.surfaceTriangles();
  visualization_msgs::Marker surface = makeMarker(body.name(), kLinesMarkerId, stamp, style);
  surface.type = visualization_msgs::Marker::TRIANGLE_LIST;
  surface.color = body.frozen()                               ? rgba(0.5f, 0.5f, 0.5f)
                  : body.shape() == core::NetworkShape::Jelly ? rgba(0.95f, 0.35f, 0.55f)
                                                              : rgba(0.35f, 0.6f, 0.95f);
  std::vector<double> strains;
  std::vector<Eigen::Vector3d> normals;
  if (style.color_by_strain)
    core::vertexStrains(body, strains);
  else
    core::vertexNormals(p.position, p.size(), triangles, normals);
  const Eigen::Vector3d light = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();

  surface.points.reserve(3 * triangles.size());
  surface.colors.reserve(3 * triangles.size());
  for (const Eigen::Vector3i& t : triangles)
  {
    for (int c = 0; c < 3; ++c)
    {
      const int corner = t[c];
      surface.points.push_back(toPoint(p.position.col(corner)));
      if (style.color_by_strain)
      {
        surface.colors.push_back(strainColor(strains[corner], style.strain_color_max));
        continue;
      }
      const float shade = static_cast<float>(0.35 + 0.65 * std::abs(normals[corner].dot(light)));
      surface.colors.push_back(rgba(shade * surface.color.r, shade * surface.color.g, shade * surface.color.b));
    }
  }
  deleteIfEmpty(surface);
  return surface;
}

// Cloth and jelly are drawn by their surface, other networks by their particles and springs.
bool drawnBySurface(const core::SpringNetworkBody& body)
{
  return body.shape() == core::NetworkShape::Cloth || body.shape() == core::NetworkShape::Jelly;
}

// The particles a body's particle marker would draw before decimation: an emitter's live ones, a
// network's free ones; none for cloth and jelly.
int drawnParticleCount(const core::Body& body)
{
  if (body.kind() == core::BodyKind::Emitter) return body.particles().size();
  if (body.kind() != core::BodyKind::SpringNetwork) return 0;
  const auto& network = static_cast<const core::SpringNetworkBody&>(body);
  return drawnBySurface(network) ? 0 : network.particles().size() - network.pinnedCount();
}

// `stride`: every how many free particles one is drawn (1 for cloth and jelly).
void addSpringBody(const core::SpringNetworkBody& body, int stride, const ros::Time& stamp, const MarkerStyle& style,
                   visualization_msgs::MarkerArray& out)
{
  const core::ParticlePool& p = body.particles();
  const int n = p.size();
  const bool has_surface = drawnBySurface(body);

  // Free particles and pinned ones, each a SPHERE_LIST; pinned ones larger and red.
  visualization_msgs::Marker free = makeMarker(body.name(), kParticlesMarkerId, stamp, style);
  free.type = visualization_msgs::Marker::SPHERE_LIST;
  free.scale.x = free.scale.y = free.scale.z = style.particle_size;
  free.color = body.frozen() ? rgba(0.5f, 0.5f, 0.5f) : rgba(0.3f, 0.7f, 1.0f);
  visualization_msgs::Marker pins = makeMarker(body.name(), kPinsMarkerId, stamp, style);
  pins.type = visualization_msgs::Marker::SPHERE_LIST;
  pins.scale.x = pins.scale.y = pins.scale.z = 2.0 * style.particle_size;
  pins.color = rgba(1.0f, 0.25f, 0.2f);
  free.points.reserve(has_surface ? 0 : n / stride + 1);
  // Cloth and jelly are drawn by their surface; only their pinned particles get spheres, and, once
  // they have torn, the free particles a tear left in no surface triangle (still held by springs).
  std::vector<char> on_surface;
  if (has_surface && body.tornSprings() + body.tornTriangles() > 0)
  {
    on_surface.assign(static_cast<std::size_t>(n), 0);
    for (const Eigen::Vector3i& t : body.surfaceTriangles())
      for (int c = 0; c < 3; ++c)
        on_surface[static_cast<std::size_t>(t[c])] = 1;
  }
  int free_index = 0;
  for (int i = 0; i < n; ++i)
  {
    if (body.isPinned(i))
      pins.points.push_back(toPoint(p.position.col(i)));
    else if (has_surface ? !on_surface.empty() && !on_surface[static_cast<std::size_t>(i)] : free_index++ % stride == 0)
      free.points.push_back(toPoint(p.position.col(i)));
  }
  deleteIfEmpty(free);
  deleteIfEmpty(pins);

  if (has_surface)
  {
    out.markers.push_back(std::move(free));
    out.markers.push_back(surfaceMarker(body, stamp, style));
    out.markers.push_back(std::move(pins));
    return;
  }

  // The rope as one line through its particles in order; a network as one segment per spring. A
  // rope that tore is drawn by the stretch springs it has left (one segment each), so that the
  // line shows its breaks.
  visualization_msgs::Marker lines = makeMarker(body.name(), kLinesMarkerId, stamp, style);
  lines.scale.x = style.line_width;
  lines.color = body.frozen() ? rgba(0.5f, 0.5f, 0.5f) : rgba(0.95f, 0.85f, 0.6f);
  if (body.shape() == core::NetworkShape::Rope && body.tornSprings() == 0)
  {
    lines.type = visualization_msgs::Marker::LINE_STRIP;
    lines.points.reserve(n);
    for (int i = 0; i < n; ++i)
      lines.points.push_back(toPoint(p.position.col(i)));
  }
  else
  {
    const bool torn_rope = body.shape() == core::NetworkShape::Rope;
    lines.type = visualization_msgs::Marker::LINE_LIST;
    lines.points.reserve(2 * body.springs().size());
    for (const core::Spring& spring : body.springs())
    {
      if (torn_rope && spring.spring_class != core::SpringClass::Stretch) continue;
      lines.points.push_back(toPoint(p.position.col(spring.i)));
      lines.points.push_back(toPoint(p.position.col(spring.j)));
    }
  }
  deleteIfEmpty(lines);

  out.markers.push_back(std::move(free));
  out.markers.push_back(std::move(lines));
  out.markers.push_back(std::move(pins));
}

// `stride`: every how many live particles one is drawn. The marker goes into the array without
// points; its particles are in the next of `samples`, for finishMarkers(): the snapshot its step
// took for it, or else a copy made here.
void addEmitter(const core::EmitterBody& emitter, int stride, const ros::Time& stamp, const MarkerStyle& style,
                visualization_msgs::MarkerArray& out, MarkerSamples& samples)
{
  visualization_msgs::Marker marker = makeMarker(emitter.name(), kParticlesMarkerId, stamp, style);
  marker.type = visualization_msgs::Marker::POINTS;
  marker.scale.x = marker.scale.y = style.particle_size;
  out.markers.push_back(std::move(marker));

  if (samples.used == samples.emitters.size()) samples.emitters.emplace_back();
  EmitterMarkerSample& sample = samples.emitters[samples.used++];
  sample.marker = out.markers.size() - 1;
  sample.lifetime = emitter.definition().lifetime;
  const bool taken_by_step = samples.asked && sample.emitter == &emitter && sample.particles.stride == stride;
  if (!taken_by_step) emitter.copySnapshot(stride, sample.particles);
}

// An emitter's marker from its sample: a point and a colour by age for each finite particle.
void finishEmitter(const EmitterMarkerSample& sample, visualization_msgs::Marker& marker)
{
  const core::ParticleSnapshot& copy = sample.particles;
  const std::size_t count = copy.age.size();
  marker.points.reserve(count);
  marker.colors.reserve(count);
  for (std::size_t k = 0; k < count; ++k)
  {
    const Eigen::Map<const Eigen::Vector3d> x(&copy.position[3 * k]);
    if (!x.allFinite()) continue;  // never publish NaN; such a body is reported elsewhere
    marker.points.push_back(toPoint(x));
    marker.colors.push_back(ageColor(copy.age[k] / sample.lifetime));
  }
  marker.action = marker.points.empty() ? visualization_msgs::Marker::DELETE : visualization_msgs::Marker::ADD;
}

// The strides of the bodies' particle markers: style.max_points shared between them.
std::vector<int> particleStrides(const core::World& world, const MarkerStyle& style)
{
  std::vector<int> counts;
  counts.reserve(world.bodies().size());
  for (const auto& body : world.bodies())
    counts.push_back(drawnParticleCount(*body));
  return decimationStrides(counts, style.max_points);
}
}  // namespace

visualization_msgs::MarkerArray buildMarkers(const core::World& world, const ros::Time& stamp, const MarkerStyle& style,
                                             bool delete_all, const std::vector<std::string>& removed)
{
  MarkerSamples samples;
  visualization_msgs::MarkerArray out = buildMarkersDeferred(world, stamp, style, delete_all, removed, samples);
  finishMarkers(samples, out);
  return out;
}

void finishMarkers(const MarkerSamples& samples, visualization_msgs::MarkerArray& markers)
{
  for (std::size_t e = 0; e < samples.used; ++e)
    finishEmitter(samples.emitters[e], markers.markers.at(samples.emitters[e].marker));
}

visualization_msgs::MarkerArray buildMarkersDeferred(const core::World& world, const ros::Time& stamp,
                                                     const MarkerStyle& style, bool delete_all,
                                                     const std::vector<std::string>& removed, MarkerSamples& samples)
{
  samples.used = 0;
  visualization_msgs::MarkerArray out;
  if (delete_all)
  {
    visualization_msgs::Marker clear = makeMarker("", 0, stamp, style);
    clear.action = visualization_msgs::Marker::DELETEALL;
    out.markers.push_back(clear);
  }
  for (const std::string& name : removed)
  {
    for (int id = 0; id < kMarkerIdsPerBody; ++id)
    {
      visualization_msgs::Marker gone = makeMarker(name, id, stamp, style);
      gone.action = visualization_msgs::Marker::DELETE;
      out.markers.push_back(gone);
    }
  }
  // Colliders, drawn translucent so that particles behind them stay visible: spheres, boxes, and
  // capsules as a cylinder (its axis is the marker's z, the capsule's x) between two spheres.
  int collider_id = 0;
  auto collider = [&](int type, const Eigen::Vector3d& center, const Eigen::Quaterniond& orientation,
                      const Eigen::Vector3d& scale) {
    visualization_msgs::Marker marker = makeMarker(kCollidersNamespace, collider_id++, stamp, style);
    marker.type = type;
    marker.action = visualization_msgs::Marker::ADD;
    marker.pose.position = toPoint(center);
    marker.pose.orientation.x = orientation.x();
    marker.pose.orientation.y = orientation.y();
    marker.pose.orientation.z = orientation.z();
    marker.pose.orientation.w = orientation.w();
    marker.scale = toVector3(scale);
    marker.color.r = marker.color.g = 0.55f;
    marker.color.b = 0.65f;
    marker.color.a = 0.6f;
    out.markers.push_back(marker);
  };
  const core::Environment& env = world.environment();
  for (const core::SphereColliderDef& sphere : env.spheres)
    collider(visualization_msgs::Marker::SPHERE, sphere.center, Eigen::Quaterniond::Identity(),
             Eigen::Vector3d::Constant(2.0 * sphere.radius));
  for (const core::BoxColliderDef& box : env.boxes)
    collider(visualization_msgs::Marker::CUBE, box.center, box.orientation, 2.0 * box.half_extents);
  for (const core::CapsuleColliderDef& capsule : env.capsules)
  {
    const Eigen::Vector3d axis = capsule.orientation * Eigen::Vector3d::UnitX();
    const Eigen::Quaterniond z_along_axis =
        capsule.orientation * Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2.0, Eigen::Vector3d::UnitY()));
    const double diameter = 2.0 * capsule.radius;
    collider(visualization_msgs::Marker::CYLINDER, capsule.center, z_along_axis,
             Eigen::Vector3d(diameter, diameter, 2.0 * capsule.half_length));
    for (double end : {-1.0, 1.0})
      collider(visualization_msgs::Marker::SPHERE, capsule.center + end * capsule.half_length * axis,
               Eigen::Quaterniond::Identity(), Eigen::Vector3d::Constant(diameter));
  }
  // The bodies' particle markers share style.max_points between them.
  const std::vector<int> strides = particleStrides(world, style);
  for (std::size_t b = 0; b < world.bodies().size(); ++b)
  {
    const core::Body& body = *world.bodies()[b];
    if (body.kind() == core::BodyKind::Emitter)
      addEmitter(static_cast<const core::EmitterBody&>(body), strides[b], stamp, style, out, samples);
    else if (body.kind() == core::BodyKind::SpringNetwork)
      addSpringBody(static_cast<const core::SpringNetworkBody&>(body), strides[b], stamp, style, out);
  }
  samples.asked = false;
  return out;
}

void snapshotNextStep(core::World& world, const MarkerStyle& style, MarkerSamples& samples)
{
  const std::vector<int> strides = particleStrides(world, style);
  // Every emitter's entry first: the emitters keep pointers into them.
  const auto emitters = static_cast<std::size_t>(
      std::count_if(world.bodies().begin(), world.bodies().end(),
                    [](const auto& body) { return body->kind() == core::BodyKind::Emitter; }));
  if (samples.emitters.size() < emitters) samples.emitters.resize(emitters);
  std::size_t e = 0;
  for (std::size_t b = 0; b < world.bodies().size(); ++b)
  {
    if (world.bodies()[b]->kind() != core::BodyKind::Emitter) continue;
    auto& emitter = static_cast<core::EmitterBody&>(*world.bodies()[b]);
    EmitterMarkerSample& sample = samples.emitters[e++];
    sample.emitter = &emitter;
    sample.particles.stride = 0;  // until the step takes it
    emitter.snapshotNextStep(strides[b], &sample.particles);
  }
  samples.asked = true;
}

void forgetSnapshotRequests(core::World& world)
{
  for (const auto& body : world.bodies())
    if (body->kind() == core::BodyKind::Emitter) static_cast<core::EmitterBody&>(*body).snapshotNextStep(0, nullptr);
}

}  // namespace ros_interface
}  // namespace particle_sim
