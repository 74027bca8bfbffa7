// Tearing (SpringNetworkDef::tear_strain): a spring stretched past the tear strain at the end of a
// step breaks. A cloth pulled apart by two grippers tears where its untorn twin is most strained
// and comes apart in two; a tear never adds energy; the surface left is a manifold whose every
// edge still has a spring; tearing is deterministic, and reset mends it.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <numeric>
#include <set>
#include <utility>
#include <vector>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/integrators/bdf2.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/symplectic_euler.h"
#include "particle_sim/core/spring_network.h"
#include "test_helpers.h"

using namespace particle_sim::core;
using particle_sim_test::noGravity;

namespace
{
constexpr int kColumns = 16;         // particles along u (x), the pull's direction
constexpr int kRows = 8;             // particles along v (y)
constexpr double kSpacing = 0.04;    // [m] grid spacing
constexpr double kTearStrain = 0.3;  // [-]
constexpr double kPullSpeed = 0.5;   // [m/s] of the right gripper
constexpr double kDt = 1.0 / 240.0;  // [s]

int gridIndex(int column, int row)
{
  return row * kColumns + column;
}

// A flat cloth held by two grippers: the left one holds its first column, the right one its last
// (the spring cloth), or the two middle particles of each (the Baraff–Witkin cloth: held by whole
// columns, its strain would be uniform and every triangle would tear in the same step).
ClothGridDef grippedCloth(IntegratorType integrator, double tear_strain = kTearStrain,
                          ClothModel model = ClothModel::Springs)
{
  ClothGridDef def(model);
  def.name = "torn";
  def.origin = {0.0, 0.0, 1.0};
  def.edge_u = {kSpacing * (kColumns - 1), 0.0, 0.0};
  def.edge_v = {0.0, kSpacing * (kRows - 1), 0.0};
  def.nu = kColumns;
  def.nv = kRows;
  def.mass = 0.2;
  const bool whole_columns = model == ClothModel::Springs;
  for (int row = whole_columns ? 0 : kRows / 2 - 1; row < (whole_columns ? kRows : kRows / 2 + 1); ++row)
  {
    def.pins.push_back(gridIndex(0, row));
    def.pins.push_back(gridIndex(kColumns - 1, row));
  }
  def.integrator.type = integrator;
  def.tear_strain = tear_strain;
  return def;
}

// Two particles 1 m apart, both pinned, joined by one stretch spring of 100 N/m.
SpringNetworkDef pinnedPair(double tear_strain)
{
  SpringNetworkDef def;
  def.name = "pair";
  def.positions = {Eigen::Vector3d::Zero(), Eigen::Vector3d(1.0, 0.0, 0.0)};
  def.masses = {1.0, 1.0};
  def.springs = {Spring{0, 1, 1.0, 100.0, 0.0, SpringClass::Stretch}};
  def.pins = {0, 1};
  def.tear_strain = tear_strain;
  return def;
}

// Moves the right gripper by one step of the pull.
void pullRightGripper(SpringNetworkBody& body)
{
  for (int row = 0; row < kRows; ++row)
  {
    const int index = gridIndex(kColumns - 1, row);
    if (!body.isPinned(index)) continue;
    ASSERT_TRUE(body.setPinTarget(index, body.pinTarget(index) + Eigen::Vector3d(kPullSpeed * kDt, 0.0, 0.0)));
  }
}

// Strain (l − L) / L of a spring at the body's positions, computed here from the definition.
double strainOf(const SpringNetworkBody& body, const Spring& spring)
{
  const Eigen::Matrix3Xd& x = body.particles().position;
  return ((x.col(spring.j) - x.col(spring.i)).norm() - spring.rest_length) / spring.rest_length;
}

std::pair<int, int> ordered(int a, int b)
{
  return a < b ? std::make_pair(a, b) : std::make_pair(b, a);
}

// Particles reachable from `from` over the springs left.
std::vector<char> reachable(const SpringNetworkBody& body, int from)
{
  const int n = body.particles().size();
  std::vector<std::vector<int>> neighbours(n);
  for (const Spring& spring : body.springs())
  {
    neighbours[spring.i].push_back(spring.j);
    neighbours[spring.j].push_back(spring.i);
  }
  std::vector<char> seen(n, 0);
  std::vector<int> stack{from};
  seen[from] = 1;
  while (!stack.empty())
  {
    const int i = stack.back();
    stack.pop_back();
    for (int j : neighbours[i])
    {
      if (!seen[j]) stack.push_back(j), seen[j] = 1;
    }
  }
  return seen;
}

double mechanicalEnergy(const SpringNetworkBody& body, const Environment& env)
{
  return body.kineticEnergy() + body.potentialEnergy(env.gravity);
}

// The tear strain at the end of a pull of kColumns−1 cells by 0.3 of their length at 0.5 m/s is
// reached after about 0.17 m of travel, 80 steps: 300 steps pull well past it.
constexpr int kPullSteps = 300;

}  // namespace

