#include "particle_sim/core/environment.h"

#include <algorithm>
#include <cmath>

#include "particle_sim/core/validation.h"
#include "particle_sim/core/worker_pool.h"

namespace particle_sim
{
namespace core
{
Status validate(const ContactDef& def, const std::string& where)
{
  if (Status s = checkRange(where + ".restitution", def.restitution, 0.0, 1.0); !s) return s;
  if (Status s = checkMin(where + ".bounce_speed", def.bounce_speed, 0.0); !s) return s;
  return checkMin(where + ".friction", def.friction, 0.0);
}

Status validate(const AirDef& def)
{
  if (Status s = checkMin("air.drag", def.drag, 0.0); !s) return s;
  return checkRange("air.wind", def.wind, limits::kWindComponent);
}

Status validate(const GroundPlaneDef& def)
{
  if (Status s = checkFinite("ground.height", def.height); !s) return s;
  return validate(def.contact, "ground");
}

Status validate(const SphereColliderDef& def)
{
  const std::string where = "sphere '" + def.name + "'";
  if (Status s = checkFinite(where + ".center", def.center); !s) return s;
  if (Status s = checkPositive(where + ".radius", def.radius); !s) return s;
  return validate(def.contact, where);
}

Status validateOrientation(const std::string& where, const Eigen::Quaterniond& q)
{
  const Eigen::Vector4d c = q.coeffs();
  if (!c.allFinite() || std::abs(q.norm() - 1.0) > 1e-6)
    return Status::failure(where + ".orientation = [" + formatValue(q.x()) + ", " + formatValue(q.y()) + ", " +
                           formatValue(q.z()) + ", " + formatValue(q.w()) +
                           "] (x, y, z, w) is not a unit quaternion: its norm must be 1 within 1e-6");
  return Status::success();
}

Status validate(const BoxColliderDef& def)
{
  const std::string where = "box '" + def.name + "'";
  if (Status s = checkFinite(where + ".center", def.center); !s) return s;
  if (Status s = validateOrientation(where, def.orientation); !s) return s;
  for (int k = 0; k < 3; ++k)
  {
    if (Status s = checkPositive(where + ".half_extents[" + std::to_string(k) + "]", def.half_extents[k]); !s) return s;
  }
  return validate(def.contact, where);
}

Status validate(const CapsuleColliderDef& def)
{
  const std::string where = "capsule '" + def.name + "'";
  if (Status s = checkFinite(where + ".center", def.center); !s) return s;
  if (Status s = validateOrientation(where, def.orientation); !s) return s;
  if (Status s = checkMin(where + ".half_length", def.half_length, 0.0); !s) return s;
  if (Status s = checkPositive(where + ".radius", def.radius); !s) return s;
  return validate(def.contact, where);
}

namespace
{
// Applies one contact: pushes the particle out along the outward unit normal n by (1 + e) times
// the penetration depth, reflects the inward normal velocity with restitution e (0 below the
// bounce speed) and removes tangential velocity by Coulomb friction on the normal impulse.
void respond(const ContactDef& contact, const Eigen::Vector3d& n, double depth, Eigen::Ref<Eigen::Vector3d> x,
             Eigen::Ref<Eigen::Vector3d> v, double start_vn)
{
  const double vn = v.dot(n);
  // Slow impacts (a particle resting on the surface, pulled in by one step) do not bounce: without
  // this, resting particles would keep a velocity they never move with.
  const bool impact = vn < -contact.bounce_speed && start_vn < -contact.bounce_speed;
  const double e = impact ? contact.restitution : 0.0;
  x += (1.0 + e) * depth * n;
  if (vn >= 0.0) return;  // already leaving the surface
  const Eigen::Vector3d v_tangent = v - vn * n;
  const double normal_change = -(1.0 + e) * vn;  // > 0
  const double tangent_speed = v_tangent.norm();
  const double tangent_loss = std::min(tangent_speed, contact.friction * normal_change);
  v = -e * vn * n;
  if (tangent_speed > 0.0) v += v_tangent * (1.0 - tangent_loss / tangent_speed);
}
}  // namespace

namespace
{
// The first s in (0, 1] where the segment a + s (b − a) enters the sphere (center, radius), or −1
// when it does not (both ends outside).
double entryOnSegment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& center, double radius)
{
  const Eigen::Vector3d d = b - a, f = a - center;
  const double qa = d.squaredNorm(), qb = 2.0 * f.dot(d), qc = f.squaredNorm() - radius * radius;
  if (qa == 0.0 || qc < 0.0) return -1.0;
  const double discriminant = qb * qb - 4.0 * qa * qc;
  if (discriminant < 0.0) return -1.0;
  const double s = (-qb - std::sqrt(discriminant)) / (2.0 * qa);
  return s > 0.0 && s <= 1.0 ? s : -1.0;
}
}  // namespace

namespace
{
// [m] How far inside a box a swept path may end and still be taken as sliding along its face.
constexpr double kGrazingDepth = 1e-9;

// The first s in (0, 1] where the segment a + s d enters the box |q_k| <= e_k (box coordinates), or
// −1 when it does not (a inside, or the segment misses it): the slab method. `face` is the axis of
// the face it enters through.
double entryIntoBox(const Eigen::Vector3d& a, const Eigen::Vector3d& d, const Eigen::Vector3d& e, int& face)
{
  double enter = 0.0, leave = 1.0;
  face = -1;
  for (int k = 0; k < 3; ++k)
  {
    if (d[k] == 0.0)
    {
      if (std::abs(a[k]) > e[k]) return -1.0;
      continue;
    }
    double t1 = (-e[k] - a[k]) / d[k], t2 = (e[k] - a[k]) / d[k];
    if (t1 > t2) std::swap(t1, t2);
    if (t1 > enter)
    {
      enter = t1;
      face = k;
    }
    leave = std::min(leave, t2);
    if (enter > leave) return -1.0;
  }
  return enter > 0.0 && face >= 0 ? enter : -1.0;
}

// The first s in (0, 1] where the segment a + s d enters the capsule of axis x, half length L and
// radius r (capsule coordinates), or −1: the side (a cylinder between x = ±L) and the two caps.
double entryIntoCapsule(const Eigen::Vector3d& a, const Eigen::Vector3d& d, double half_length, double r)
{
  double first = -1.0;
  auto consider = [&first](double s) {
    if (s > 0.0 && s <= 1.0 && (first < 0.0 || s < first)) first = s;
  };
  const double qa = d.y() * d.y() + d.z() * d.z(), qb = 2.0 * (a.y() * d.y() + a.z() * d.z());
  const double qc = a.y() * a.y() + a.z() * a.z() - r * r;
  if (qa > 0.0 && qc > 0.0)
  {
    const double discriminant = qb * qb - 4.0 * qa * qc;
    if (discriminant >= 0.0)
    {
      const double s = (-qb - std::sqrt(discriminant)) / (2.0 * qa);
      if (std::abs(a.x() + s * d.x()) <= half_length) consider(s);
    }
  }
  for (double cap : {-half_length, half_length})
    consider(entryOnSegment(a, a + d, Eigen::Vector3d(cap, 0.0, 0.0), r));
  return first;
}

// A contact with a collider moving rigidly (`motion`, about `center`): the response sees the
// particle's velocity relative to the surface point, and hands the surface's velocity back.
void respondMoving(const ContactDef& contact, const ColliderMotion& motion, const Eigen::Vector3d& center,
                   const Eigen::Vector3d& n, double depth, Eigen::Ref<Eigen::Vector3d> x, Eigen::Ref<Eigen::Vector3d> v,
                   double start_vn)
{
  const Eigen::Vector3d surface_velocity = motion.velocity + motion.angular_velocity.cross(Eigen::Vector3d(x) - center);
  Eigen::Vector3d relative = v - surface_velocity;
  respond(contact, n, depth, x, relative, start_vn - surface_velocity.dot(n));
  v = relative + surface_velocity;
}

// resolveCollisions for the particles [begin, end).
void resolveCollisionsOf(int begin, int end, const Environment& env, ParticlePool& pool,
                         const Eigen::Matrix3Xd* start_velocity, const Eigen::Matrix3Xd* start_position,
                         double thickness, double h)
{
  // The contact thickness grows every collider: the ground rises by it, spheres get thicker.
  const double ground_height = env.ground.height + thickness;
  for (int i = begin; i < end; ++i)
  {
    if (pool.inverse_mass[i] == 0.0) continue;  // pinned particles follow their target
    auto x = pool.position.col(i);
    auto v = pool.velocity.col(i);
    // The approach speed along n at the start of the step (the current one when not given).
    auto start_vn = [&](const Eigen::Vector3d& n) { return start_velocity ? start_velocity->col(i).dot(n) : v.dot(n); };

    // Ground plane z = height, normal +z.
    if (env.ground.enabled && x.z() < ground_height)
      respond(env.ground.contact, Eigen::Vector3d::UnitZ(), ground_height - x.z(), x, v,
              start_vn(Eigen::Vector3d::UnitZ()));

    // Spheres: outward normal from the centre through the particle.
    for (const SphereColliderDef& sphere : env.spheres)
    {
      const double radius = sphere.radius + thickness;
      // A path that entered the sphere (and maybe left it again): back to where it entered, just
      // inside, so that the contact below bounces it there rather than pushing it out of the far
      // side.
      if (start_position)
      {
        const double s = entryOnSegment(start_position->col(i), x, sphere.center, radius);
        if (s > 0.0)
        {
          const Eigen::Vector3d entry = start_position->col(i) + s * (x - start_position->col(i));
          x = entry + 1e-9 * radius * (sphere.center - entry).normalized();
        }
      }
      const Eigen::Vector3d offset = x - sphere.center;
      const double distance = offset.norm();
      if (distance >= radius) continue;
      const Eigen::Vector3d normal = distance > 1e-12 ? Eigen::Vector3d(offset / distance) : Eigen::Vector3d::UnitZ();
      respond(sphere.contact, normal, radius - distance, x, v, start_vn(normal));
    }

    // Boxes: in the box's coordinates q = Rᵀ (x − c), out through the nearest face of the box
    // grown by the thickness.
    for (const BoxColliderDef& box : env.boxes)
    {
      const Eigen::Matrix3d rotation = box.orientation.toRotationMatrix();
      const Eigen::Vector3d extents = box.half_extents.array() + thickness;
      const Eigen::Vector3d q = rotation.transpose() * (Eigen::Vector3d(x) - box.center);
      const Eigen::Vector3d depth = extents - q.cwiseAbs();
      // A path that ends inside by no more than rounding (one sliding along a face) is not swept:
      // its entry, found from a segment parallel to the face, could be anywhere along it.
      const bool grazing = depth.minCoeff() > 0.0 && depth.minCoeff() <= kGrazingDepth;
      if (start_position && !grazing)
      {
        // The path relative to the box, from where the particle was against where the box was: one
        // that entered it (and maybe left it again) stops on the face it entered through.
        const Eigen::Vector3d a =
            rotation.transpose() * (Eigen::Vector3d(start_position->col(i)) - (box.center - h * box.motion.velocity));
        int face = -1;
        const double s = entryIntoBox(a, q - a, extents, face);
        if (s > 0.0)
        {
          Eigen::Vector3d entry = a + s * (q - a);
          entry[face] = std::copysign(extents[face], a[face]);
          x = box.center + rotation * entry;
          const Eigen::Vector3d normal = rotation.col(face) * std::copysign(1.0, a[face]);
          respondMoving(box.contact, box.motion, box.center, normal, 0.0, x, v, start_vn(normal));
          continue;
        }
      }
      if (depth.minCoeff() <= 0.0) continue;
      int face = 0;
      depth.minCoeff(&face);
      const Eigen::Vector3d normal = rotation.col(face) * (q[face] < 0.0 ? -1.0 : 1.0);
      respondMoving(box.contact, box.motion, box.center, normal, depth[face], x, v, start_vn(normal));
    }

    // Capsules: out from the nearest point of the axis segment.
    for (const CapsuleColliderDef& capsule : env.capsules)
    {
      const Eigen::Matrix3d rotation = capsule.orientation.toRotationMatrix();
      const double radius = capsule.radius + thickness;
      Eigen::Vector3d q = rotation.transpose() * (Eigen::Vector3d(x) - capsule.center);
      if (start_position)
      {
        const Eigen::Vector3d a = rotation.transpose() * (Eigen::Vector3d(start_position->col(i)) -
                                                          (capsule.center - h * capsule.motion.velocity));
        const double s = entryIntoCapsule(a, q - a, capsule.half_length, radius);
        if (s > 0.0)
        {
          const Eigen::Vector3d entry = a + s * (q - a);
          const Eigen::Vector3d axis_point(std::clamp(entry.x(), -capsule.half_length, capsule.half_length), 0.0, 0.0);
          q = entry + 1e-9 * radius * (axis_point - entry).normalized();
          x = capsule.center + rotation * q;
        }
      }
      const Eigen::Vector3d axis_point(std::clamp(q.x(), -capsule.half_length, capsule.half_length), 0.0, 0.0);
      const Eigen::Vector3d offset = q - axis_point;
      const double distance = offset.norm();
      if (distance >= radius) continue;
      // On the axis itself any direction perpendicular to it will do: +z of the capsule.
      const Eigen::Vector3d local_normal =
          distance > 1e-12 ? Eigen::Vector3d(offset / distance) : Eigen::Vector3d::UnitZ();
      const Eigen::Vector3d normal = rotation * local_normal;
      respondMoving(capsule.contact, capsule.motion, capsule.center, normal, radius - distance, x, v, start_vn(normal));
    }
  }
}

}  // namespace

void resolveCollisions(const Environment& env, ParticlePool& pool, const Eigen::Matrix3Xd* start_velocity,
                       const Eigen::Matrix3Xd* start_position, double thickness, double h, WorkerPool* workers)
{
  // No collider, no pass over the particles.
  if (!env.hasColliders()) return;
  // Each particle is handled alone, so the particles may be shared between threads: the same bits.
  shareLoop(workers, pool.size(), kParticlesPerVectorChunk, [&](int begin, int end) {
    resolveCollisionsOf(begin, end, env, pool, start_velocity, start_position, thickness, h);
  });
}

void resolveCollisionsIn(int begin, int end, const Environment& env, ParticlePool& pool,
                         const Eigen::Matrix3Xd* start_velocity, const Eigen::Matrix3Xd* start_position,
                         double thickness, double h)
{
  if (env.hasColliders()) resolveCollisionsOf(begin, end, env, pool, start_velocity, start_position, thickness, h);
}

}  // namespace core
}  // namespace particle_sim
