#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <vector>

namespace particle_sim
{
namespace core
{
class SpringNetworkBody;

/// A body's collisions with itself and with the other bodies that enable theirs: cloth and jelly by
/// their surface triangles and edges, ropes as chains of capsules (their edges).
struct SelfCollisionDef
{
  bool enabled = false;
  /// [m] in limits::kSelfCollisionThickness: the distance kept between two parts of the body (between
  /// two bodies, the mean of their thicknesses). A rope's thickness is its diameter.
  double thickness = 0.005;
};

/// What the collision pass of one step did, for one body or for the world.
struct CollisionCounts
{
  int proximity_pairs = 0;        ///< pairs closer than their thickness at the step's start, repelled
  int collisions = 0;             ///< pairs found crossing during the step, stopped by an impulse
  int impact_zone_particles = 0;  ///< particles the fail-safe moved rigidly with their impact zone
};

struct CollisionReport
{
  int passes = 0;        ///< continuous-detection passes run (those of the fail-safe included)
  int searches = 0;      ///< broad-phase searches for candidate pairs (0: those of an earlier step served)
  int impact_zones = 0;  ///< rigid impact zones the fail-safe formed (0: the impulses sufficed)
  CollisionCounts total;
  std::vector<CollisionCounts> bodies;  ///< one per world body, in order (zero where it is off)
};

/// Self- and body–body collision of surfaces after each world step (Bridson, Fedkiw & Anderson
/// 2002), on the bodies that enable it. Each body has stepped from x0 (its positions at the step's
/// start) to x1 with whatever method it uses; the pass works on the average velocities
/// v̄ = (x1 − x0) / h of the step and changes them by impulses between pairs:
/// 1. proximity: a point and a triangle, or two edges, closer than their thickness at x0 get an
///    impulse that separates them by a tenth of the missing distance over the step;
/// 2. continuous detection: every point–triangle and edge–edge pair that becomes coplanar during the
///    step (the cubic in t of their linear paths) and touches there, or that ends the step touching
///    (parallel items), gets an impulse that stops its approach, pass after pass (Gauss–Seidel),
///    until a pass finds nothing or the passes run out;
/// 3. fail-safe (rigid impact zones, Provot 1997): the particles of the pairs still colliding are
///    merged into zones that move rigidly (their momentum and angular momentum kept), growing until
///    nothing collides; x0 had no intersection, so then no step ends with one.
/// Then x1 = x0 + h v̄. The end velocities get only impulses that stop an approach (inelastic) and
/// the zones' rigid projection, so the pass never adds kinetic energy; the separation moves
/// positions only.
///
/// Broad phase: a uniform grid of the edges' and triangles' swept boxes (swept in a frame moving with
/// the particles' median velocity; cells one mean edge long, or the mean travel if longer),
/// counting-sorted by cell into a hash table for edges and one for triangles; each point looks for
/// triangles and each edge for edges in the cells of its own box, and keeps its pairs in the order
/// of the other item, so the cells change the cost, never the result (but for items whose box spans
/// too many cells, tested against all after the others). The boxes are grown by a margin, and the
/// candidates serve the next steps while every particle's path stays inside its box (the frame's
/// position is kept from step to step): a cloth that falls, lies still or is carried searches
/// rarely. Every pair that can come within its thickness is a candidate either way, and a pass
/// tests every pair a particle of which moved since the pair's last test, so the margin and the
/// reuse change the cost, never the result. Deterministic, and allocation-free once its arrays have
/// grown to the scene's size. Pinned particles have infinite mass: they move as their pins say.
class SelfCollisionSolver
{
public:
  /// Runs the pass over `bodies` (the world's bodies that enable self_collision and are not frozen)
  /// after a step of `h` [s]. `report` is cleared; bodies[k]'s counts go to
  /// report.bodies[report_index[k]] (report.bodies must be large enough). Nothing runs for none.
  void resolve(double h, const std::vector<SpringNetworkBody*>& bodies, const std::vector<int>& report_index,
               CollisionReport& report);
  /// Rebuild the surfaces at the next resolve(): the World calls it when bodies are added, removed
  /// or reset (a new body may take a removed one's address and size).
  void forgetTopology() { topology_stale_ = true; }
  /// Search the candidate pairs afresh at the next resolve(), as if none had been found. It changes
  /// what the pass costs, never what it does (the tests compare the two).
  void forgetCandidates() { candidates_valid_ = false; }
  /// The margin [share of the mean edge, ≥ 0; default 0.1] the candidates' boxes are grown by, so
  /// that they serve later steps. Like forgetCandidates(), it changes the cost, never the result.
  /// A negative or NaN share is taken as 0 (a box smaller than its path would lose pairs).
  void setCandidateMargin(double share) { candidate_margin_ = std::max(0.0, share); }

private:
  struct Item
  {
    std::uint64_t cell;  // the grid cell's key
    std::uint32_t item;  // index into codes_
  };
  struct Pair
  {
    std::uint32_t a, b;  // point and triangle (kind 0) or two edges (kind 1)
    std::uint32_t kind;
  };
  // A pair's four particles with their weights: the relative velocity is Σ w_k v̄_k (point–triangle:
  // the point, then the corners; edge–edge: the first edge's ends, then the second's).
  struct Stencil
  {
    int particle[4];
    double weight[4];
  };
  // A pair's closest points at the step's start (x0), found once per candidate list.
  struct PairStart
  {
    Stencil stencil;
    Eigen::Vector3d normal;  // from the second item to the first
    double distance;
    bool valid;  // false: degenerate geometry
  };
  struct TopologyKey
  {
    const SpringNetworkBody* body;
    int particles;
    long long torn;
  };
  struct ZoneSum
  {
    double mass = 0.0;
    Eigen::Vector3d moment = Eigen::Vector3d::Zero();    // Σ m x0
    Eigen::Vector3d momentum = Eigen::Vector3d::Zero();  // Σ m v̄
    Eigen::Vector3d angular_momentum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
    Eigen::Vector3d omega = Eigen::Vector3d::Zero();
    int pinned = 0;
    Eigen::Vector3d pinned_velocity = Eigen::Vector3d::Zero();
  };