// Two copies of the cloth, one that tears and one that cannot, pulled alike: they agree to the bit
// until the first tear, which breaks exactly the springs that the untorn twin has past the tear
// strain (the most strained among them); pulled on, the cloth comes apart between the grippers.
TEST(Tearing, PulledClothTearsWhereItsUntornTwinIsMostStrained)
{
  for (IntegratorType type : {kImplicitEulerIntegrator, kSymplecticEulerIntegrator})
  {
    SCOPED_TRACE(toString(type));
    SpringNetworkBody torn(buildClothGrid(grippedCloth(type)));
    SpringNetworkBody twin(buildClothGrid(grippedCloth(type, 0.0)));
    const Environment env = noGravity();
    int first_tear = -1;
    for (int step = 0; step < kPullSteps; ++step)
    {
      pullRightGripper(torn);
      pullRightGripper(twin);
      torn.step(kDt, env);
      twin.step(kDt, env);
      ASSERT_TRUE(torn.particles().position.allFinite() && torn.particles().velocity.allFinite()) << "step " << step;
      if (first_tear >= 0) continue;
      if (torn.lastTornSprings() == 0)
      {
        ASSERT_TRUE(torn.particles().position == twin.particles().position) << "step " << step;
        continue;
      }
      first_tear = step;
      std::set<std::pair<int, int>> broken, over;
      for (const std::pair<int, int>& pair : torn.lastTear().springs)
        broken.insert(ordered(pair.first, pair.second));
      const Spring* most_strained = nullptr;
      for (const Spring& spring : twin.springs())
      {
        if (strainOf(twin, spring) > kTearStrain) over.insert(ordered(spring.i, spring.j));
        if (!most_strained || strainOf(twin, spring) > strainOf(twin, *most_strained)) most_strained = &spring;
      }
      EXPECT_EQ(broken, over);
      EXPECT_EQ(broken.count(ordered(most_strained->i, most_strained->j)), 1u);
      EXPECT_EQ(torn.springs().size() + broken.size(), twin.springs().size());
    }
    ASSERT_GT(first_tear, 0) << "the cloth never tore";
    // Apart: no spring path joins the grippers.
    const std::vector<char> left = reachable(torn, gridIndex(0, 0));
    for (int row = 0; row < kRows; ++row)
      EXPECT_FALSE(left[gridIndex(kColumns - 1, row)]) << "row " << row;
    EXPECT_GT(torn.tornSprings(), kRows);
  }
}

// Grippers that stop at the first tear do no more work; the tear runs on through the cloth, and a
// tear never adds energy (a broken spring or triangle takes its energy with it, and the methods go
// on dissipating around the hole). The spring cloth
// loses energy in every step. A Baraff–Witkin cloth may gain a little in a step without a tear
// where torn flaps fold (its energy is not convex there: backward Euler then reports a stability
// event, and symplectic Euler's energy wobbles), so for it the steps that tear and the hold as a
// whole are checked.
TEST(Tearing, ATearNeverAddsEnergy)
{
  for (ClothModel model : {ClothModel::Springs, ClothModel::BaraffWitkin})
  {
    for (IntegratorType type : {kImplicitEulerIntegrator, kSymplecticEulerIntegrator})
    {
      SCOPED_TRACE(std::string(toString(type)) + " " + toString(model));
      SpringNetworkBody body(buildClothGrid(grippedCloth(type, kTearStrain, model)));
      const Environment env = noGravity();
      auto torn = [&body] { return body.tornSprings() + body.tornTriangles(); };
      for (int step = 0; torn() == 0; ++step)
      {
        ASSERT_LT(step, kPullSteps) << "the cloth never tore";
        pullRightGripper(body);
        body.step(kDt, env);
      }
      const long long torn_while_pulling = torn();
      const double held_energy = mechanicalEnergy(body, env);
      double energy = held_energy;
      for (int hold = 0; hold < 300; ++hold)
      {
        body.step(kDt, env);
        const double after = mechanicalEnergy(body, env);
        const bool tore = body.lastTornSprings() + body.lastTornTriangles() > 0;
        if (model == ClothModel::Springs || tore)
        {
          EXPECT_LE(after, energy + 1e-12 * std::abs(energy)) << "hold step " << hold << (tore ? ", a tear" : "");
        }
        energy = after;
      }
      EXPECT_LT(energy, held_energy);
      EXPECT_GT(torn(), torn_while_pulling) << "no tear while the grippers held still";
    }
  }
}

