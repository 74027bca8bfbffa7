// Capture regions of a grasp (core/capture.h): which particles a sphere, a box or "the N nearest"
// fixed in a moved and turned gripper frame takes, against brute-force answers computed in the sim
// frame (no inverse transform), and the offsets that put each particle back where it was.

#include "particle_sim/core/capture.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "particle_sim/core/builders/cloth_grid.h"

using namespace particle_sim::core;

namespace
{
// A flat 11 x 11 cloth, 1 m square in the xy plane at z = 1.
SpringNetworkBody makeCloth()
{
  ClothGridDef def;
  def.name = "sheet";
  def.origin = {0.0, 0.0, 1.0};
  def.edge_u = {1.0, 0.0, 0.0};
  def.edge_v = {0.0, 1.0, 0.0};
  def.nu = def.nv = 11;
  return SpringNetworkBody(buildClothGrid(def));
}

// The gripper: at (0.52, 0.31, 1.1) (no two particles equally far from it), turned 90° about z and then 30° about its
// x.
Eigen::Isometry3d gripperPose()
{
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translate(Eigen::Vector3d(0.52, 0.31, 1.1));
  pose.rotate(Eigen::AngleAxisd(M_PI / 2.0, Eigen::Vector3d::UnitZ()));
  pose.rotate(Eigen::AngleAxisd(M_PI / 6.0, Eigen::Vector3d::UnitX()));
  return pose;
}

std::vector<int> indicesOf(const std::vector<CapturedParticle>& captured)
{
  std::vector<int> out;
  for (const CapturedParticle& c : captured)
    out.push_back(c.index);
  return out;
}
}  // namespace

TEST(Capture, SphereInATurnedFrameTakesWhatIsWithinItsRadiusAndKnowsEachOffset)
{
  const SpringNetworkBody cloth = makeCloth();
  const Eigen::Isometry3d pose = gripperPose();
  CaptureRegion region;
  region.shape = CaptureRegion::Shape::Sphere;
  region.center = {0.0, 0.1, -0.05};
  region.radius = 0.23;
  // Brute force in the sim frame: the centre is R c + t.
  const Eigen::Vector3d center = pose.linear() * region.center + pose.translation();
  std::vector<int> expected;
  for (int i = 0; i < cloth.particles().size(); ++i)
    if ((cloth.particles().position.col(i) - center).norm() <= region.radius) expected.push_back(i);
  ASSERT_GT(expected.size(), 5u);
  int skipped = -1;
  const std::vector<CapturedParticle> captured = captureParticles(cloth, pose, region, skipped);
  EXPECT_EQ(indicesOf(captured), expected);
  EXPECT_EQ(skipped, 0);
  for (const CapturedParticle& c : captured)
    EXPECT_LT((pose.linear() * c.offset + pose.translation() - cloth.particles().position.col(c.index)).norm(), 1e-12);
}

TEST(Capture, BoxAlongTheFramesAxesAndPinnedParticlesSkipped)
{
  SpringNetworkBody cloth = makeCloth();
  const Eigen::Isometry3d pose = gripperPose();
  CaptureRegion region;
  region.shape = CaptureRegion::Shape::Box;
  region.center = {0.05, -0.1, 0.0};
  region.half_extents = {0.32, 0.12, 0.2};
  // Brute force: the projections of x − centre on the frame's axes (columns of R).
  const Eigen::Vector3d center = pose.linear() * region.center + pose.translation();
  std::vector<int> inside;
  for (int i = 0; i < cloth.particles().size(); ++i)
  {
    const Eigen::Vector3d d = cloth.particles().position.col(i) - center;
    bool in = true;
    for (int axis = 0; axis < 3; ++axis)
      in = in && std::abs(d.dot(pose.linear().col(axis))) <= region.half_extents[axis];
    if (in) inside.push_back(i);
  }
  ASSERT_GT(inside.size(), 5u);
  // Two of them pinned: left out, and counted.
  ASSERT_TRUE(cloth.pin(inside[0], cloth.particles().position.col(inside[0])).ok);
  ASSERT_TRUE(cloth.pin(inside[2], cloth.particles().position.col(inside[2])).ok);
  std::vector<int> expected = inside;
  expected.erase(expected.begin() + 2);
  expected.erase(expected.begin());
  int skipped = 0;
  EXPECT_EQ(indicesOf(captureParticles(cloth, pose, region, skipped)), expected);
  EXPECT_EQ(skipped, 2);
}

TEST(Capture, NearestTakesTheCountClosestFreeParticles)
{
  SpringNetworkBody cloth = makeCloth();
  const Eigen::Isometry3d pose = gripperPose();
  CaptureRegion region;
  region.shape = CaptureRegion::Shape::Nearest;
  region.center = {0.0, 0.0, 0.0};
  region.count = 7;
  // The nearest particle to the gripper's origin, pinned, is passed over.
  const Eigen::Vector3d center = pose.translation();
  std::vector<std::pair<double, int>> by_distance;
  for (int i = 0; i < cloth.particles().size(); ++i)
    by_distance.emplace_back((cloth.particles().position.col(i) - center).norm(), i);
  std::sort(by_distance.begin(), by_distance.end());
  ASSERT_TRUE(cloth.pin(by_distance[0].second, center).ok);
  std::vector<int> expected;
  for (int k = 1; k <= 7; ++k)
    expected.push_back(by_distance[static_cast<std::size_t>(k)].second);
  std::sort(expected.begin(), expected.end());
  int skipped = 0;
  EXPECT_EQ(indicesOf(captureParticles(cloth, pose, region, skipped)), expected);
  // More than there are: every free particle.
  region.count = 1000;
  EXPECT_EQ(captureParticles(cloth, pose, region, skipped).size(), 120u);
}
