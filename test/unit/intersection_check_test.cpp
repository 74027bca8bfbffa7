// The brute-force intersection checks of intersection_check.h against independent truth: hand-built
// configurations with known answers (crossing, 1e-6 apart, coplanar, touching), rigid motions that
// must not change the answer, an orientation-predicate reference on random triangles in general
// position, dense sampling of segments and triangles for the distances, and meshes and chains
// whose self-intersections are known by construction.

#include "intersection_check.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

namespace
{
using Eigen::Vector3d;
using particle_sim_test::countChainCrossings;
using particle_sim_test::countIntersectionsBetween;
using particle_sim_test::countSurfaceIntersections;
using particle_sim_test::segmentDistance;
using particle_sim_test::triangleDistance;
using particle_sim_test::trianglesIntersect;

struct Triangle
{
  Vector3d p[3];
};

bool intersect(const Triangle& a, const Triangle& b)
{
  return trianglesIntersect(a.p[0], a.p[1], a.p[2], b.p[0], b.p[1], b.p[2]);
}

double distance(const Triangle& a, const Triangle& b)
{
  return triangleDistance(a.p[0], a.p[1], a.p[2], b.p[0], b.p[1], b.p[2]);
}

// Both argument orders and both vertex windings must give the same answer.
void expectIntersect(const Triangle& a, const Triangle& b, bool expected)
{
  const Triangle a_flipped{{a.p[0], a.p[2], a.p[1]}};
  const Triangle b_rotated{{b.p[1], b.p[2], b.p[0]}};
  EXPECT_EQ(intersect(a, b), expected);
  EXPECT_EQ(intersect(b, a), expected);
  EXPECT_EQ(intersect(a_flipped, b_rotated), expected);
  EXPECT_EQ(intersect(b_rotated, a_flipped), expected);
}

Triangle shifted(const Triangle& t, const Vector3d& offset)
{
  return Triangle{{t.p[0] + offset, t.p[1] + offset, t.p[2] + offset}};
}

const Triangle kUnit{{Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)}};  // in z = 0

// A random rotation (normalised Gaussian quaternion) and a translation in [-10, 10]^3.
Eigen::Isometry3d randomRigid(std::mt19937& rng)
{
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-10.0, 10.0);
  Eigen::Quaterniond q(gauss(rng), gauss(rng), gauss(rng), gauss(rng));
  q.normalize();
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = q.toRotationMatrix();
  t.translation() = Vector3d(uniform(rng), uniform(rng), uniform(rng));
  return t;
}

Triangle transformed(const Eigen::Isometry3d& t, const Triangle& tri)
{
  return Triangle{{t * tri.p[0], t * tri.p[1], t * tri.p[2]}};
}

// Independent reference for triangles in general position: the orientation predicate
// orient(a, b, c, d) = ((b - a) x (c - a)) . (d - a). Segment pq pierces triangle abc iff p and q lie
// on opposite sides of its plane and the line pq passes on the same side of all three directed edges.
// Two triangles in general position intersect iff an edge of one pierces the other. `ambiguous` is
// set when a predicate is too close to 0 for its sign to be trusted.
double orient(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& d)
{
  return (b - a).cross(c - a).dot(d - a);
}

bool pierces(const Vector3d& p, const Vector3d& q, const Triangle& t, bool* ambiguous)
{
  const double eps = 1e-7;
  const double sp = orient(t.p[0], t.p[1], t.p[2], p);
  const double sq = orient(t.p[0], t.p[1], t.p[2], q);
  if (std::abs(sp) < eps || std::abs(sq) < eps) *ambiguous = true;
  if ((sp > 0) == (sq > 0)) return false;
  const double s0 = orient(p, q, t.p[0], t.p[1]);
  const double s1 = orient(p, q, t.p[1], t.p[2]);
  const double s2 = orient(p, q, t.p[2], t.p[0]);
  if (std::abs(s0) < eps || std::abs(s1) < eps || std::abs(s2) < eps) *ambiguous = true;
  return (s0 > 0 && s1 > 0 && s2 > 0) || (s0 < 0 && s1 < 0 && s2 < 0);
}