// The surface a tear leaves, split along the tear: every edge of a triangle in at most two triangles
// and every directed edge in at most one (consistently oriented); every triangle kept has at most
// one edge whose spring broke, and every triangle that went (compared by the built particles its
// corners come from) had two; every free particle's triangles are joined through edges that still
// have a spring (a vertex the tear left with several groups was split, one particle per group);
// the splits conserve the mass; and the cloth opened: its two halves no longer share a triangle.
TEST(Tearing, TornClothSplitsIntoAManifoldAlongItsTear)
{
  const ClothGridDef def = grippedCloth(kImplicitEulerIntegrator);
  SpringNetworkBody body(buildClothGrid(def));
  const Environment env = noGravity();
  for (int step = 0; step < kPullSteps; ++step)
  {
    pullRightGripper(body);
    body.step(kDt, env);
  }
  const int built_particles = static_cast<int>(body.definition().positions.size());
  const int n = body.particles().size();
  ASSERT_GT(body.splitParticles(), 0) << "the tear split no vertex";
  EXPECT_EQ(n, built_particles + body.splitParticles());
  for (int i = 0; i < n; ++i)
  {
    const int origin = body.particleOrigin(i);
    EXPECT_EQ(origin == i, i < built_particles) << "particle " << i;
    EXPECT_LT(origin, built_particles);
    EXPECT_TRUE(body.particles().position.col(i).allFinite());
  }
  EXPECT_NEAR(body.particleMasses().sum(), def.mass, 1e-12 * def.mass);

  const std::vector<Eigen::Vector3i>& surface = body.surfaceTriangles();
  const std::vector<Eigen::Vector3i>& built = body.definition().triangles;
  ASSERT_LT(surface.size(), built.size());
  ASSERT_GT(surface.size(), 0u);
  std::set<std::pair<int, int>> joined, joined_origins;
  for (const Spring& spring : body.springs())
  {
    joined.insert(ordered(spring.i, spring.j));
    joined_origins.insert(ordered(body.particleOrigin(spring.i), body.particleOrigin(spring.j)));
  }
  auto has_spring = [&](int a, int b) { return joined.count(ordered(a, b)) == 1; };
  std::map<std::pair<int, int>, int> uses, directed_uses;
  std::set<std::array<int, 3>> kept_origins;
  for (const Eigen::Vector3i& t : surface)
  {
    int missing = 0;
    for (int c = 0; c < 3; ++c)
    {
      const int a = t[c], b = t[(c + 1) % 3];
      missing += has_spring(a, b) ? 0 : 1;
      ++uses[ordered(a, b)];
      ++directed_uses[{a, b}];
    }
    EXPECT_LE(missing, 1) << "kept triangle " << t.transpose();
    std::array<int, 3> origins{body.particleOrigin(t[0]), body.particleOrigin(t[1]), body.particleOrigin(t[2])};
    std::sort(origins.begin(), origins.end());
    kept_origins.insert(origins);
  }
  for (const auto& [edge, count] : uses)
    EXPECT_LE(count, 2) << edge.first << "-" << edge.second;
  for (const auto& [edge, count] : directed_uses)
    EXPECT_EQ(count, 1) << edge.first << "->" << edge.second;
  for (const Eigen::Vector3i& t : built)
  {
    std::array<int, 3> corners{t[0], t[1], t[2]};
    std::sort(corners.begin(), corners.end());
    if (kept_origins.count(corners)) continue;
    int missing = 0;
    for (int c = 0; c < 3; ++c)
      missing += joined_origins.count(ordered(t[c], t[(c + 1) % 3])) ? 0 : 1;
    EXPECT_GE(missing, 2) << "triangle " << t.transpose() << " went with two of its springs";
  }

  // Each free particle's triangles form one group through edges with a spring (union–find).
  for (int u = 0; u < n; ++u)
  {
    if (body.isPinned(u)) continue;
    std::vector<int> fan;
    for (int t = 0; t < static_cast<int>(surface.size()); ++t)
      if (surface[t][0] == u || surface[t][1] == u || surface[t][2] == u) fan.push_back(t);
    std::vector<int> group(fan.size());
    std::iota(group.begin(), group.end(), 0);
    std::function<int(int)> root = [&](int a) { return group[a] == a ? a : group[a] = root(group[a]); };
    for (std::size_t a = 0; a < fan.size(); ++a)
      for (std::size_t b = a + 1; b < fan.size(); ++b)
        for (int c = 0; c < 3; ++c)
        {
          const int w = surface[fan[a]][c];
          const Eigen::Vector3i& other = surface[fan[b]];
          if (w != u && (other[0] == w || other[1] == w || other[2] == w) && has_spring(u, w))
            group[root(static_cast<int>(b))] = root(static_cast<int>(a));
        }
    for (std::size_t a = 1; a < fan.size(); ++a)
      EXPECT_EQ(root(static_cast<int>(a)), root(0)) << "particle " << u << "'s triangles fall apart";
  }

  // Opened: no chain of triangles sharing an edge joins the two grippers.
  std::map<std::pair<int, int>, int> first_triangle_of_edge;
  std::vector<int> triangle_group(surface.size());
  std::iota(triangle_group.begin(), triangle_group.end(), 0);
  std::function<int(int)> triangle_root = [&](int t) {
    return triangle_group[t] == t ? t : triangle_group[t] = triangle_root(triangle_group[t]);
  };
  for (int t = 0; t < static_cast<int>(surface.size()); ++t)
    for (int c = 0; c < 3; ++c)
    {
      const auto edge = ordered(surface[t][c], surface[t][(c + 1) % 3]);
      const auto found = first_triangle_of_edge.find(edge);
      if (found == first_triangle_of_edge.end())
        first_triangle_of_edge[edge] = t;
      else
        triangle_group[triangle_root(t)] = triangle_root(found->second);
    }
  std::set<int> left_groups, right_groups;
  for (int t = 0; t < static_cast<int>(surface.size()); ++t)
    for (int c = 0; c < 3; ++c)
    {
      const int origin = body.particleOrigin(surface[t][c]);
      if (origin % kColumns == 0) left_groups.insert(triangle_root(t));
      if (origin % kColumns == kColumns - 1) right_groups.insert(triangle_root(t));
    }
  for (int group : left_groups)
    EXPECT_EQ(right_groups.count(group), 0u) << "the grippers still share a sheet of triangles";
}