  void gather(double h, const std::vector<SpringNetworkBody*>& bodies);
  void buildTopology(const std::vector<SpringNetworkBody*>& bodies);
  void scatter(double h, const std::vector<SpringNetworkBody*>& bodies);
  // The frame's velocity for the paths: the particles' median v̄, per axis.
  void chooseFrame();
  // Candidate pairs whose boxes (swept from x0 to x0 + h v̄ in the frame, grown by half the largest
  // thickness and by a margin) overlap, found through a uniform grid; then their start stencils.
  void findCandidates(double h, CollisionReport& report);
  void refindCandidates(double h, CollisionReport& report);  // chooseFrame(), then findCandidates()
  // Each candidate's stencil at the step's start.
  void findPairStarts(double h);
  // Whether the candidates found last still cover the paths: at the step's start (`step_start`),
  // every path inside its recorded box; within the step, after impulses, every path's end inside
  // it give or take half the largest thickness.
  bool pathsInsideBoxes(double h, bool step_start) const;
  // The stencil of `pair` at time t·h of the step, its distance and the direction from the second
  // item to the first; false when the geometry is degenerate.
  bool stencil(const Pair& pair, double t, double h, Stencil& s, Eigen::Vector3d& normal, double& distance) const;
  // The contact normal from the distance vector d between closest points, or from `plane` where
  // they touch; false when both vanish.
  bool contactNormal(const Eigen::Vector3d& d, double distance, const Eigen::Vector3d& plane,
                     Eigen::Vector3d& normal) const;
  double normalVelocity(const Stencil& s, const Eigen::Vector3d& n) const;
  // False when the pair cannot come within touching distance during the step (a bound from its
  // distances at the start and end and its relative motion).
  bool mayTouch(const Pair& pair, const PairStart& start, double h) const;
  void repelProximities(double h, CollisionReport& report);
  // One Gauss–Seidel pass of continuous detection over the candidates: the number of pairs that
  // touch during the step while approaching. Each gets an impulse (`apply_impulses`) or has its
  // particles merged into one impact zone (`merge_zones`).
  int detectCollisions(double h, bool apply_impulses, bool merge_zones, CollisionReport& report);
  void mergeImpactZones(double h, CollisionReport& report);
  // Replaces `v` of every zone's particles by the zone's rigid motion.
  void rigidifyZones(Eigen::Matrix3Xd& v);
  void countZones(CollisionReport& report);
  int findZone(int i);
  void unite(int a, int b);
  // Changes the relative normal velocity of `s` along `n` by `dv` [m/s] with an impulse shared by
  // inverse mass, and stops the approach of the end velocities along n.
  void applyImpulse(const Stencil& s, const Eigen::Vector3d& n, double dv);
  // Counts a pair in the report's total and in its bodies' counts (body_counts_).
  void count(const Stencil& s, int CollisionCounts::*field, CollisionReport& report);
  double pairThickness(int particle_a, int particle_b) const;

