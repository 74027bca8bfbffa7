#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "particle_sim/core/spring_network.h"

namespace particle_sim
{
namespace core
{
/// A region fixed in a gripper's frame that captures particles (a grasp, issue 14).
struct CaptureRegion
{
  enum class Shape
  {
    Sphere,   ///< the particles within `radius` of the centre
    Box,      ///< the particles inside the box of `half_extents` along the frame's axes
    Nearest,  ///< the `count` particles nearest the centre (ties: the lower index)
  };
  Shape shape = Shape::Sphere;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();        ///< [m] in the gripper frame
  double radius = 0.0;                                     ///< [m] Sphere
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();  ///< [m] Box, along the frame's axes
  int count = 0;                                           ///< Nearest
};

/// A particle of a body and where it sits in the gripper frame.
struct CapturedParticle
{
  int index = 0;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< [m] in the gripper frame: frame⁻¹ x
};

/// The particles of `body` that `region`, in the gripper frame whose pose in the sim frame is
/// `frame` (x_sim = frame · x_gripper), captures, in index order. Pinned particles are left out (a
/// particle has one holder) and counted in `pinned_skipped`; non-finite ones are left out. Nearest
/// takes the `count` nearest among this body's free particles.
std::vector<CapturedParticle> captureParticles(const SpringNetworkBody& body, const Eigen::Isometry3d& frame,
                                               const CaptureRegion& region, int& pinned_skipped);

}  // namespace core
}  // namespace particle_sim