// The same pull tears the same springs in the same steps and ends in the same state, to the bit;
// reset() mends every tear (springs, surface, bound, count) and the pull then repeats itself.
TEST(Tearing, TearingIsDeterministicAndResetMendsIt)
{
  const Environment env = noGravity();
  auto pull = [&](SpringNetworkBody& body, std::vector<std::pair<int, int>>& log) {
    for (int step = 0; step < kPullSteps; ++step)
    {
      pullRightGripper(body);
      body.step(kDt, env);
      log.insert(log.end(), body.lastTear().springs.begin(), body.lastTear().springs.end());
    }
  };
  const ClothGridDef def = grippedCloth(kImplicitEulerIntegrator);
  SpringNetworkBody first(buildClothGrid(def)), second(buildClothGrid(def));
  const double built_bound = first.frequencyBound();
  std::vector<std::pair<int, int>> first_log, second_log, after_reset_log;
  pull(first, first_log);
  pull(second, second_log);
  ASSERT_FALSE(first_log.empty());
  EXPECT_EQ(first_log, second_log);
  EXPECT_TRUE(first.particles().position == second.particles().position);
  EXPECT_EQ(first.surfaceTriangles(), second.surfaceTriangles());

  const Eigen::Matrix3Xd torn_positions = first.particles().position;
  first.reset();
  EXPECT_EQ(first.tornSprings(), 0);
  EXPECT_EQ(first.springs().size(), first.definition().springs.size());
  EXPECT_EQ(first.surfaceTriangles(), first.definition().triangles);
  EXPECT_EQ(first.frequencyBound(), built_bound);
  pull(first, after_reset_log);
  EXPECT_EQ(after_reset_log, first_log);
  EXPECT_TRUE(first.particles().position == torn_positions);
}

// After a tear the explicit methods' stability bound is that of the springs left: the same as a
// body built from them alone. Here the stiff spring of a chain starts past the tear strain, so the
// bound falls from its stiffness to the soft one's.
TEST(Tearing, StabilityBoundIsThatOfTheSpringsLeft)
{
  SpringNetworkDef def;
  def.name = "chain";
  def.positions = {Eigen::Vector3d::Zero(), Eigen::Vector3d(1.0, 0.0, 0.0), Eigen::Vector3d(3.0, 0.0, 0.0)};
  def.masses = {1.0, 1.0, 1.0};
  def.springs = {Spring{0, 1, 1.0, 100.0, 0.0, SpringClass::Stretch},
                 Spring{1, 2, 1.0, 10000.0, 0.0, SpringClass::Stretch}};
  def.pins = {0};
  def.integrator.type = kSymplecticEulerIntegrator;
  def.tear_strain = 0.5;
  SpringNetworkBody body(def);
  const double built_bound = body.frequencyBound();
  body.step(1e-4, noGravity());
  ASSERT_EQ(body.tornSprings(), 1);
  SpringNetworkDef left = def;
  left.springs = body.springs();
  left.tear_strain = 0.0;
  EXPECT_EQ(body.frequencyBound(), SpringNetworkBody(left).frequencyBound());
  EXPECT_LT(body.frequencyBound(), 0.2 * built_bound);
}