  std::vector<CollisionCounts> body_counts_;  // per participating body, copied to the report at the end
  // The participating particles, all bodies in one numbering, and their surfaces.
  std::vector<TopologyKey> topology_bodies_;
  std::vector<int> body_first_;
  Eigen::Matrix3Xd x0_, vbar_, v_end_;  // v_end_: the velocities the step ended with
  std::vector<double> inverse_mass_, thickness_;
  std::vector<int> body_of_;
  std::vector<int> origin_;     // per particle, the particle as built it comes from (a tear's copies share it)
  std::vector<char> is_point_;  // in some edge or triangle
  std::vector<Eigen::Vector3i> triangles_;
  std::vector<Eigen::Vector2i> edges_;
  double length_scale_ = 0.0;  // [m] the surfaces' mean edge (at least the largest thickness)
  double cell_size_ = 0.0;     // [m] the grid's, chosen at each candidate search
  double max_thickness_ = 0.0;
  // Broad phase.
  std::vector<std::uint32_t> codes_;    // kind << 30 | index, points then edges then triangles
  Eigen::Matrix3Xd box_lo_, box_hi_;    // per code
  Eigen::Matrix3Xd path_lo_, path_hi_;  // per particle: the box of its path when the candidates were found
  Eigen::Vector3d frame_velocity_ = Eigen::Vector3d::Zero();  // [m/s] of the frame those paths are in
  Eigen::Vector3d frame_origin_ = Eigen::Vector3d::Zero();    // [m] where that frame is at the step's start
  bool candidates_valid_ = false;                             // false until found for this topology
  bool candidates_margined_ = false;                          // found with a margin
  bool candidates_reused_ = false;                            // have served a step after the one they were found in
  int searches_without_margin_ = 0;                           // left before a margin is tried again
  double candidate_margin_ = 0.1;                             // [share of length_scale_]
  std::vector<double> median_scratch_;                        // per particle: for the frame's velocity
  std::size_t buckets_ = 1;                                   // of the grid's hash table, a power of 2 (4 per item)
  std::vector<std::size_t> bucket_start_, bucket_fill_;
  std::vector<Item> entries_;
  std::vector<std::uint32_t> big_;  // codes_ indices whose box spans too many cells: tested against all
  std::vector<char> big_flag_;      // per code
  std::vector<long long> seen_;     // per code: the last item that found it (a pair once)
  std::vector<Pair> pairs_;
  std::vector<PairStart> pair_start_;  // per pair
  bool new_candidates_ = true;
  std::vector<char> moved_, moving_;  // per particle: moved by the last pass, by this one
  std::vector<char> changed_;         // per particle: changed in this step (scatter writes it back)
  bool topology_stale_ = true;
  // Fail-safe.
  std::vector<int> zone_;  // union–find parent per particle (−1: in no zone)
  std::vector<ZoneSum> zone_sums_;
};

}  // namespace core
}  // namespace particle_sim
