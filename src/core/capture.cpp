#include "particle_sim/core/capture.h"

#include <algorithm>
#include <cmath>

namespace particle_sim
{
namespace core
{
std::vector<CapturedParticle> captureParticles(const SpringNetworkBody& body, const Eigen::Isometry3d& frame,
                                               const CaptureRegion& region, int& pinned_skipped)
{
  // Each free particle is taken into the gripper frame, y = frame⁻¹ x, and tested against the
  // region there; Nearest keeps the `count` smallest distances |y − c|.
  const Eigen::Isometry3d to_gripper = frame.inverse();
  const ParticlePool& p = body.particles();
  std::vector<CapturedParticle> inside;
  std::vector<std::pair<double, int>> by_distance;
  pinned_skipped = 0;
  for (int i = 0; i < p.size(); ++i)
  {
    const Eigen::Vector3d x = p.position.col(i);
    if (!x.allFinite()) continue;
    const Eigen::Vector3d y = to_gripper * x;
    const Eigen::Vector3d d = y - region.center;
    bool captured = false;
    switch (region.shape)
    {
      case CaptureRegion::Shape::Sphere:
        captured = d.norm() <= region.radius;
        break;
      case CaptureRegion::Shape::Box:
        captured = (d.cwiseAbs().array() <= region.half_extents.array()).all();
        break;
      case CaptureRegion::Shape::Nearest:
        if (!body.isPinned(i)) by_distance.emplace_back(d.norm(), i);
        break;
    }
    if (!captured) continue;
    if (body.isPinned(i))
      ++pinned_skipped;
    else
      inside.push_back({i, y});
  }
  if (region.shape != CaptureRegion::Shape::Nearest) return inside;

  const std::size_t keep =
      std::min<std::size_t>(by_distance.size(), static_cast<std::size_t>(std::max(0, region.count)));
  std::partial_sort(by_distance.begin(), by_distance.begin() + static_cast<std::ptrdiff_t>(keep), by_distance.end());
  by_distance.resize(keep);
  std::sort(by_distance.begin(), by_distance.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
  for (const auto& [distance, i] : by_distance)
    inside.push_back({i, to_gripper * Eigen::Vector3d(p.position.col(i))});
  return inside;
}

}  // namespace core
}  // namespace particle_sim