// The Baraff–Witkin cloth alike: the first tear removes exactly the triangles its untorn twin has
// past the tear strain (computed here from the rest map: w = Σ_m ∂w/∂x_m x_m), with them leave the
// surface and every bend across their edges, and pulled on, the cloth comes apart.
TEST(Tearing, BaraffWitkinClothLosesItsOverstretchedTriangles)
{
  SpringNetworkBody torn(buildClothGrid(grippedCloth(kImplicitEulerIntegrator, kTearStrain, ClothModel::BaraffWitkin)));
  SpringNetworkBody twin(buildClothGrid(grippedCloth(kImplicitEulerIntegrator, 0.0, ClothModel::BaraffWitkin)));
  ASSERT_NE(torn.baraffWitkin(), nullptr);
  const Environment env = noGravity();
  auto key = [](int a, int b, int c) {
    std::array<int, 3> k{a, b, c};
    std::sort(k.begin(), k.end());
    return k;
  };
  bool torn_once = false;
  for (int step = 0; step < kPullSteps; ++step)
  {
    pullRightGripper(torn);
    pullRightGripper(twin);
    torn.step(kDt, env);
    twin.step(kDt, env);
    ASSERT_TRUE(torn.particles().position.allFinite());
    if (torn_once || torn.lastTornTriangles() == 0) continue;
    torn_once = true;
    const BaraffWitkinDef& rest = twin.baraffWitkin()->definition();
    const Eigen::Matrix3Xd& x = twin.particles().position;
    std::set<std::array<int, 3>> over, removed;
    for (const BwTriangle& t : rest.triangles)
    {
      Eigen::Vector3d wu = Eigen::Vector3d::Zero(), wv = Eigen::Vector3d::Zero();
      for (int m = 0; m < 3; ++m)
      {
        wu += t.dwu[m] * x.col(t.v[m]);
        wv += t.dwv[m] * x.col(t.v[m]);
      }
      if (std::max(wu.norm() / rest.b_u, wv.norm() / rest.b_v) - 1.0 > kTearStrain)
        over.insert(key(t.v[0], t.v[1], t.v[2]));
    }
    for (const Eigen::Vector3i& t : torn.lastTear().triangles)
      removed.insert(key(t[0], t[1], t[2]));
    EXPECT_EQ(removed, over);
    EXPECT_EQ(torn.surfaceTriangles().size() + removed.size(), twin.surfaceTriangles().size());
    for (const Eigen::Vector3i& t : torn.surfaceTriangles())
      EXPECT_EQ(removed.count(key(t[0], t[1], t[2])), 0u);
    // Every bend left has both its triangles, (x0, x1, x2) and (x3, x2, x1), among those left.
    std::set<std::array<int, 3>> left;
    for (const BwTriangle& t : torn.baraffWitkin()->definition().triangles)
      left.insert(key(t.v[0], t.v[1], t.v[2]));
    const BaraffWitkinDef& now = torn.baraffWitkin()->definition();
    ASSERT_EQ(now.bends.size(), now.bend_weights.size());
    EXPECT_LT(now.bends.size(), rest.bends.size());
    for (const BwBend& b : now.bends)
    {
      EXPECT_EQ(left.count(key(b.v[0], b.v[1], b.v[2])), 1u);
      EXPECT_EQ(left.count(key(b.v[3], b.v[2], b.v[1])), 1u);
    }
  }
  ASSERT_TRUE(torn_once) << "the cloth never tore";
  EXPECT_EQ(torn.tornSprings(), 0);
  // Apart: no triangle path joins the grippers.
  const int n = torn.particles().size();
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  std::function<int(int)> root = [&](int i) { return parent[i] == i ? i : parent[i] = root(parent[i]); };
  for (const BwTriangle& t : torn.baraffWitkin()->definition().triangles)
    for (int m = 1; m < 3; ++m)
      parent[root(t.v[m])] = root(t.v[0]);
  for (int left = 0; left < kRows; ++left)
    for (int right = 0; right < kRows; ++right)
    {
      if (!torn.isPinned(gridIndex(0, left)) || !torn.isPinned(gridIndex(kColumns - 1, right))) continue;
      EXPECT_NE(root(gridIndex(0, left)), root(gridIndex(kColumns - 1, right))) << "rows " << left << ", " << right;
    }
  // Split along the tear (it has no springs: triangles hold each other through the edges they
  // share): the conditions left are the surface left, corner for corner, every bend's two triangles
  // are among them, and each free particle's triangles are one group through shared edges.
  const BaraffWitkinDef& end = torn.baraffWitkin()->definition();
  std::set<std::array<int, 3>> surface_left, conditions_left;
  for (const Eigen::Vector3i& t : torn.surfaceTriangles())
    surface_left.insert(key(t[0], t[1], t[2]));
  for (const BwTriangle& t : end.triangles)
    conditions_left.insert(key(t.v[0], t.v[1], t.v[2]));
  EXPECT_EQ(conditions_left, surface_left);
  for (const BwBend& b : end.bends)
  {
    EXPECT_EQ(conditions_left.count(key(b.v[0], b.v[1], b.v[2])), 1u);
    EXPECT_EQ(conditions_left.count(key(b.v[3], b.v[2], b.v[1])), 1u);
  }
  EXPECT_NEAR(torn.particleMasses().sum(), twin.particleMasses().sum(), 1e-12);
  for (int u = 0; u < torn.particles().size(); ++u)
  {
    if (torn.isPinned(u)) continue;
    std::vector<std::array<int, 3>> fan;
    for (const BwTriangle& t : end.triangles)
      if (t.v[0] == u || t.v[1] == u || t.v[2] == u) fan.push_back({t.v[0], t.v[1], t.v[2]});
    std::vector<int> group(fan.size());
    std::iota(group.begin(), group.end(), 0);
    std::function<int(int)> group_root = [&](int a) { return group[a] == a ? a : group[a] = group_root(group[a]); };
    for (std::size_t a = 0; a < fan.size(); ++a)
      for (std::size_t b = a + 1; b < fan.size(); ++b)
        for (int w : fan[a])
          if (w != u && std::find(fan[b].begin(), fan[b].end(), w) != fan[b].end())
            group[group_root(static_cast<int>(b))] = group_root(static_cast<int>(a));
    for (std::size_t a = 1; a < fan.size(); ++a)
      EXPECT_EQ(group_root(static_cast<int>(a)), group_root(0)) << "particle " << u << "'s triangles fall apart";
  }
  torn.reset();
  EXPECT_EQ(torn.particles().size(), twin.particles().size());
  EXPECT_EQ(torn.baraffWitkin()->definition().triangles.size(), twin.baraffWitkin()->definition().triangles.size());
  EXPECT_EQ(torn.baraffWitkin()->definition().bends.size(), twin.baraffWitkin()->definition().bends.size());
  EXPECT_EQ(torn.tornTriangles(), 0);
}

