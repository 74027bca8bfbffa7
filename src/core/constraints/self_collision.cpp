#include "particle_sim/core/constraints/self_collision.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "particle_sim/core/spring_network.h"

namespace particle_sim
{
namespace core
{
namespace
{
// Items of the broad phase: kind in the top two bits of the item code.
constexpr std::uint32_t kPoint = 0;
constexpr std::uint32_t kEdge = 1;
constexpr std::uint32_t kTriangle = 2;
constexpr int kKindShift = 30;
constexpr std::uint32_t kIndexMask = (1u << kKindShift) - 1;

// Gauss–Seidel passes of continuous detection with impulses before the fail-safe takes over.
constexpr int kImpulsePasses = 8;
// Rounds of the fail-safe (merge the colliding particles into zones, move the zones rigidly).
constexpr int kZoneRounds = 64;
// Proximity: the repulsion separates a pair by this share of its missing distance over a step.
constexpr double kRepulsionShare = 0.1;
// Continuous detection: a pair coplanar within this share of its thickness touches; the impulse
// leaves it separating by this share of its thickness over the step.
constexpr double kTouchShare = 1e-3;
constexpr double kSeparationShare = 0.1;
// An item whose box spans more grid cells than this (a particle flung far in one step) is tested
// against every other item instead of being put in every cell.
constexpr double kMaxCellsPerItem = 512.0;
// The candidates' boxes are grown by a margin (candidate_margin_, a share of the mean edge), so that
// they serve the next steps while no particle moves further than that against the frame. A margin
// that served no later step is left off for this many searches (scenes whose particles move against
// each other every step would pay for its extra pairs for nothing), then tried again.
constexpr int kSearchesWithoutMargin = 16;

// Closest point to p on triangle (a, b, c) as barycentric weights w (Ericson, Real-Time Collision
// Detection, 5.1.5: the Voronoi region of p among the corners, edges and face).
Eigen::Vector3d closestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                  const Eigen::Vector3d& c)
{
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return {1.0, 0.0, 0.0};
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return {0.0, 1.0, 0.0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0)
  {
    const double v = d1 / (d1 - d3);
    return {1.0 - v, v, 0.0};
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return {0.0, 0.0, 1.0};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0)
  {
    const double w = d2 / (d2 - d6);
    return {1.0 - w, 0.0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
  {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0.0, 1.0 - w, w};
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return {1.0 - v - w, v, w};
}

// Parameters (s, t) in [0, 1]² of the closest points p0 + s (p1 − p0) and q0 + t (q1 − q0) of two
// segments (Ericson 5.1.9: the unconstrained minimum clamped to the square, edge by edge).
Eigen::Vector2d closestOnSegments(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& q0,
                                  const Eigen::Vector3d& q1)
{
  const Eigen::Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  constexpr double kTiny = 1e-30;
  if (a <= kTiny && e <= kTiny) return {0.0, 0.0};
  if (a <= kTiny) return {0.0, std::clamp(f / e, 0.0, 1.0)};
  const double c = d1.dot(r);
  if (e <= kTiny) return {std::clamp(-c / a, 0.0, 1.0), 0.0};
  const double b = d1.dot(d2), denom = a * e - b * b;
  double s = denom > kTiny * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
  double t = (b * s + f) / e;
  if (t < 0.0)
  {
    t = 0.0;
    s = std::clamp(-c / a, 0.0, 1.0);
  }
  else if (t > 1.0)
  {
    t = 1.0;
    s = std::clamp((b - c) / a, 0.0, 1.0);
  }
  return {s, t};
}

// The roots in [0, 1] of c3 t³ + c2 t² + c1 t + c0, in increasing order, in `roots` (at most 3):
// the cubic is monotone between the roots of its derivative, and each monotone piece whose ends
// differ in sign is bisected.
int unitRoots(double c3, double c2, double c1, double c0, double roots[3])
{
  const auto f = [&](double t) { return ((c3 * t + c2) * t + c1) * t + c0; };
  double ends[4];
  int n_ends = 0;
  ends[n_ends++] = 0.0;
  // f'(t) = 3 c3 t² + 2 c2 t + c1.
  const double qa = 3.0 * c3, qb = 2.0 * c2, qc = c1;
  double critical[2];
  int n_critical = 0;
  if (qa != 0.0)
  {
    const double disc = qb * qb - 4.0 * qa * qc;
    if (disc >= 0.0)
    {
      const double sq = std::sqrt(disc);
      critical[n_critical++] = (-qb - sq) / (2.0 * qa);
      critical[n_critical++] = (-qb + sq) / (2.0 * qa);
      if (critical[0] > critical[1]) std::swap(critical[0], critical[1]);
    }
  }
  else if (qb != 0.0)
  {
    critical[n_critical++] = -qc / qb;
  }
  for (int k = 0; k < n_critical; ++k)
  {
    if (critical[k] > 0.0 && critical[k] < 1.0) ends[n_ends++] = critical[k];
  }
  ends[n_ends++] = 1.0;
  int n_roots = 0;
  for (int k = 0; k + 1 < n_ends; ++k)
  {
    double lo = ends[k], hi = ends[k + 1];
    double f_lo = f(lo);
    const double f_hi = f(hi);
    if (f_lo == 0.0)
    {
      if (n_roots == 0 || roots[n_roots - 1] != lo) roots[n_roots++] = lo;
      continue;
    }
    if ((f_lo < 0.0) == (f_hi < 0.0) || f_hi == 0.0) continue;  // no crossing inside (a root at hi comes next)
    for (int it = 0; it < 44; ++it)                             // t to 1e-13
    {
      const double mid = 0.5 * (lo + hi);
      const double f_mid = f(mid);
      if ((f_mid < 0.0) == (f_lo < 0.0))
      {
        lo = mid;
        f_lo = f_mid;
      }
      else
      {
        hi = mid;
      }
    }
    roots[n_roots++] = hi;
  }
  if (f(1.0) == 0.0 && (n_roots == 0 || roots[n_roots - 1] != 1.0) && n_roots < 3) roots[n_roots++] = 1.0;
  return n_roots;
}

// The coefficients of the triple product (u + t du) × (w + t dw) · (s + t ds) as a cubic in t.
void tripleProductCubic(const Eigen::Vector3d& u, const Eigen::Vector3d& du, const Eigen::Vector3d& w,
                        const Eigen::Vector3d& dw, const Eigen::Vector3d& s, const Eigen::Vector3d& ds, double c[4])
{
  const Eigen::Vector3d uw = u.cross(w);
  const Eigen::Vector3d mixed = du.cross(w) + u.cross(dw);
  const Eigen::Vector3d dudw = du.cross(dw);
  c[0] = uw.dot(s);
  c[1] = mixed.dot(s) + uw.dot(ds);
  c[2] = dudw.dot(s) + mixed.dot(ds);
  c[3] = dudw.dot(ds);
}

// A key of grid cell (ix, iy, iz), each wrapped to 21 bits (cells 2^21 apart share a key: more
// candidates, which the boxes then reject), and its hash bucket among `buckets` (a power of 2).
std::uint64_t cellKey(int ix, int iy, int iz)
{
  const auto wrap = [](int i) { return static_cast<std::uint64_t>(static_cast<std::uint32_t>(i)) & ((1u << 21) - 1); };
  return (wrap(ix) << 42) | (wrap(iy) << 21) | wrap(iz);
}

std::size_t bucketOf(std::uint64_t key, std::size_t buckets)
{
  key ^= key >> 33;
  key *= 0xff51afd7ed558ccdULL;
  key ^= key >> 33;
  return static_cast<std::size_t>(key) & (buckets - 1);
}
}  // namespace

bool SelfCollisionSolver::pathsInsideBoxes(double h, bool step_start) const
{
  // The boxes are in the frame, whose origin is at frame_origin_ at the step's start and moves by
  // h · frame_velocity_ over the step. At a step's start, the candidates found at an earlier step
  // still hold while every particle's path lies inside the box recorded for it (they were grown by
  // a margin for that): then every pair whose boxes overlap now overlapped then, and the list holds
  // it. Within the step (after impulses), the path's end may leave its box by half the largest
  // thickness: pairs whose grown boxes did not overlap then cannot meet now (they may come within a
  // thickness, which only the proximity pass at the step's start, on covering candidates, looks at).
  const double slack = step_start ? 0.0 : 0.5 * max_thickness_;
  const auto inside = [&](const Eigen::Vector3d& y, Eigen::Index i) {
    return (y.array() >= path_lo_.col(i).array() - slack).all() && (y.array() <= path_hi_.col(i).array() + slack).all();
  };
  for (Eigen::Index i = 0; i < x0_.cols(); ++i)
  {
    const Eigen::Vector3d start = x0_.col(i) - frame_origin_;
    const Eigen::Vector3d end = start + h * (vbar_.col(i) - frame_velocity_);
    if ((step_start && !inside(start, i)) || !inside(end, i)) return false;
  }
  return true;
}

double SelfCollisionSolver::pairThickness(int particle_a, int particle_b) const
{
  return 0.5 * (thickness_[particle_a] + thickness_[particle_b]);
}

void SelfCollisionSolver::resolve(double h, const std::vector<SpringNetworkBody*>& bodies,
                                  const std::vector<int>& report_index, CollisionReport& report)
{
  report.passes = 0;
  report.searches = 0;
  report.impact_zones = 0;
  report.total = CollisionCounts{};
  std::fill(report.bodies.begin(), report.bodies.end(), CollisionCounts{});
  if (bodies.empty()) return;
  gather(h, bodies);
  if (triangles_.empty() && edges_.empty()) return;
  body_counts_.assign(bodies.size(), CollisionCounts{});

  // 1. Pairs closer than their thickness at the step's start are pushed apart. The candidates of
  // an earlier step serve while they cover every path (a cloth that falls or lies still keeps
  // them); otherwise they are found again.
  chooseFrame();
  if (candidates_valid_ && pathsInsideBoxes(h, true))
  {
    candidates_reused_ = true;
    new_candidates_ = true;  // new to this step: its first pass tests them all
    findPairStarts(h);
  }
  else
  {
    if (candidates_margined_ && !candidates_reused_)
      searches_without_margin_ = kSearchesWithoutMargin;
    else if (searches_without_margin_ > 0)
      --searches_without_margin_;
    findCandidates(h, report);
  }
  repelProximities(h, report);
  // 2. Pairs that cross during the step are stopped, pass after pass.
  bool clear = false;
  for (int pass = 0; pass < kImpulsePasses && !clear; ++pass)
  {
    if (!pathsInsideBoxes(h, false)) refindCandidates(h, report);  // the repulsion or the last pass moved paths out
    ++report.passes;
    clear = detectCollisions(h, true, false, report) == 0;
  }
  // 3. What still collides moves in rigid impact zones.
  if (!clear) mergeImpactZones(h, report);
  scatter(h, bodies);
  frame_origin_ += h * frame_velocity_;
  for (std::size_t b = 0; b < bodies.size(); ++b)
    report.bodies[report_index[b]] = body_counts_[b];
}

void SelfCollisionSolver::gather(double h, const std::vector<SpringNetworkBody*>& bodies)
{
  // Topology (particles, edges, triangles) is rebuilt when the bodies or their surfaces changed.
  bool same_topology = bodies.size() == topology_bodies_.size();
  for (std::size_t b = 0; b < bodies.size() && same_topology; ++b)
  {
    same_topology = bodies[b] == topology_bodies_[b].body &&
                    bodies[b]->particles().size() == topology_bodies_[b].particles &&
                    bodies[b]->tornSprings() + bodies[b]->tornTriangles() == topology_bodies_[b].torn;
  }
  if (!same_topology || topology_stale_) buildTopology(bodies);
  topology_stale_ = false;

  // Start positions and average velocities of the step, in one numbering.
  for (std::size_t b = 0; b < bodies.size(); ++b)
  {
    const ParticlePool& p = bodies[b]->particles();
    const Eigen::Matrix3Xd& start = bodies[b]->stepStartPositions();
    const int first = body_first_[b];
    for (int i = 0; i < p.size(); ++i)
    {
      x0_.col(first + i) = start.col(i);
      vbar_.col(first + i) = (p.position.col(i) - start.col(i)) / h;
      inverse_mass_[first + i] = p.inverse_mass[i];
      v_end_.col(first + i) = p.velocity.col(i);
      changed_[first + i] = 0;
    }
  }
}

void SelfCollisionSolver::buildTopology(const std::vector<SpringNetworkBody*>& bodies)
{
  topology_bodies_.clear();
  body_first_.clear();
  int n = 0;
  for (SpringNetworkBody* body : bodies)
  {
    body_first_.push_back(n);
    topology_bodies_.push_back({body, body->particles().size(), body->tornSprings() + body->tornTriangles()});
    n += body->particles().size();
  }
  x0_.resize(3, n);
  vbar_.resize(3, n);
  v_end_.resize(3, n);
  inverse_mass_.assign(n, 0.0);
  thickness_.assign(n, 0.0);
  body_of_.assign(n, 0);
  origin_.assign(n, 0);
  is_point_.assign(n, 0);
  zone_.assign(n, -1);
  moved_.assign(n, 0);
  moving_.assign(n, 0);
  changed_.assign(n, 0);
  zone_sums_.resize(n);
  candidates_valid_ = false;
  searches_without_margin_ = 0;
  frame_origin_.setZero();
  triangles_.clear();
  edges_.clear();
  max_thickness_ = 0.0;
  double edge_length_sum = 0.0;
  for (std::size_t b = 0; b < bodies.size(); ++b)
  {
    const SpringNetworkBody& body = *bodies[b];
    const int first = body_first_[b];
    const double thickness = body.definition().self_collision.thickness;
    max_thickness_ = std::max(max_thickness_, thickness);
    for (int i = 0; i < body.particles().size(); ++i)
    {
      thickness_[first + i] = thickness;
      body_of_[first + i] = static_cast<int>(b);
      origin_[first + i] = first + body.particleOrigin(i);
    }
    // Cloth and jelly collide by their surface triangles and those triangles' edges; ropes and
    // networks without triangles by their stretch springs (chains of capsules).
    const std::size_t edges_before = edges_.size();
    for (const Eigen::Vector3i& t : body.surfaceTriangles())
    {
      triangles_.emplace_back(first + t[0], first + t[1], first + t[2]);
      for (int k = 0; k < 3; ++k)
      {
        const int a = first + t[k], c = first + t[(k + 1) % 3];
        edges_.emplace_back(std::min(a, c), std::max(a, c));
      }
    }
    if (body.surfaceTriangles().empty())
    {
      for (const Spring& s : body.springs())
      {
        if (s.spring_class == SpringClass::Stretch && s.i != s.j)
          edges_.emplace_back(first + std::min(s.i, s.j), first + std::max(s.i, s.j));
      }
    }
    std::sort(
        edges_.begin() + static_cast<std::ptrdiff_t>(edges_before), edges_.end(),
        [](const Eigen::Vector2i& l, const Eigen::Vector2i& r) { return l[0] != r[0] ? l[0] < r[0] : l[1] < r[1]; });
    edges_.erase(std::unique(edges_.begin() + static_cast<std::ptrdiff_t>(edges_before), edges_.end()), edges_.end());
    for (std::size_t e = edges_before; e < edges_.size(); ++e)
    {
      is_point_[edges_[e][0]] = 1;
      is_point_[edges_[e][1]] = 1;
      edge_length_sum +=
          (body.stepStartPositions().col(edges_[e][1] - first) - body.stepStartPositions().col(edges_[e][0] - first))
              .norm();
    }
  }
  // The surfaces' length scale: their mean edge (the grid's smallest cell).
  const double mean_edge = edges_.empty() ? max_thickness_ : edge_length_sum / static_cast<double>(edges_.size());
  length_scale_ = std::max({mean_edge, max_thickness_, 1e-6});

  // Room for the broad phase, so that the steps allocate nothing: an item's box spans up to 2 cells
  // along each axis at rest, more when it moves fast; pairs are a few per item.
  const std::size_t items = static_cast<std::size_t>(n) + edges_.size() + triangles_.size();
  codes_.reserve(items);
  box_lo_.resize(3, static_cast<Eigen::Index>(items));
  path_lo_.resize(3, n);
  path_hi_.resize(3, n);
  box_hi_.resize(3, static_cast<Eigen::Index>(items));
  buckets_ = 1;
  while (buckets_ < 4 * items)
    buckets_ <<= 1;
  bucket_start_.assign(2 * buckets_ + 1, 0);  // the edges' table, then the triangles'
  bucket_fill_.assign(2 * buckets_, 0);
  entries_.reserve(16 * items);
  pairs_.reserve(16 * items);
  pair_start_.reserve(16 * items);
  median_scratch_.resize(n);
  big_.reserve(64);
  big_flag_.reserve(items);
  seen_.reserve(items);
}

void SelfCollisionSolver::chooseFrame()
{
  // The paths are boxed in a frame moving with the particles' median velocity (per axis): two
  // items meet in it exactly when they meet in the world, and a cloth that falls or is carried as
  // a whole no longer sweeps every item through its neighbours' boxes, while a cloth most of which
  // lies still (a corner lifted) keeps the world's frame.
  const int n = static_cast<int>(x0_.cols());
  frame_velocity_.setZero();
  if (n == 0 || !vbar_.allFinite()) return;
  for (int axis = 0; axis < 3; ++axis)
  {
    for (int i = 0; i < n; ++i)
      median_scratch_[i] = vbar_(axis, i);
    std::nth_element(median_scratch_.begin(), median_scratch_.begin() + n / 2, median_scratch_.begin() + n);
    frame_velocity_[axis] = median_scratch_[n / 2];
  }
}

void SelfCollisionSolver::refindCandidates(double h, CollisionReport& report)
{
  chooseFrame();
  findCandidates(h, report);
}

void SelfCollisionSolver::findCandidates(double h, CollisionReport& report)
{
  ++report.searches;
  // Each item's box: swept from x0 to x1 = x0 + h v̄ (relative to the frame), grown by half the
  // largest thickness, so that two boxes overlap whenever their items come within a thickness of
  // each other during the step; and by a margin, so that the candidates serve the next steps too,
  // while the particles stay within it.
  const double grow = 0.5 * max_thickness_;
  const double margin = searches_without_margin_ > 0 ? 0.0 : candidate_margin_ * length_scale_;
  const int n = static_cast<int>(x0_.cols());
  double travel = 0.0;  // [m] summed over the particles, in the frame
  for (int i = 0; i < n; ++i)
  {
    const Eigen::Vector3d a = x0_.col(i) - frame_origin_, b = a + h * (vbar_.col(i) - frame_velocity_);
    path_lo_.col(i) = a.cwiseMin(b).array() - margin;
    path_hi_.col(i) = a.cwiseMax(b).array() + margin;
    travel += (b - a).norm();
  }
  candidates_valid_ = true;
  candidates_margined_ = margin > 0.0;
  candidates_reused_ = false;
  // Grid cells about one edge long, longer when the particles travel further in the step: each
  // item spans a few cells and each cell holds a few items (a cloth falling a cell a step would
  // otherwise put every item in a column of cells). The cells change only how the pairs are found,
  // not their order: each item's pairs are sorted by the other item (but for items too large for
  // the grid, tested against all after the others).
  cell_size_ = std::max(length_scale_, travel / n);
  const auto itemBox = [&](std::uint32_t code, Eigen::Vector3d& lo, Eigen::Vector3d& hi) {
    const std::uint32_t kind = code >> kKindShift, index = code & kIndexMask;
    const int* ids = kind == kPoint ? nullptr : kind == kEdge ? edges_[index].data() : triangles_[index].data();
    const int count = kind == kPoint ? 1 : kind == kEdge ? 2 : 3;
    lo = path_lo_.col(ids ? ids[0] : static_cast<int>(index));
    hi = path_hi_.col(ids ? ids[0] : static_cast<int>(index));
    for (int k = 1; k < count; ++k)
    {
      lo = lo.cwiseMin(path_lo_.col(ids[k]));
      hi = hi.cwiseMax(path_hi_.col(ids[k]));
    }
    lo.array() -= grow;
    hi.array() += grow;
  };
  const auto cellRange = [&](std::size_t k, Eigen::Array3i& lo, Eigen::Array3i& hi) {
    const Eigen::Index col = static_cast<Eigen::Index>(k);
    const Eigen::Array3d l = (box_lo_.col(col) / cell_size_).array().floor();
    const Eigen::Array3d u = (box_hi_.col(col) / cell_size_).array().floor();
    // NaN, far away (past the int range) or spanning too many cells: big.
    if (!((u - l + 1.0).prod() <= kMaxCellsPerItem) || !(l.abs().maxCoeff() < 1e9) || !(u.abs().maxCoeff() < 1e9))
      return false;
    lo = l.cast<int>();
    hi = u.cast<int>();
    return true;
  };

  // Boxes of every item (codes_: points, then edges, then triangles); the edges and triangles go
  // into the grid, unless their box spans too many cells ("big": tested against every item).
  new_candidates_ = true;
  codes_.clear();
  for (int i = 0; i < n; ++i)
    if (is_point_[i]) codes_.push_back((kPoint << kKindShift) | static_cast<std::uint32_t>(i));
  const std::size_t first_edge = codes_.size();
  for (std::size_t e = 0; e < edges_.size(); ++e)
    codes_.push_back((kEdge << kKindShift) | static_cast<std::uint32_t>(e));
  const std::size_t first_triangle = codes_.size();
  for (std::size_t t = 0; t < triangles_.size(); ++t)
    codes_.push_back((kTriangle << kKindShift) | static_cast<std::uint32_t>(t));
  std::size_t entries = 0;
  big_.clear();
  for (std::size_t k = 0; k < codes_.size(); ++k)
  {
    Eigen::Vector3d lo, hi;
    itemBox(codes_[k], lo, hi);
    box_lo_.col(static_cast<Eigen::Index>(k)) = lo;
    box_hi_.col(static_cast<Eigen::Index>(k)) = hi;
    Eigen::Array3i cl, ch;
    if (!cellRange(k, cl, ch))
      big_.push_back(static_cast<std::uint32_t>(k));
    else if (k >= first_edge)
      entries += static_cast<std::size_t>((ch - cl + 1).prod());
  }
  big_flag_.assign(codes_.size(), 0);
  for (std::uint32_t k : big_)
    big_flag_[k] = 1;

  // Counting sort of the (cell, item) entries of the edges and triangles by the hash bucket of the
  // cell, in two tables (edges, then triangles: a point looks only for triangles, an edge only for
  // edges): within a bucket in codes_ order, so the pairs come in a fixed order.
  const std::size_t buckets = buckets_;
  const auto tableBucket = [&](std::uint64_t key, bool triangles) {
    return bucketOf(key, buckets) + (triangles ? buckets : 0);
  };
  std::fill(bucket_start_.begin(), bucket_start_.end(), 0);
  entries_.resize(entries);
  const auto forEachCell = [&](std::size_t k, auto&& visit) {
    Eigen::Array3i lo, hi;
    cellRange(k, lo, hi);
    for (int ix = lo[0]; ix <= hi[0]; ++ix)
      for (int iy = lo[1]; iy <= hi[1]; ++iy)
        for (int iz = lo[2]; iz <= hi[2]; ++iz)
          visit(cellKey(ix, iy, iz));
  };
  for (std::size_t k = first_edge; k < codes_.size(); ++k)
    if (!big_flag_[k])
      forEachCell(k, [&](std::uint64_t key) { ++bucket_start_[tableBucket(key, k >= first_triangle) + 1]; });
  for (std::size_t b = 0; b < 2 * buckets; ++b)
    bucket_start_[b + 1] += bucket_start_[b];
  std::copy(bucket_start_.begin(), bucket_start_.end() - 1, bucket_fill_.begin());
  for (std::size_t k = first_edge; k < codes_.size(); ++k)
    if (!big_flag_[k])
      forEachCell(k, [&](std::uint64_t key) {
        entries_[bucket_fill_[tableBucket(key, k >= first_triangle)]++] = Item{key, static_cast<std::uint32_t>(k)};
      });

  // Pairs: a point and a triangle, or two edges, whose boxes overlap and that share no particle (a
  // tear's copy counts as the particle it was split from: the two sides of a split vertex touch).
  // Each point (each edge) looks in the cells of its box; a stamp per item keeps a pair found in
  // several cells once.
  pairs_.clear();
  seen_.assign(codes_.size(), -1);
  const auto overlap = [&](std::size_t ka, std::size_t kb) {
    const Eigen::Index a = static_cast<Eigen::Index>(ka), b = static_cast<Eigen::Index>(kb);
    return !((box_lo_.col(a).array() > box_hi_.col(b).array()).any() ||
             (box_lo_.col(b).array() > box_hi_.col(a).array()).any());
  };
  const auto consider = [&](std::size_t ki, std::size_t kj) {  // ki < kj in codes_ order
    const std::uint32_t a = codes_[ki] & kIndexMask, c = codes_[kj] & kIndexMask;
    if (ki < first_edge)
    {
      if (kj < first_triangle) return;  // a point pairs with triangles only
      const Eigen::Vector3i& t = triangles_[c];
      const int o = origin_[a];
      if (origin_[t[0]] == o || origin_[t[1]] == o || origin_[t[2]] == o) return;
    }
    else
    {
      if (kj >= first_triangle) return;  // an edge pairs with edges only
      const Eigen::Vector2i &e = edges_[a], &f = edges_[c];
      const int e0 = origin_[e[0]], e1 = origin_[e[1]], f0 = origin_[f[0]], f1 = origin_[f[1]];
      if (e0 == f0 || e0 == f1 || e1 == f0 || e1 == f1) return;
    }
    if (!overlap(ki, kj)) return;
    pairs_.push_back(Pair{a, c, ki < first_edge ? 0u : 1u});
  };
  for (std::size_t k = 0; k < first_triangle; ++k)
  {
    if (big_flag_[k]) continue;
    const auto stamp = static_cast<long long>(k);
    const std::size_t first_pair = pairs_.size();
    forEachCell(k, [&](std::uint64_t key) {
      const std::size_t b = tableBucket(key, k < first_edge);  // a point looks for triangles
      for (std::size_t e = bucket_start_[b]; e < bucket_start_[b + 1]; ++e)
      {
        const std::size_t other = entries_[e].item;
        if (other <= k || entries_[e].cell != key || seen_[other] == stamp) continue;
        seen_[other] = stamp;
        consider(k, other);
      }
    });
    std::sort(pairs_.begin() + static_cast<std::ptrdiff_t>(first_pair), pairs_.end(),
              [](const Pair& l, const Pair& r) { return l.b < r.b; });
  }
  // Big items against every item (each pair once, from the big item of the two that comes first).
  for (std::uint32_t kb : big_)
  {
    for (std::size_t k = 0; k < codes_.size(); ++k)
    {
      if (k == kb || (big_flag_[k] && k < kb)) continue;
      if (k < kb)
        consider(k, kb);
      else
        consider(kb, k);
    }
  }

  findPairStarts(h);
}

void SelfCollisionSolver::findPairStarts(double h)
{
  // Each pair's stencil at the step's start: x0 does not change during the pass, so it serves the
  // repulsion, the touching bound and the touching-end check of every pass.
  pair_start_.resize(pairs_.size());
  for (std::size_t k = 0; k < pairs_.size(); ++k)
  {
    PairStart& start = pair_start_[k];
    start.valid = stencil(pairs_[k], 0.0, h, start.stencil, start.normal, start.distance);
  }
}

bool SelfCollisionSolver::contactNormal(const Eigen::Vector3d& d, double distance, const Eigen::Vector3d& plane,
                                        Eigen::Vector3d& normal) const
{
  // Along the distance vector; where the items touch, the plane's normal (the face's, or the two
  // edges' cross product); false when that too vanishes.
  if (distance > 1e-12 * length_scale_)
    normal = d / distance;
  else if (plane.norm() > 0.0)
    normal = plane.normalized();
  else
    return false;
  return true;
}

bool SelfCollisionSolver::stencil(const Pair& pair, double t, double h, Stencil& s, Eigen::Vector3d& normal,
                                  double& distance) const
{
  // Positions at time t·h of the step.
  const auto at = [&](int i) -> Eigen::Vector3d { return x0_.col(i) + t * h * vbar_.col(i); };
  if (pair.kind == 0)
  {
    const Eigen::Vector3i& tri = triangles_[pair.b];
    const Eigen::Vector3d p = at(static_cast<int>(pair.a)), a = at(tri[0]), b = at(tri[1]), c = at(tri[2]);
    const Eigen::Vector3d w = closestOnTriangle(p, a, b, c);
    const Eigen::Vector3d q = w[0] * a + w[1] * b + w[2] * c;
    s = Stencil{{static_cast<int>(pair.a), tri[0], tri[1], tri[2]}, {1.0, -w[0], -w[1], -w[2]}};
    const Eigen::Vector3d d = p - q;
    distance = d.norm();
    return contactNormal(d, distance, (b - a).cross(c - a), normal);
  }
  const Eigen::Vector2i &e = edges_[pair.a], &f = edges_[pair.b];
  const Eigen::Vector3d p0 = at(e[0]), p1 = at(e[1]), q0 = at(f[0]), q1 = at(f[1]);
  const Eigen::Vector2d st = closestOnSegments(p0, p1, q0, q1);
  s = Stencil{{e[0], e[1], f[0], f[1]}, {1.0 - st[0], st[0], -(1.0 - st[1]), -st[1]}};
  const Eigen::Vector3d d = (p0 + st[0] * (p1 - p0)) - (q0 + st[1] * (q1 - q0));
  distance = d.norm();
  return contactNormal(d, distance, (p1 - p0).cross(q1 - q0), normal);
}

double SelfCollisionSolver::normalVelocity(const Stencil& s, const Eigen::Vector3d& n) const
{
  double v = 0.0;
  for (int k = 0; k < 4; ++k)
    v += s.weight[k] * vbar_.col(s.particle[k]).dot(n);
  return v;
}

void SelfCollisionSolver::applyImpulse(const Stencil& s, const Eigen::Vector3d& n, double dv)
{
  // An impulse j along n changes v̄_k by w_k j / m_k n, and so the relative normal velocity
  // Σ w_k v̄_k · n by j Σ w_k² / m_k. The end velocities get their own impulse: the one that stops
  // their approach along n, if they approach (inelastic, so it never adds kinetic energy).
  double denom = 0.0;
  for (int k = 0; k < 4; ++k)
    denom += s.weight[k] * s.weight[k] * inverse_mass_[s.particle[k]];
  if (denom <= 0.0) return;  // every particle pinned
  double end_approach = 0.0;
  for (int k = 0; k < 4; ++k)
    end_approach += s.weight[k] * v_end_.col(s.particle[k]).dot(n);
  const double j = dv / denom;
  const double j_end = end_approach < 0.0 ? -end_approach / denom : 0.0;
  for (int k = 0; k < 4; ++k)
  {
    const int i = s.particle[k];
    if (inverse_mass_[i] == 0.0) continue;
    vbar_.col(i) += s.weight[k] * j * inverse_mass_[i] * n;
    v_end_.col(i) += s.weight[k] * j_end * inverse_mass_[i] * n;
    moving_[i] = 1;
    changed_[i] = 1;
  }
}

void SelfCollisionSolver::count(const Stencil& s, int CollisionCounts::*field, CollisionReport& report)
{
  ++(report.total.*field);
  const int body_a = body_of_[s.particle[0]], body_b = body_of_[s.particle[3]];
  ++(body_counts_[body_a].*field);
  if (body_b != body_a) ++(body_counts_[body_b].*field);
}

void SelfCollisionSolver::repelProximities(double h, CollisionReport& report)
{
  for (const PairStart& start : pair_start_)
  {
    if (!start.valid) continue;
    const Stencil& s = start.stencil;
    const Eigen::Vector3d& n = start.normal;
    const double distance = start.distance;
    const double thickness = pairThickness(s.particle[0], s.particle[3]);
    if (distance >= thickness) continue;
    count(s, &CollisionCounts::proximity_pairs, report);
    // Separate by a share of the missing distance over the step; the approach it cancels is
    // inelastic (end velocities too), the rest moves positions only.
    const double v_n = normalVelocity(s, n);
    const double target = kRepulsionShare * (thickness - distance) / h;
    if (v_n >= target) continue;
    applyImpulse(s, n, target - v_n);
  }
}

bool SelfCollisionSolver::mayTouch(const Pair& pair, const PairStart& start, double h) const
{
  // The distance between the pair's items changes at most as fast as the largest relative
  // displacement L of a particle of one item against a particle of the other over the step, so it
  // stays above (d(0) + d(1) − L) / 2 throughout. The distance to the plane of the triangle (or
  // between the lines of the edges) is below d and cheaper: it is tried first.
  int first[3], second[3];
  int n_first = 0, n_second = 0;
  if (pair.kind == 0)
  {
    first[n_first++] = static_cast<int>(pair.a);
    for (int k = 0; k < 3; ++k)
      second[n_second++] = triangles_[pair.b][k];
  }
  else
  {
    for (int k = 0; k < 2; ++k)
    {
      first[n_first++] = edges_[pair.a][k];
      second[n_second++] = edges_[pair.b][k];
    }
  }
  double lipschitz = 0.0;
  for (int i = 0; i < n_first; ++i)
    for (int j = 0; j < n_second; ++j)
      lipschitz = std::max(lipschitz, (vbar_.col(first[i]) - vbar_.col(second[j])).norm());
  const double touch = kTouchShare * pairThickness(first[0], second[0]);
  // Cheapest first: d(t) ≥ d(0) − t h L already keeps most candidates (items a margin apart) clear.
  if (start.valid && start.distance - h * lipschitz > touch) return false;
  const auto planeDistance = [&](double t) {
    const auto at = [&](int i) -> Eigen::Vector3d { return x0_.col(i) + t * h * vbar_.col(i); };
    const Eigen::Vector3d normal = pair.kind == 0 ? (at(second[1]) - at(second[0])).cross(at(second[2]) - at(second[0]))
                                                  : (at(first[1]) - at(first[0])).cross(at(second[1]) - at(second[0]));
    const double norm = normal.norm();
    return norm > 0.0 ? std::abs(normal.dot(at(first[0]) - at(second[0]))) / norm : 0.0;
  };
  if (0.5 * (planeDistance(0.0) + planeDistance(1.0) - h * lipschitz) > touch) return false;
  Stencil s;
  Eigen::Vector3d n;
  double d_end = 0.0;
  if (!start.valid || !stencil(pair, 1.0, h, s, n, d_end)) return true;
  return 0.5 * (start.distance + d_end - h * lipschitz) <= touch;
}

int SelfCollisionSolver::detectCollisions(double h, bool apply_impulses, bool merge_zones, CollisionReport& report)
{
  // The first pass over new candidates looks at every pair; a later one only at the pairs with a
  // particle that the pass before moved (the others were clear then and have not changed).
  const bool all_pairs = new_candidates_;
  new_candidates_ = false;
  std::swap(moved_, moving_);
  std::fill(moving_.begin(), moving_.end(), 0);
  int found = 0;
  for (std::size_t pair_index = 0; pair_index < pairs_.size(); ++pair_index)
  {
    const Pair& pair = pairs_[pair_index];
    const PairStart& start = pair_start_[pair_index];
    int ids[4];
    if (pair.kind == 0)
    {
      const Eigen::Vector3i& tri = triangles_[pair.b];
      ids[0] = tri[0];
      ids[1] = tri[1];
      ids[2] = tri[2];
      ids[3] = static_cast<int>(pair.a);
    }
    else
    {
      ids[0] = edges_[pair.a][0];
      ids[1] = edges_[pair.a][1];
      ids[2] = edges_[pair.b][0];
      ids[3] = edges_[pair.b][1];
    }
    // After the first pass only pairs with a particle that an impulse moved since their last test
    // can have changed: in the pass before (after them), or in this one (before them).
    const auto changed = [&](int i) { return moved_[i] || moving_[i]; };
    if (!all_pairs && !changed(ids[0]) && !changed(ids[1]) && !changed(ids[2]) && !changed(ids[3])) continue;
    if (!mayTouch(pair, start, h)) continue;
    // The pair's four particles move in straight lines over the step; they are coplanar where the
    // triple product of their differences vanishes, a cubic in t.
    const Eigen::Vector3d x0 = x0_.col(ids[0]), d0 = h * vbar_.col(ids[0]);
    const Eigen::Vector3d u = x0_.col(ids[1]) - x0, du = h * vbar_.col(ids[1]) - d0;
    const Eigen::Vector3d w = x0_.col(ids[2]) - x0, dw = h * vbar_.col(ids[2]) - d0;
    const Eigen::Vector3d r = x0_.col(ids[3]) - x0, dr = h * vbar_.col(ids[3]) - d0;
    double c[4];
    tripleProductCubic(u, du, w, dw, r, dr, c);
    double roots[3];
    const int n_roots = unitRoots(c[3], c[2], c[1], c[0], roots);
    // A pair that touches while approaching: impulses leave it separating at a share of its
    // thickness over the step; the impact zones only need it not to approach.
    bool hit = false;
    const auto respond = [&](const Stencil& s, const Eigen::Vector3d& n, double thickness) {
      const double v_n = normalVelocity(s, n);
      const double target = kSeparationShare * thickness / h;
      if (v_n >= (apply_impulses ? target : 0.0)) return false;
      hit = true;
      ++found;
      if (apply_impulses)
      {
        count(s, &CollisionCounts::collisions, report);
        applyImpulse(s, n, target - v_n);
      }
      if (merge_zones)
      {
        for (int m = 1; m < 4; ++m)
          unite(s.particle[0], s.particle[m]);
      }
      return true;
    };
    for (int k = 0; k < n_roots; ++k)
    {
      Stencil s;
      Eigen::Vector3d n;
      double distance = 0.0;
      if (!stencil(pair, roots[k], h, s, n, distance)) continue;
      const double thickness = pairThickness(s.particle[0], s.particle[3]);
      if (distance > kTouchShare * thickness) continue;
      // They touch at roots[k]. The normal is the plane's there (the face's, or the two edges'
      // cross product), turned to the side the first item was on just before: the sign of the
      // triple product between the previous root (or the start) and this one, which is that
      // plane's normal times the first item's offset from the second. Where it was in the plane
      // all along, the normal is turned against their approach.
      const double t = roots[k];
      const auto at = [&](int m) -> Eigen::Vector3d { return x0_.col(ids[m]) + t * h * vbar_.col(ids[m]); };
      const Eigen::Vector3d plane =
          pair.kind == 0 ? (at(1) - at(0)).cross(at(2) - at(0)) : (at(1) - at(0)).cross(at(3) - at(2));
      const double t_before = 0.5 * ((k == 0 ? 0.0 : roots[k - 1]) + t);
      const double side = ((c[3] * t_before + c[2]) * t_before + c[1]) * t_before + c[0];
      if (plane.norm() > 0.0) n = plane.normalized();
      if (side < 0.0 || (side == 0.0 && normalVelocity(s, n) > 0.0)) n = -n;
      if (respond(s, n, thickness)) break;
    }
    if (hit) continue;
    // Items that move in parallel (two parallel edges, a point sliding along a face) are coplanar
    // all along or never, and the cubic does not see them meet: the end of the step is checked too,
    // with the direction they were apart in at the start.
    Stencil s_end;
    Eigen::Vector3d n_end;
    double d_end = 0.0;
    if (!stencil(pair, 1.0, h, s_end, n_end, d_end) || !start.valid) continue;
    const double thickness = pairThickness(s_end.particle[0], s_end.particle[3]);
    if (d_end <= kTouchShare * thickness) respond(s_end, start.normal, thickness);
  }
  return found;
}

int SelfCollisionSolver::findZone(int i)
{
  if (zone_[i] < 0) zone_[i] = i;
  while (zone_[i] != i)
  {
    zone_[i] = zone_[zone_[i]];  // path halving
    i = zone_[i];
  }
  return i;
}

void SelfCollisionSolver::unite(int a, int b)
{
  const int ra = findZone(a), rb = findZone(b);
  if (ra != rb) zone_[std::max(ra, rb)] = std::min(ra, rb);  // the lower index is the root: deterministic
}

void SelfCollisionSolver::mergeImpactZones(double h, CollisionReport& report)
{
  const int n = static_cast<int>(x0_.cols());
  std::fill(zone_.begin(), zone_.end(), -1);
  for (int round = 0; round < kZoneRounds; ++round)
  {
    if (!pathsInsideBoxes(h, false)) refindCandidates(h, report);
    ++report.passes;
    if (detectCollisions(h, false, true, report) == 0)
    {
      countZones(report);
      return;
    }
    rigidifyZones(vbar_);
    rigidifyZones(v_end_);
  }
  // Still colliding after every round: every free particle stops where it started the step (x0 had
  // no intersection; only pins can still move).
  for (int i = 0; i < n; ++i)
  {
    if (inverse_mass_[i] == 0.0) continue;
    vbar_.col(i).setZero();
    v_end_.col(i).setZero();
    changed_[i] = 1;
    if (zone_[i] < 0) zone_[i] = i;
  }
  countZones(report);
}

void SelfCollisionSolver::countZones(CollisionReport& report)
{
  const int n = static_cast<int>(x0_.cols());
  for (int i = 0; i < n; ++i)
  {
    if (zone_[i] < 0) continue;
    if (findZone(i) == i) ++report.impact_zones;
    ++report.total.impact_zone_particles;
    ++body_counts_[body_of_[i]].impact_zone_particles;
  }
}

void SelfCollisionSolver::rigidifyZones(Eigen::Matrix3Xd& v)
{
  // Each zone moves as a rigid body with its particles' momentum and angular momentum about its
  // centre of mass (v_i = v_cm + ω × (x_i − x_cm), I ω = L): the rigid motion nearest to theirs in
  // kinetic energy, which it never exceeds. A zone holding pinned particles moves with their mean
  // velocity instead. Linear paths of an affine motion keep the zone free of
  // intersections it did not have at x0.
  const int n = static_cast<int>(x0_.cols());
  for (int i = 0; i < n; ++i)
    if (zone_[i] >= 0 && findZone(i) == i) zone_sums_[i] = ZoneSum{};
  for (int i = 0; i < n; ++i)
  {
    if (zone_[i] < 0) continue;
    ZoneSum& z = zone_sums_[findZone(i)];
    if (inverse_mass_[i] == 0.0)
    {
      ++z.pinned;
      z.pinned_velocity += v.col(i);
      continue;
    }
    const double m = 1.0 / inverse_mass_[i];
    z.mass += m;
    z.moment += m * x0_.col(i);
    z.momentum += m * v.col(i);
  }
  for (int i = 0; i < n; ++i)
  {
    if (zone_[i] < 0 || inverse_mass_[i] == 0.0) continue;
    ZoneSum& z = zone_sums_[findZone(i)];
    const double m = 1.0 / inverse_mass_[i];
    const Eigen::Vector3d r = x0_.col(i) - z.moment / z.mass;
    z.angular_momentum += m * r.cross(v.col(i) - z.momentum / z.mass);
    z.inertia += m * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
  }
  for (int i = 0; i < n; ++i)
  {
    if (zone_[i] >= 0 && findZone(i) == i && zone_sums_[i].pinned == 0 && zone_sums_[i].mass > 0.0)
    {
      ZoneSum& z = zone_sums_[i];
      const double scale = z.inertia.trace() + 1e-300;
      z.omega = (z.inertia + 1e-12 * scale * Eigen::Matrix3d::Identity()).ldlt().solve(z.angular_momentum);
    }
  }
  for (int i = 0; i < n; ++i)
  {
    if (zone_[i] < 0 || inverse_mass_[i] == 0.0) continue;
    const ZoneSum& z = zone_sums_[findZone(i)];
    if (z.pinned > 0)
      v.col(i) = z.pinned_velocity / z.pinned;
    else
      v.col(i) = z.momentum / z.mass + z.omega.cross(x0_.col(i) - z.moment / z.mass);
    moving_[i] = 1;
    changed_[i] = 1;
  }
}

void SelfCollisionSolver::scatter(double h, const std::vector<SpringNetworkBody*>& bodies)
{
  // Only the particles an impulse, a zone or the last resort changed move: x1 = x0 + h v̄, with
  // their end velocity.
  for (std::size_t b = 0; b < bodies.size(); ++b)
  {
    ParticlePool& p = bodies[b]->particlesForContacts();
    const int first = body_first_[b];
    bool moved = false;
    for (int i = 0; i < p.size(); ++i)
    {
      const int g = first + i;
      if (!changed_[g]) continue;
      p.position.col(i) = x0_.col(g) + h * vbar_.col(g);
      p.velocity.col(i) = v_end_.col(g);
      moved = true;
    }
    if (moved) bodies[b]->particlesMovedAfterStep();
  }
}

}  // namespace core
}  // namespace particle_sim