bool referenceIntersect(const Triangle& a, const Triangle& b, bool* ambiguous)
{
  bool result = false;
  for (int i = 0; i < 3; ++i)
  {
    result = pierces(a.p[i], a.p[(i + 1) % 3], b, ambiguous) || result;
    result = pierces(b.p[i], b.p[(i + 1) % 3], a, ambiguous) || result;
  }
  return result;
}

// Points of a triangle on a barycentric grid with n subdivisions.
std::vector<Vector3d> sampleTriangle(const Triangle& t, int n)
{
  std::vector<Vector3d> points;
  for (int i = 0; i <= n; ++i)
  {
    for (int j = 0; i + j <= n; ++j)
    {
      const double u = static_cast<double>(i) / n, v = static_cast<double>(j) / n;
      points.push_back((1.0 - u - v) * t.p[0] + u * t.p[1] + v * t.p[2]);
    }
  }
  return points;
}

double longestEdge(const Triangle& t)
{
  return std::max(std::max((t.p[1] - t.p[0]).norm(), (t.p[2] - t.p[1]).norm()), (t.p[0] - t.p[2]).norm());
}

// An n x n vertex grid of spacing 1 / (n - 1) over [0, 1]^2, mapped through `place(u, v)`, each cell
// split into two triangles along alternating diagonals.
struct Mesh
{
  Eigen::Matrix3Xd x;
  std::vector<Eigen::Vector3i> triangles;
};

template <typename Place>
Mesh gridMesh(int n, Place place)
{
  Mesh mesh;
  mesh.x.resize(3, n * n);
  for (int j = 0; j < n; ++j)
  {
    for (int i = 0; i < n; ++i)
    {
      mesh.x.col(j * n + i) = place(static_cast<double>(i) / (n - 1), static_cast<double>(j) / (n - 1));
    }
  }
  for (int j = 0; j + 1 < n; ++j)
  {
    for (int i = 0; i + 1 < n; ++i)
    {
      const int a = j * n + i, b = a + 1, c = a + n, d = c + 1;
      if ((i + j) % 2 == 0)
      {
        mesh.triangles.emplace_back(a, b, d);
        mesh.triangles.emplace_back(a, d, c);
      }
      else
      {
        mesh.triangles.emplace_back(a, b, c);
        mesh.triangles.emplace_back(b, d, c);
      }
    }
  }
  return mesh;
}

Mesh flatGrid(int n)
{
  return gridMesh(n, [](double u, double v) { return Vector3d(u, v, 0.0); });
}

// The grid folded at u = 0.5: the half u > 0.5 comes back over the lower half (x = 1 - u) at the
// height z = 4 s (c - s), s = u - 0.5: above it for c >= 0.5, crossing it at x = 0.5 - c for c < 0.5.
Mesh foldedGrid(int n, double c)
{
  return gridMesh(n, [c](double u, double v) {
    if (u <= 0.5) return Vector3d(u, v, 0.0);
    const double s = u - 0.5;
    return Vector3d(0.5 - s, v, 4.0 * s * (c - s));
  });
}

// All pairs sharing no vertex, without the bounding-box rejection: checks that the rejection loses
// nothing.
int bruteForceCount(const Mesh& mesh)
{
  int count = 0;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
  {
    for (std::size_t j = i + 1; j < mesh.triangles.size(); ++j)
    {
      const Eigen::Vector3i& s = mesh.triangles[i];
      const Eigen::Vector3i& t = mesh.triangles[j];
      bool shared = false;
      for (int k = 0; k < 3; ++k)
        shared = shared || s[k] == t[0] || s[k] == t[1] || s[k] == t[2];
      if (shared) continue;
      if (trianglesIntersect(mesh.x.col(s[0]), mesh.x.col(s[1]), mesh.x.col(s[2]), mesh.x.col(t[0]), mesh.x.col(t[1]),
                             mesh.x.col(t[2])))
      {
        ++count;
      }
    }
  }
  return count;
}
}  // namespace

// ---------------------------------------------------------------------------------------------
// Triangle pairs with known answers