// A Baraff–Witkin cloth of 3 x 3 particles, two cells split by the diagonal through the centre,
// whose corners 0 and 8 start far from their rest places: the four triangles at those corners are
// past the tear strain and go in the first step, which leaves the centre particle 4 with two
// triangles that share only it (a bowtie). It is split: one particle per triangle, its mass shared
// by their rest areas (equal here), each triangle and the bends across its edges with its own.
TEST(Tearing, BaraffWitkinClothSplitsTheParticleItsTornTrianglesLeftInTwoGroups)
{
  SpringNetworkDef def;
  def.name = "bowtie";
  def.shape = NetworkShape::Cloth;
  std::vector<Eigen::Vector2d> uvs;
  for (int b = 0; b < 3; ++b)
    for (int a = 0; a < 3; ++a)
    {
      uvs.emplace_back(0.1 * a, 0.1 * b);
      def.positions.emplace_back(0.1 * a, 0.1 * b, 0.0);
    }
  def.positions[0] += Eigen::Vector3d(-0.2, -0.2, 0.0);
  def.positions[8] += Eigen::Vector3d(0.2, 0.2, 0.0);
  def.masses.assign(9, 0.01);
  for (int b = 0; b < 2; ++b)
    for (int a = 0; a < 2; ++a)
    {
      const int i = 3 * b + a;
      def.triangles.emplace_back(i, i + 1, i + 4);
      def.triangles.emplace_back(i, i + 4, i + 3);
    }
  std::string error;
  ASSERT_TRUE(buildBaraffWitkin(def.positions, uvs, def.triangles, def.baraff_witkin, error)) << error;
  def.tear_strain = kTearStrain;
  def.integrator.type = kSymplecticEulerIntegrator;
  ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
  SpringNetworkBody body(def);
  const Eigen::Vector3d momentum = body.momentum();
  body.step(1e-5, noGravity());
  ASSERT_EQ(body.lastTornTriangles(), 4);
  ASSERT_EQ(body.splitParticles(), 1);
  ASSERT_EQ(body.particles().size(), 10);
  EXPECT_EQ(body.particleOrigin(9), 4);
  EXPECT_DOUBLE_EQ(body.particleMasses()[4], 0.005);
  EXPECT_DOUBLE_EQ(body.particleMasses()[9], 0.005);
  EXPECT_TRUE(body.particles().position.col(9) == body.particles().position.col(4));
  EXPECT_LT((body.momentum() - momentum).norm(), 1e-12);
  // The surface: (1, 2, 5) and (1, 5, 4) in one sheet, (3, 4, 7) and (3, 7, 6) in the other, which
  // now holds the copy in place of 4; the conditions are the same triangles.
  const std::vector<Eigen::Vector3i>& surface = body.surfaceTriangles();
  ASSERT_EQ(surface.size(), 4u);
  int holding_4 = 0, holding_9 = 0;
  for (const Eigen::Vector3i& t : surface)
  {
    const bool first_sheet = (t.array() == 1).any();
    const bool has_4 = (t.array() == 4).any(), has_9 = (t.array() == 9).any();
    EXPECT_FALSE(has_4 && has_9);
    holding_4 += has_4 ? 1 : 0;
    holding_9 += has_9 ? 1 : 0;
    if (has_4 || has_9)
    {
      EXPECT_NE(first_sheet, has_9) << t.transpose();
    }
  }
  EXPECT_EQ(holding_4, 1);
  EXPECT_EQ(holding_9, 1);
  const BaraffWitkinDef& left = body.baraffWitkin()->definition();
  ASSERT_EQ(left.triangles.size(), 4u);
  for (const BwTriangle& t : left.triangles)
  {
    EXPECT_EQ(std::count_if(surface.begin(), surface.end(),
                            [&](const Eigen::Vector3i& s) {
                              std::array<int, 3> a{s[0], s[1], s[2]}, b{t.v[0], t.v[1], t.v[2]};
                              std::sort(a.begin(), a.end());
                              std::sort(b.begin(), b.end());
                              return a == b;
                            }),
              1);
  }
  // The bends left join triangles of one sheet each: none holds both 4 and 9.
  for (const BwBend& b : left.bends)
  {
    const bool has_4 = std::find(b.v.begin(), b.v.end(), 4) != b.v.end();
    const bool has_9 = std::find(b.v.begin(), b.v.end(), 9) != b.v.end();
    EXPECT_FALSE(has_4 && has_9);
  }
  // It steps on, and a reset puts the nine particles and eight triangles back.
  for (int k = 0; k < 10; ++k)
    body.step(1e-4, noGravity());
  EXPECT_TRUE(body.particles().position.allFinite());
  body.reset();
  EXPECT_EQ(body.particles().size(), 9);
  EXPECT_EQ(body.baraffWitkin()->definition().triangles.size(), 8u);
  EXPECT_EQ(body.splitParticles(), 0);
}

