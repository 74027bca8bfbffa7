#include "particle_sim/core/constraints/resting_contact.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace particle_sim
{
namespace core
{
void findRestingContacts(const Environment& env, const ParticlePool& pool, double thickness,
                         std::vector<RestingContact>& out)
{
  // For each particle, the signed distance to every collider grown by the thickness; the smallest
  // one within kRestingContactDistance is its contact. No collider, no pass over the particles.
  out.clear();
  if (!env.hasColliders()) return;
  const int n = pool.size();
  for (int i = 0; i < n; ++i)
  {
    if (pool.inverse_mass[i] == 0.0) continue;  // pinned particles follow their target
    const Eigen::Vector3d x = pool.position.col(i);
    RestingContact contact;
    double nearest = kRestingContactDistance;
    auto consider = [&](double distance, const Eigen::Vector3d& normal, const Eigen::Vector3d& surface_velocity,
                        const ContactDef& def) {
      if (distance > nearest) return;
      nearest = distance;
      contact.particle = i;
      contact.normal = normal;
      contact.surface_velocity = surface_velocity;
      contact.friction = def.friction;
    };

    if (env.ground.enabled)
      consider(x.z() - (env.ground.height + thickness), Eigen::Vector3d::UnitZ(), Eigen::Vector3d::Zero(),
               env.ground.contact);
    for (const SphereColliderDef& sphere : env.spheres)
    {
      const Eigen::Vector3d offset = x - sphere.center;
      const double distance = offset.norm();
      if (distance > 1e-12)
        consider(distance - (sphere.radius + thickness), offset / distance, Eigen::Vector3d::Zero(), sphere.contact);
    }
    // Boxes, in the box's coordinates q = Rᵀ (x − c): outside, from the nearest point of the box
    // (on a face, an edge or a corner); inside, out through the nearest face.
    for (const BoxColliderDef& box : env.boxes)
    {
      const Eigen::Matrix3d rotation = box.orientation.toRotationMatrix();
      const Eigen::Vector3d extents = box.half_extents.array() + thickness;
      const Eigen::Vector3d q = rotation.transpose() * (x - box.center);
      const Eigen::Vector3d offset = q - q.cwiseMax(-extents).cwiseMin(extents);
      const Eigen::Vector3d surface_velocity = box.motion.velocity + box.motion.angular_velocity.cross(x - box.center);
      if (const double distance = offset.norm(); distance > 0.0)
      {
        consider(distance, rotation * (offset / distance), surface_velocity, box.contact);
        continue;
      }
      int face = 0;
      const double distance = (q.cwiseAbs() - extents).maxCoeff(&face);  // <= 0
      consider(distance, rotation.col(face) * (q[face] < 0.0 ? -1.0 : 1.0), surface_velocity, box.contact);
    }
    // Capsules: from the nearest point of the axis segment.
    for (const CapsuleColliderDef& capsule : env.capsules)
    {
      const Eigen::Matrix3d rotation = capsule.orientation.toRotationMatrix();
      const Eigen::Vector3d q = rotation.transpose() * (x - capsule.center);
      const Eigen::Vector3d offset =
          q - Eigen::Vector3d(std::clamp(q.x(), -capsule.half_length, capsule.half_length), 0.0, 0.0);
      const double distance = offset.norm();
      if (distance > 1e-12)
        consider(distance - (capsule.radius + thickness), rotation * (offset / distance),
                 capsule.motion.velocity + capsule.motion.angular_velocity.cross(x - capsule.center), capsule.contact);
    }
    if (contact.particle >= 0) out.push_back(contact);
  }
}

}  // namespace core
}  // namespace particle_sim