TEST(IntersectionCheck, PiercingTrianglesIntersect)
{
  // One edge of b goes through the interior of the unit triangle at (0.25, 0.2, 0).
  const Triangle b{{Vector3d(0.2, 0.2, -0.5), Vector3d(0.3, 0.2, 0.5), Vector3d(0.2, 0.3, 0.5)}};
  expectIntersect(kUnit, b, true);
  EXPECT_NEAR(distance(kUnit, b), 0.0, 1e-15);
  // A triangle standing across another: two of its edges pierce it, no vertex of either is inside
  // the other.
  const Triangle flat{{Vector3d(-1, -1, 0), Vector3d(1, -1, 0), Vector3d(0, 1, 0)}};
  const Triangle standing{{Vector3d(-0.5, 0, -1), Vector3d(0.5, 0, -1), Vector3d(0, 0, 1)}};
  expectIntersect(flat, standing, true);
  // Mutually linked: each pierces the other through an edge.
  const Triangle ring_a{{Vector3d(0, 0, 0), Vector3d(2, 0, 0), Vector3d(1, 0, 2)}};      // in y = 0
  const Triangle ring_b{{Vector3d(1, -1, 1), Vector3d(1, 1, 1), Vector3d(1, 0.5, -1)}};  // in x = 1
  expectIntersect(ring_a, ring_b, true);
}

TEST(IntersectionCheck, TrianglesSeparatedByOneMicronDoNotIntersect)
{
  // b's lowest vertex hovers 1e-6 above the interior of the unit triangle.
  const Triangle b{{Vector3d(0.2, 0.2, 1e-6), Vector3d(0.3, 0.2, 1), Vector3d(0.2, 0.3, 1)}};
  expectIntersect(kUnit, b, false);
  EXPECT_NEAR(distance(kUnit, b), 1e-6, 1e-15);
  // Parallel planes 1e-6 apart, overlapping in projection.
  const Triangle above = shifted(kUnit, Vector3d(0.1, 0.1, 1e-6));
  expectIntersect(kUnit, above, false);
  EXPECT_NEAR(distance(kUnit, above), 1e-6, 1e-15);
  // Far apart.
  expectIntersect(kUnit, shifted(kUnit, Vector3d(5, 5, 5)), false);
}

TEST(IntersectionCheck, CoplanarOverlappingTrianglesIntersect)
{
  // Partial overlap: edges cross.
  expectIntersect(kUnit, Triangle{{Vector3d(0.2, 0.2, 0), Vector3d(1.2, 0.2, 0), Vector3d(0.2, 1.2, 0)}}, true);
  // One strictly inside the other: no edges cross, only containment.
  expectIntersect(kUnit, Triangle{{Vector3d(0.1, 0.1, 0), Vector3d(0.3, 0.1, 0), Vector3d(0.1, 0.3, 0)}}, true);
  // Identical triangles.
  expectIntersect(kUnit, kUnit, true);
  // Star of David: each pokes its vertices out through the other's edges.
  const Triangle up{{Vector3d(-1, -0.5, 0), Vector3d(1, -0.5, 0), Vector3d(0, 1, 0)}};
  const Triangle down{{Vector3d(-1, 0.5, 0), Vector3d(0, -1, 0), Vector3d(1, 0.5, 0)}};
  expectIntersect(up, down, true);
}

TEST(IntersectionCheck, CoplanarDisjointAndTouchingTriangles)
{
  // Left of the unit triangle's edge x = 0, 1e-6 away.
  const Triangle left{{Vector3d(-1e-6, 0.2, 0), Vector3d(-1, 0.2, 0), Vector3d(-1e-6, 0.8, 0)}};
  expectIntersect(kUnit, left, false);
  EXPECT_NEAR(distance(kUnit, left), 1e-6, 1e-15);
  // Beyond the hypotenuse x + y = 1.
  expectIntersect(kUnit, shifted(kUnit, Vector3d(0.6, 0.6, 0)), false);
  // Sharing part of an edge exactly: touching counts.
  expectIntersect(kUnit, shifted(left, Vector3d(1e-6, 0, 0)), true);
  // Meeting at one vertex (different vertex objects at the same position).
  expectIntersect(kUnit, Triangle{{Vector3d(1, 0, 0), Vector3d(2, 0, 0), Vector3d(2, 1, 0)}}, true);
}