// After a tear the body is the body of the springs it has left: one built from them at the same
// state steps (and tears) alike. That holds only if every spring kept its own constants and
// Jacobian blocks through the compaction. Symplectic Euler keeps no history: five steps agree bit
// for bit. Implicit Euler solved directly: one step agrees to round-off (the rebuilt body's
// pattern lacks the torn springs' zero blocks, so its factorization orders its sums otherwise).
// (CG's warm start and BDF2's previous step are history the rebuilt body does not have.) The
// gripped cloth's particles and springs are taken as a network: a cloth would also remember which
// of its edges lost their springs, to split along them (TornClothSplitsIntoAManifoldAlongItsTear).
TEST(Tearing, TornBodyStepsLikeOneBuiltFromTheSpringsLeft)
{
  for (IntegratorType type : {kSymplecticEulerIntegrator, kImplicitEulerIntegrator})
  {
    SCOPED_TRACE(toString(type));
    ClothGridDef def = grippedCloth(type);
    def.integrator.linear_solver = LinearSolverType::Direct;
    SpringNetworkDef network = buildClothGrid(def);
    network.shape = NetworkShape::Network;
    SpringNetworkBody body(network);
    // Different constants per class first, so that a spring that took another's place would show.
    ASSERT_TRUE(body.setSpringConstants(SpringClass::Shear, 300.0, 0.2).ok);
    const Environment env = noGravity();
    int step = 0;
    for (; body.tornSprings() == 0; ++step)
    {
      ASSERT_LT(step, kPullSteps) << "the cloth never tore";
      pullRightGripper(body);
      body.step(kDt, env);
    }
    SpringNetworkDef left = body.definition();
    left.springs = body.springs();
    left.triangles = body.surfaceTriangles();
    left.positions.clear();
    left.velocities.clear();
    left.masses.clear();
    for (int i = 0; i < body.particles().size(); ++i)
    {
      left.positions.push_back(body.particles().position.col(i));
      left.velocities.push_back(body.particles().velocity.col(i));
      left.masses.push_back(body.particleMasses()[i]);
    }
    SpringNetworkBody rebuilt(left);
    const bool exact = type == kSymplecticEulerIntegrator;
    for (int more = 0; more < (exact ? 5 : 1); ++more)
    {
      pullRightGripper(body);
      pullRightGripper(rebuilt);
      body.step(kDt, env);
      rebuilt.step(kDt, env);
      EXPECT_EQ(body.lastTear().springs, rebuilt.lastTear().springs) << "step " << more;
    }
    if (exact)
    {
      EXPECT_TRUE(body.particles().position == rebuilt.particles().position);
      EXPECT_TRUE(body.particles().velocity == rebuilt.particles().velocity);
    }
    else
    {
      EXPECT_LT((body.particles().position - rebuilt.particles().position).cwiseAbs().maxCoeff(), 1e-12);
      EXPECT_LT((body.particles().velocity - rebuilt.particles().velocity).cwiseAbs().maxCoeff(), 1e-9);
    }
  }
}

