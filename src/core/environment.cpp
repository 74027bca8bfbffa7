#include "particle_sim/core/environment.h"

#include <algorithm>
#include <cmath>

#include "particle_sim/core/validation.h"

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

void resolveCollisions(const Environment& env, ParticlePool& pool, const Eigen::Matrix3Xd* start_velocity,
                       const Eigen::Matrix3Xd* start_position, double thickness)
{
  // The contact thickness grows every collider: the ground rises by it, spheres get thicker.
  const double ground_height = env.ground.height + thickness;
  const int n = pool.size();
  for (int i = 0; i < n; ++i)
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
  }
}

}  // namespace core
}  // namespace particle_sim