TEST(IntersectionCheck, VertexTouchingFaceIntersects)
{
  // From above and from below; both count as contact.
  expectIntersect(kUnit, Triangle{{Vector3d(0.2, 0.2, 0), Vector3d(0.3, 0.2, 1), Vector3d(0.2, 0.3, 1)}}, true);
  expectIntersect(kUnit, Triangle{{Vector3d(0.2, 0.2, 0), Vector3d(0.3, 0.2, -1), Vector3d(0.2, 0.3, -1)}}, true);
  // A vertex lying on an edge of the other.
  expectIntersect(kUnit, Triangle{{Vector3d(0.5, 0, 0), Vector3d(0.5, -1, 1), Vector3d(0.6, -1, 1)}}, true);
}

TEST(IntersectionCheck, EdgeThroughEdge)
{
  // a lies in z = 0 on the side y <= 0 of its edge along the x axis; b lies in x = 0 on the side
  // y >= 0 of its edge along the z axis. The two edges cross at the origin and nothing else meets.
  const Triangle a{{Vector3d(-1, 0, 0), Vector3d(1, 0, 0), Vector3d(0, -1, 0)}};
  const Triangle b{{Vector3d(0, 0, -1), Vector3d(0, 0, 1), Vector3d(0, 1, 0)}};
  expectIntersect(a, b, true);
  EXPECT_NEAR(distance(a, b), 0.0, 1e-15);
  // Pulled 1e-6 apart: separate.
  expectIntersect(a, shifted(b, Vector3d(0, 1e-6, 0)), false);
  EXPECT_NEAR(distance(a, shifted(b, Vector3d(0, 1e-6, 0))), 1e-6, 1e-15);
  // Pushed 1e-6 into each other: b's edge passes through a's interior.
  expectIntersect(a, shifted(b, Vector3d(0, -1e-6, 0)), true);
}

TEST(IntersectionCheck, RigidMotionsKeepTheAnswer)
{
  std::mt19937 rng(20240611u);
  const Triangle piercing{{Vector3d(0.2, 0.2, -0.5), Vector3d(0.3, 0.2, 0.5), Vector3d(0.2, 0.3, 0.5)}};
  const Triangle hovering{{Vector3d(0.2, 0.2, 1e-6), Vector3d(0.3, 0.2, 1), Vector3d(0.2, 0.3, 1)}};
  const Triangle touching{{Vector3d(0.2, 0.2, 0), Vector3d(0.3, 0.2, 1), Vector3d(0.2, 0.3, 1)}};
  const Triangle a{{Vector3d(-1, 0, 0), Vector3d(1, 0, 0), Vector3d(0, -1, 0)}};
  const Triangle edge_gap{{Vector3d(0, 1e-6, -1), Vector3d(0, 1e-6, 1), Vector3d(0, 1, 0)}};
  for (int trial = 0; trial < 2000; ++trial)
  {
    const Eigen::Isometry3d t = randomRigid(rng);
    EXPECT_TRUE(intersect(transformed(t, kUnit), transformed(t, piercing))) << trial;
    EXPECT_FALSE(intersect(transformed(t, kUnit), transformed(t, hovering))) << trial;
    EXPECT_NEAR(distance(transformed(t, kUnit), transformed(t, hovering)), 1e-6, 1e-13) << trial;
    // An exact contact stays a contact: round-off of the motion is far below 1e-12 relative.
    EXPECT_TRUE(intersect(transformed(t, kUnit), transformed(t, touching))) << trial;
    EXPECT_FALSE(intersect(transformed(t, a), transformed(t, edge_gap))) << trial;
  }
}

TEST(IntersectionCheck, AgreesWithOrientationPredicatesOnRandomTriangles)
{
  std::mt19937 rng(7u);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const auto point = [&]() { return Vector3d(uniform(rng), uniform(rng), uniform(rng)); };
  int intersecting = 0, disjoint = 0;
  for (int trial = 0; trial < 20000; ++trial)
  {
    const Triangle a{{point(), point(), point()}};
    const Triangle b{{point(), point(), point()}};
    bool ambiguous = false;
    const bool expected = referenceIntersect(a, b, &ambiguous);
    if (ambiguous) continue;
    ASSERT_EQ(intersect(a, b), expected) << trial;
    ++(expected ? intersecting : disjoint);
  }
  EXPECT_GT(intersecting, 1000);
  EXPECT_GT(disjoint, 1000);
}