// A torn spring no longer holds anything: Provot's strain limit forgets it too. Two particles whose
// spring a pin tears apart fly apart once released; the limit would pull them back to 10 %.
TEST(Tearing, StrainLimitLetsGoOfTornSprings)
{
  SpringNetworkDef def = pinnedPair(0.5);
  def.strain_limit.max_strain = 0.1;
  SpringNetworkBody body(def);
  const Environment env = noGravity();
  ASSERT_TRUE(body.setPinTarget(1, Eigen::Vector3d(2.0, 0.0, 0.0)).ok);  // both ends pinned: the limit cannot hold it
  body.step(0.01, env);
  ASSERT_EQ(body.tornSprings(), 1);
  ASSERT_TRUE(body.unpin(1).ok);
  for (int n = 0; n < 10; ++n)
    body.step(0.01, env);
  EXPECT_GT(body.particles().position(0, 1), 2.0);  // it flies on at its 100 m/s
}

// Constants set at run time, then a tear, then reset(): every spring is back with the constants it
// was built with.
TEST(Tearing, ResetAfterSetConstantsAndATearRestoresTheBuiltSprings)
{
  const SpringNetworkDef def = buildClothGrid(grippedCloth(kImplicitEulerIntegrator));
  SpringNetworkBody body(def);
  ASSERT_TRUE(body.setSpringConstants(SpringClass::Stretch, 5000.0, 1.0).ok);
  const Environment env = noGravity();
  for (int step = 0; step < kPullSteps; ++step)
  {
    pullRightGripper(body);
    body.step(kDt, env);
  }
  ASSERT_GT(body.tornSprings(), 0);
  body.reset();
  ASSERT_EQ(body.springs().size(), def.springs.size());
  for (std::size_t k = 0; k < def.springs.size(); ++k)
  {
    const Spring &now = body.springs()[k], &built = def.springs[k];
    EXPECT_TRUE(now.i == built.i && now.j == built.j && now.stiffness == built.stiffness &&
                now.damping == built.damping && now.rest_length == built.rest_length)
        << "spring " << k;
  }
}

// A spring at exactly the tear strain holds; a hair past it breaks, in the step that took it there.
TEST(Tearing, BreaksPastTheTearStrainOnly)
{
  for (double stretch : {0.5, 0.5 + 1e-9})
  {
    SpringNetworkBody body(pinnedPair(0.5));
    ASSERT_TRUE(body.setPinTarget(1, Eigen::Vector3d(1.0 + stretch, 0.0, 0.0)));
    body.step(0.01, noGravity());
    EXPECT_EQ(body.tornSprings(), stretch > 0.5 ? 1 : 0) << "stretch " << stretch;
    EXPECT_EQ(body.springs().size(), stretch > 0.5 ? 0u : 1u);
  }
}

TEST(Tearing, RefusesOutOfRangeAndUnsupportedBodies)
{
  for (double bad : {-0.1, 100.5})
  {
    SpringNetworkDef def = buildClothGrid(grippedCloth(kImplicitEulerIntegrator, bad));
    const Status status = validate(def, 100000);
    EXPECT_FALSE(status);
    EXPECT_NE(status.message.find("tear_strain"), std::string::npos) << status.message;
    EXPECT_NE(status.message.find("[0, 100]"), std::string::npos) << status.message;
  }
  SpringNetworkDef rod = buildClothGrid(grippedCloth(kImplicitEulerIntegrator));
  rod.rod_bending.bends.push_back(RodBend{{0, 1, 2}, 0.1, 0.0});
  const Status status = validate(rod, 100000);
  EXPECT_FALSE(status);
  EXPECT_NE(status.message.find("rod or plate bending"), std::string::npos) << status.message;
}
