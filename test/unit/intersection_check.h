#pragma once
// Test-only, brute-force geometry that proves cloth and ropes never pass through themselves or
// each other. Deliberately independent of the simulator (Eigen only, no code shared with src/core,
// no broad phase beyond an axis-aligned bounding-box rejection), so that a bug in the collision
// code cannot hide itself by being repeated here.
//
// Contact convention: two triangles (or a rope's segments) "intersect" when they really cross or
// when they come within kContactRelativeTolerance (1e-12) times the scale of the numbers involved
// (the largest edge length or coordinate magnitude, whichever is larger). Exact touching (a vertex
// lying in the other's face, two edges meeting at a point, coplanar triangles sharing an edge)
// therefore counts as intersecting, and a gap that is only round-off after a rotation or a
// translation still counts as touching; any gap larger than 1e-12 relative is a clean separation.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace particle_sim_test
{
constexpr double kContactRelativeTolerance = 1e-12;

// Closest distance from point p to the segment [a, b]: project p on the segment's line and clamp
// the parameter to [0, 1]; a zero-length segment is its point a.
inline double pointSegmentDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  double t = 0.0;
  if (len2 > 0.0) t = std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
  return (a + t * ab - p).norm();
}

// Exact closest distance between the segments [p0, p1] and [q0, q1]. The squared distance
// |P(s) - Q(t)|^2 is a convex quadratic on the unit square (s, t) in [0, 1]^2, so its minimum is
// either the stationary point, when that point lies strictly inside the square and is unique (the
// segments are not parallel), or lies on the square's boundary, where one parameter is 0 or 1: one
// of the four endpoint-to-segment distances. Parallel (and degenerate) segments have no unique
// stationary point and their minimum is always attained at an endpoint, so they need no special
// case beyond skipping the 2x2 solve. The determinant is computed as |u x v|^2 to avoid the
// cancellation of a c - b^2 for nearly parallel segments.
inline double segmentDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& q0,
                              const Eigen::Vector3d& q1)
{
  double best = std::min(std::min(pointSegmentDistance(p0, q0, q1), pointSegmentDistance(p1, q0, q1)),
                         std::min(pointSegmentDistance(q0, p0, p1), pointSegmentDistance(q1, p0, p1)));
  const Eigen::Vector3d u = p1 - p0;
  const Eigen::Vector3d v = q1 - q0;
  const Eigen::Vector3d w = p0 - q0;
  const double denom = u.cross(v).squaredNorm();
  if (denom > 0.0)
  {
    const double a = u.dot(u), b = u.dot(v), c = v.dot(v), d = u.dot(w), e = v.dot(w);
    const double s = (b * e - c * d) / denom;
    const double t = (a * e - b * d) / denom;
    if (s > 0.0 && s < 1.0 && t > 0.0 && t < 1.0) best = std::min(best, (p0 + s * u - (q0 + t * v)).norm());
  }
  return best;
}

// Closest distance from point p to the triangle (a, b, c). If the projection of p on the
// triangle's plane falls inside the triangle (p is on the inner side of all three edges, judged by
// the signs of n . (edge x (p - edge start)) with n the triangle's normal), the distance is the
// distance to the plane; otherwise it is the distance to the nearest edge. Both candidates are
// distances to points of the triangle, so the minimum of the ones that apply is exact. A degenerate
// (or sliver, thinner than 1e-12 of its longest edge) triangle is the union of its edges.
inline double pointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c)
{
  const double edges =
      std::min(std::min(pointSegmentDistance(p, a, b), pointSegmentDistance(p, b, c)), pointSegmentDistance(p, c, a));
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double longest2 = std::max(std::max((b - a).squaredNorm(), (c - b).squaredNorm()), (a - c).squaredNorm());
  if (n.norm() <= kContactRelativeTolerance * longest2) return edges;
  const bool inside =
      n.dot((b - a).cross(p - a)) >= 0.0 && n.dot((c - b).cross(p - b)) >= 0.0 && n.dot((a - c).cross(p - c)) >= 0.0;
  if (!inside) return edges;
  return std::min(edges, std::abs(n.dot(p - a)) / n.norm());
}