TEST(IntersectionCheck, TriangleDistanceMatchesDenseSampling)
{
  // The exact distance is a lower bound of every sampled pair's distance and is within the
  // sampling's Lipschitz bound of the closest sampled pair.
  std::mt19937 rng(11u);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const auto point = [&]() { return Vector3d(uniform(rng), uniform(rng), uniform(rng)); };
  const int n = 24;
  for (int trial = 0; trial < 60; ++trial)
  {
    const Triangle a{{point(), point(), point()}};
    const Triangle b = shifted(Triangle{{point(), point(), point()}}, Vector3d(uniform(rng), 0.0, 0.0));
    const double exact = distance(a, b);
    double sampled = std::numeric_limits<double>::infinity();
    for (const Vector3d& p : sampleTriangle(a, n))
    {
      for (const Vector3d& q : sampleTriangle(b, n))
        sampled = std::min(sampled, (p - q).norm());
    }
    EXPECT_LE(exact, sampled + 1e-12) << trial;
    EXPECT_LE(sampled, exact + (longestEdge(a) + longestEdge(b)) / n) << trial;
    if (exact > 1e-9)
    {
      EXPECT_FALSE(intersect(a, b)) << trial;
    }
    if (exact == 0.0)
    {
      EXPECT_TRUE(intersect(a, b)) << trial;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Meshes

TEST(IntersectionCheck, FlatGridHasNoSelfIntersections)
{
  const Mesh flat = flatGrid(21);
  EXPECT_EQ(countSurfaceIntersections(flat.x, flat.triangles), 0);
  // Folded over without crossing (the upper half stays above the lower one): still none.
  const Mesh folded = foldedGrid(21, 0.6);
  EXPECT_GT(folded.x.row(2).maxCoeff(), 0.1);
  EXPECT_EQ(countSurfaceIntersections(folded.x, folded.triangles), 0);
  EXPECT_EQ(bruteForceCount(folded), 0);
}

TEST(IntersectionCheck, FoldedGridCrossingItselfIsCounted)
{
  const int n = 21;
  // The upper half dives through the lower half along the line x = 0.17 (no vertex lies on it).
  const Mesh crossing = foldedGrid(n, 0.33);
  const int count = countSurfaceIntersections(crossing.x, crossing.triangles);
  EXPECT_GT(count, 0);
  EXPECT_GE(count, n - 1);  // at least one crossing pair in each strip of cells along y
  EXPECT_EQ(count, bruteForceCount(crossing));
  // Every reported pair has one triangle in each half, near the crossing line.
  for (const auto& [i, j] : particle_sim_test::surfaceIntersectionPairs(crossing.x, crossing.triangles))
  {
    for (int k : {i, j})
    {
      const Eigen::Vector3i& t = crossing.triangles[k];
      for (int v = 0; v < 3; ++v)
        EXPECT_NEAR(crossing.x(0, t[v]), 0.17, 0.1);
    }
  }
}

TEST(IntersectionCheck, IntersectionsBetweenTwoMeshes)
{
  const Mesh flat = flatGrid(11);
  const Mesh above = gridMesh(11, [](double u, double v) { return Vector3d(u + 0.03, v + 0.03, 1e-6); });
  EXPECT_EQ(countIntersectionsBetween(flat.x, flat.triangles, above.x, above.triangles), 0);
  // A vertical sheet through the middle of the flat one.
  const Mesh wall = gridMesh(11, [](double u, double v) { return Vector3d(0.53, u, v - 0.5); });
  const int through = countIntersectionsBetween(flat.x, flat.triangles, wall.x, wall.triangles);
  EXPECT_GT(through, 0);
  EXPECT_EQ(through, countIntersectionsBetween(wall.x, wall.triangles, flat.x, flat.triangles));
  // A vertical sheet lifted 1e-6 clear of it.
  const Mesh lifted = gridMesh(11, [](double u, double v) { return Vector3d(0.53, u, v + 1e-6); });
  EXPECT_EQ(countIntersectionsBetween(flat.x, flat.triangles, lifted.x, lifted.triangles), 0);
}

TEST(IntersectionCheck, BadTriangleIndexThrows)
{
  const Mesh flat = flatGrid(3);
  std::vector<Eigen::Vector3i> triangles = flat.triangles;
  triangles.emplace_back(0, 1, 9);
  EXPECT_THROW(countSurfaceIntersections(flat.x, triangles), std::out_of_range);
}

// ---------------------------------------------------------------------------------------------
// Segments and chains

TEST(IntersectionCheck, SegmentDistanceHandComputed)
{
  const Vector3d o(0, 0, 0), x1(1, 0, 0);
  // Parallel, overlapping in projection: the lines' distance.
  EXPECT_NEAR(segmentDistance(o, x1, Vector3d(0.5, 1, 0), Vector3d(2, 1, 0)), 1.0, 1e-15);
  // Parallel, not overlapping: endpoint (1,0,0) to endpoint (2,1,0); also reversed.
  EXPECT_NEAR(segmentDistance(o, x1, Vector3d(2, 1, 0), Vector3d(3, 1, 0)), std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(segmentDistance(o, x1, Vector3d(3, 1, 0), Vector3d(2, 1, 0)), std::sqrt(2.0), 1e-15);
  // Collinear: apart by 2, and overlapping.
  EXPECT_NEAR(segmentDistance(o, x1, Vector3d(3, 0, 0), Vector3d(4, 0, 0)), 2.0, 1e-15);
  EXPECT_NEAR(segmentDistance(o, x1, Vector3d(0.5, 0, 0), Vector3d(3, 0, 0)), 0.0, 1e-15);
  // Skew, closest points interior to both: the x axis and a line along y at height 2.
  EXPECT_NEAR(segmentDistance(Vector3d(-1, 0, 0), x1, Vector3d(0, -1, 2), Vector3d(0, 1, 2)), 2.0, 1e-15);
  // Skew, oblique: (0,1,1)-(2,-1,1) passes over (1,0,0) at height 1.
  EXPECT_NEAR(segmentDistance(o, Vector3d(2, 0, 0), Vector3d(0, 1, 1), Vector3d(2, -1, 1)), 1.0, 1e-15);
  // Skew, clamped on one segment: (1,0,0) to (2,0,1).
  EXPECT_NEAR(segmentDistance(o, x1, Vector3d(2, -1, 1), Vector3d(2, 1, 1)), std::sqrt(2.0), 1e-15);
  // Skew, clamped on both: (1,0,0) to (2,1,1) (closest points of the lines lie beyond both ends).
  EXPECT_NEAR(segmentDistance(o, x1, Vector3d(2, 1, 1), Vector3d(2, 2, 1)), std::sqrt(3.0), 1e-15);
  // Crossing at interior points, and a T junction at an endpoint.
  EXPECT_NEAR(segmentDistance(Vector3d(-1, 0, 0), x1, Vector3d(0, -1, 0), Vector3d(0, 1, 0)), 0.0, 1e-15);
  EXPECT_NEAR(segmentDistance(Vector3d(-1, 0, 0), x1, o, Vector3d(0, 1, 0)), 0.0, 1e-15);
  // Degenerate segments (points).
  EXPECT_NEAR(segmentDistance(o, o, Vector3d(1, -1, 1), Vector3d(1, 1, 1)), std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(segmentDistance(o, o, Vector3d(3, 4, 0), Vector3d(3, 4, 0)), 5.0, 1e-15);
  // Nearly parallel: (0,0,0)-(1,0,0) and (0,1,0)-(1,1+1e-9,0): closest endpoints, distance 1.
  EXPECT_NEAR(segmentDistance(o, x1, Vector3d(0, 1, 0), Vector3d(1, 1 + 1e-9, 0)), 1.0, 1e-15);
}

TEST(IntersectionCheck, SegmentDistanceMatchesDenseSampling)
{
  std::mt19937 rng(3u);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const auto point = [&]() { return Vector3d(uniform(rng), uniform(rng), uniform(rng)); };
  const int n = 400;
  for (int trial = 0; trial < 200; ++trial)
  {
    const Vector3d p0 = point(), p1 = point(), q0 = point();
    // Every fourth pair parallel.
    const Vector3d q1 = trial % 4 == 0 ? Vector3d(q0 + 0.7 * (p1 - p0)) : point();
    const double exact = segmentDistance(p0, p1, q0, q1);
    EXPECT_NEAR(exact, segmentDistance(q1, q0, p1, p0), 1e-14) << trial;
    double sampled = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= n; ++i)
    {
      const Vector3d p = p0 + (static_cast<double>(i) / n) * (p1 - p0);
      for (int j = 0; j <= n; ++j)
        sampled = std::min(sampled, (p - q0 - (static_cast<double>(j) / n) * (q1 - q0)).norm());
    }
    EXPECT_LE(exact, sampled + 1e-14) << trial;
    EXPECT_LE(sampled, exact + 0.5 * ((p1 - p0).norm() + (q1 - q0).norm()) / n) << trial;
  }
}

TEST(IntersectionCheck, StraightChainHasNoCrossings)
{
  const int count = 50;
  Eigen::Matrix3Xd x(3, count);
  for (int i = 0; i < count; ++i)
    x.col(i) = Vector3d(0.02 * i, 0.0, 1.0);
  EXPECT_EQ(countChainCrossings(x, 0, count, 0.01), 0);
  // Non-adjacent segments of a straight chain are one segment length apart.
  EXPECT_EQ(countChainCrossings(x, 0, count, 0.0199), 0);
  EXPECT_EQ(countChainCrossings(x, 0, count, 0.0201), count - 3);  // the pairs with |i - j| = 2
  // Fewer than four particles have no non-adjacent segments.
  EXPECT_EQ(countChainCrossings(x, 0, 3, 1.0), 0);
}

TEST(IntersectionCheck, ChainForcedThroughItselfIsCounted)
{
  // Three unrelated particles, then the chain (0,0,0) (2,0,0) (2,1,0) (1,1,0) (1,-1,0): its last
  // segment crosses its first at (1,0,0); the other non-adjacent pairs are 1 apart.
  Eigen::Matrix3Xd x(3, 8);
  x.col(0) = Vector3d(1, 0, 0);
  x.col(1) = Vector3d(1, 0, 0.001);
  x.col(2) = Vector3d(5, 5, 5);
  x.col(3) = Vector3d(0, 0, 0);
  x.col(4) = Vector3d(2, 0, 0);
  x.col(5) = Vector3d(2, 1, 0);
  x.col(6) = Vector3d(1, 1, 0);
  x.col(7) = Vector3d(1, -1, 0);
  EXPECT_EQ(countChainCrossings(x, 3, 5, 0.1), 1);
  EXPECT_EQ(countChainCrossings(x, 3, 5, 1.0 + 1e-9), 3);
  EXPECT_EQ(countChainCrossings(x, 3, 4, 0.1), 0);  // without the crossing segment
  // A figure eight (x, y) = (sin 2t, sin t) of 40 particles, t = pi/2 + 2 pi (i + 1/2) / 40: segments
  // 9 and 29 are symmetric about the origin and cross there at their midpoints. Lifted by
  // z = 1e-3 cos t, the branches pass 2e-3 apart instead.
  const int count = 40;
  const auto figureEight = [count](double lift) {
    Eigen::Matrix3Xd chain(3, count);
    for (int i = 0; i < count; ++i)
    {
      const double t = 0.5 * M_PI + 2.0 * M_PI * (i + 0.5) / count;
      chain.col(i) = Vector3d(std::sin(2.0 * t), std::sin(t), lift * std::cos(t));
    }
    return chain;
  };
  EXPECT_EQ(countChainCrossings(figureEight(0.0), 0, count, 1e-9), 1);
  EXPECT_EQ(countChainCrossings(figureEight(1e-3), 0, count, 1e-9), 0);
  EXPECT_EQ(countChainCrossings(figureEight(1e-3), 0, count, 0.01), 1);
  // A chain wound three times around the same circle: its turns lie on each other.
  const int wound = 61;
  Eigen::Matrix3Xd circle(3, wound);
  for (int i = 0; i < wound; ++i)
  {
    const double angle = 2.0 * M_PI * i / 20.0;  // 20 particles a turn
    circle.col(i) = Vector3d(std::cos(angle), std::sin(angle), 0.0);
  }
  EXPECT_GT(countChainCrossings(circle, 0, wound, 1e-9), 0);
  EXPECT_THROW(countChainCrossings(circle, 10, wound, 0.1), std::out_of_range);
}