// Exact closest distance between two solid triangles (0 when they touch or cross). When they are
// disjoint, the distance is attained either between two edges (9 segment pairs) or between a
// vertex and the other triangle (6 vertex-face pairs). When they intersect, some edge of one meets
// the other triangle: either it crosses the other's plane strictly (signed distances of its
// endpoints to the plane, i.e. the orientation predicate divided by the normal's length, have
// opposite signs), and then its crossing point lies in the other triangle, or an endpoint lies in
// the plane (a vertex-face pair at distance 0), or the edge lies in the plane (coplanar case: an
// endpoint inside the other triangle, or a crossing with one of its edges, both caught above). So
// the minimum over those 15 candidates and the (at most 6) crossing points' distances to the other
// triangle is 0 exactly when the triangles intersect and the true distance otherwise; every
// candidate is the distance between two points of the triangles, so none can undercut the truth
// beyond round-off. Coplanar triangles need no separate 2-D test: their overlap is an edge-edge
// crossing or a vertex inside the other triangle.
inline double triangleDistance(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& a2,
                               const Eigen::Vector3d& b0, const Eigen::Vector3d& b1, const Eigen::Vector3d& b2)
{
  const Eigen::Vector3d* a[3] = {&a0, &a1, &a2};
  const Eigen::Vector3d* b[3] = {&b0, &b1, &b2};
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i)
  {
    for (int j = 0; j < 3; ++j)
    {
      best = std::min(best, segmentDistance(*a[i], *a[(i + 1) % 3], *b[j], *b[(j + 1) % 3]));
    }
    best = std::min(best, pointTriangleDistance(*a[i], b0, b1, b2));
    best = std::min(best, pointTriangleDistance(*b[i], a0, a1, a2));
  }
  // Edges of `edges` crossing the plane of `face` strictly: the crossing point's distance to `face`.
  const auto crossings = [&best](const Eigen::Vector3d* const* edges, const Eigen::Vector3d* const* face) {
    const Eigen::Vector3d n = (*face[1] - *face[0]).cross(*face[2] - *face[0]);
    const double norm = n.norm();
    if (!(norm > 0.0)) return;  // a degenerate face is its edges, already measured
    const Eigen::Vector3d unit = n / norm;
    for (int i = 0; i < 3; ++i)
    {
      const Eigen::Vector3d& p = *edges[i];
      const Eigen::Vector3d& q = *edges[(i + 1) % 3];
      const double dp = unit.dot(p - *face[0]);
      const double dq = unit.dot(q - *face[0]);
      if (!((dp > 0.0 && dq < 0.0) || (dp < 0.0 && dq > 0.0))) continue;
      const Eigen::Vector3d x = p + (dp / (dp - dq)) * (q - p);
      best = std::min(best, pointTriangleDistance(x, *face[0], *face[1], *face[2]));
    }
  };
  crossings(a, b);
  crossings(b, a);
  return best;
}

// The scale that kContactRelativeTolerance is relative to: the largest edge length or coordinate
// magnitude of a triangle (the largest of both for a pair).
inline double triangleScale(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2)
{
  const double edge = std::max(std::max((p1 - p0).norm(), (p2 - p1).norm()), (p0 - p2).norm());
  const double coordinate =
      std::max(std::max(p0.cwiseAbs().maxCoeff(), p1.cwiseAbs().maxCoeff()), p2.cwiseAbs().maxCoeff());
  return std::max(edge, coordinate);
}

// Triangle-triangle intersection: the exact triangle distance above (orientation signs for the
// crossings, closest-point distances for everything else) compared with 1e-12 of the pair's scale.
// A real crossing has distance 0 (up to round-off); touching counts only within that tolerance
// (see the contact convention at the top of this file).
inline bool trianglesIntersect(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& a2,
                               const Eigen::Vector3d& b0, const Eigen::Vector3d& b1, const Eigen::Vector3d& b2)
{
  const double scale = std::max(triangleScale(a0, a1, a2), triangleScale(b0, b1, b2));
  return triangleDistance(a0, a1, a2, b0, b1, b2) <= kContactRelativeTolerance * scale;
}

namespace intersection_detail
{
// Per-triangle axis-aligned bounding box and scale, for the rejection test of the pair loops.
struct TriangleBox
{
  Eigen::Vector3d lo;
  Eigen::Vector3d hi;
  double scale;
};

inline std::vector<TriangleBox> triangleBoxes(const Eigen::Matrix3Xd& x, const std::vector<Eigen::Vector3i>& triangles)
{
  std::vector<TriangleBox> boxes;
  boxes.reserve(triangles.size());
  for (const Eigen::Vector3i& t : triangles)
  {
    for (int k = 0; k < 3; ++k)
    {
      if (t[k] < 0 || t[k] >= x.cols())
      {
        throw std::out_of_range("intersection_check: triangle vertex " + std::to_string(t[k]) + " outside 0.." +
                                std::to_string(x.cols() - 1));
      }
    }
    const Eigen::Vector3d p0 = x.col(t[0]), p1 = x.col(t[1]), p2 = x.col(t[2]);
    boxes.push_back({p0.cwiseMin(p1).cwiseMin(p2), p0.cwiseMax(p1).cwiseMax(p2), triangleScale(p0, p1, p2)});
  }
  return boxes;
}

// True when the boxes are farther apart along some axis than the pair's contact tolerance, so that
// trianglesIntersect() would answer false anyway.
inline bool separated(const TriangleBox& a, const TriangleBox& b)
{
  const double tolerance = kContactRelativeTolerance * std::max(a.scale, b.scale);
  return ((a.lo - b.hi).array() > tolerance).any() || ((b.lo - a.hi).array() > tolerance).any();
}

inline bool shareVertex(const Eigen::Vector3i& s, const Eigen::Vector3i& t)
{
  for (int i = 0; i < 3; ++i)
  {
    for (int j = 0; j < 3; ++j)
    {
      if (s[i] == t[j]) return true;
    }
  }
  return false;
}
}  // namespace intersection_detail

// Self-intersections of one triangle mesh with positions x (one particle per column): every pair of
// triangles that share no vertex (index), O(n^2) with an AABB rejection, tested with
// trianglesIntersect(). Returns the intersecting pairs (i < j) for diagnostics. Triangles that
// share a vertex index touch by construction and are not tested; distinct vertices at the same
// position (e.g. the two copies of a just-torn vertex) are not exempt: their triangles touch.
inline std::vector<std::pair<int, int>> surfaceIntersectionPairs(const Eigen::Matrix3Xd& x,
                                                                 const std::vector<Eigen::Vector3i>& triangles)
{
  const std::vector<intersection_detail::TriangleBox> boxes = intersection_detail::triangleBoxes(x, triangles);
  std::vector<std::pair<int, int>> pairs;
  const int n = static_cast<int>(triangles.size());
  for (int i = 0; i < n; ++i)
  {
    const Eigen::Vector3i& s = triangles[i];
    for (int j = i + 1; j < n; ++j)
    {
      const Eigen::Vector3i& t = triangles[j];
      if (intersection_detail::separated(boxes[i], boxes[j]) || intersection_detail::shareVertex(s, t)) continue;
      if (trianglesIntersect(x.col(s[0]), x.col(s[1]), x.col(s[2]), x.col(t[0]), x.col(t[1]), x.col(t[2])))
      {
        pairs.emplace_back(i, j);
      }
    }
  }
  return pairs;
}

// The number of intersecting pairs of surfaceIntersectionPairs().
inline int countSurfaceIntersections(const Eigen::Matrix3Xd& x, const std::vector<Eigen::Vector3i>& triangles)
{
  return static_cast<int>(surfaceIntersectionPairs(x, triangles).size());
}

// Intersections between two different meshes (positions xa with triangles ta, xb with tb): every
// pair (one triangle of each), O(na nb) with an AABB rejection; returns the number of intersecting
// pairs.
inline int countIntersectionsBetween(const Eigen::Matrix3Xd& xa, const std::vector<Eigen::Vector3i>& ta,
                                     const Eigen::Matrix3Xd& xb, const std::vector<Eigen::Vector3i>& tb)
{
  const std::vector<intersection_detail::TriangleBox> boxes_a = intersection_detail::triangleBoxes(xa, ta);
  const std::vector<intersection_detail::TriangleBox> boxes_b = intersection_detail::triangleBoxes(xb, tb);
  int count = 0;
  for (std::size_t i = 0; i < ta.size(); ++i)
  {
    const Eigen::Vector3i& s = ta[i];
    for (std::size_t j = 0; j < tb.size(); ++j)
    {
      if (intersection_detail::separated(boxes_a[i], boxes_b[j])) continue;
      const Eigen::Vector3i& t = tb[j];
      if (trianglesIntersect(xa.col(s[0]), xa.col(s[1]), xa.col(s[2]), xb.col(t[0]), xb.col(t[1]), xb.col(t[2])))
      {
        ++count;
      }
    }
  }
  return count;
}

// A rope: particles first .. first + count - 1 (columns of x) joined in order by count - 1
// segments. Counts the pairs of segments i, j with j - i >= 2 (adjacent segments share a particle)
// whose exact distance (segmentDistance) is below min_distance; O(count^2), no broad phase. With
// min_distance = 0 nothing can count, so pass a small positive distance (e.g. the rope's contact
// thickness, or 1e-12 of its size) to count crossings.
inline int countChainCrossings(const Eigen::Matrix3Xd& x, int first, int count, double min_distance)
{
  if (first < 0 || count < 0 || first + count > x.cols())
  {
    throw std::out_of_range("intersection_check: chain " + std::to_string(first) + " + " + std::to_string(count) +
                            " outside 0.." + std::to_string(x.cols()));
  }
  int crossings = 0;
  const int segments = count - 1;
  for (int i = 0; i < segments; ++i)
  {
    for (int j = i + 2; j < segments; ++j)
    {
      const double d = segmentDistance(x.col(first + i), x.col(first + i + 1), x.col(first + j), x.col(first + j + 1));
      if (d < min_distance) ++crossings;
    }
  }
  return crossings;
}
}  // namespace particle_sim_test
