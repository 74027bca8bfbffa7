// Tearing (SpringNetworkDef::tear_strain): a spring stretched past the tear strain at the end of a
// step breaks. A cloth pulled apart by two grippers tears where its untorn twin is most strained
// and comes apart in two; a tear never adds energy; the surface left is a manifold whose every
// edge still has a spring; tearing is deterministic, and reset mends it.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <utility>
#include <vector>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/symplectic_euler.h"
#include "particle_sim/core/spring_network.h"

using namespace particle_sim::core;

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

// A flat cloth held by two grippers: the left one holds its first column, the right one its last.
ClothGridDef grippedCloth(IntegratorType integrator, double tear_strain = kTearStrain)
{
  ClothGridDef def;
  def.name = "torn";
  def.origin = {0.0, 0.0, 1.0};
  def.edge_u = {kSpacing * (kColumns - 1), 0.0, 0.0};
  def.edge_v = {0.0, kSpacing * (kRows - 1), 0.0};
  def.nu = kColumns;
  def.nv = kRows;
  def.mass = 0.2;
  for (int row = 0; row < kRows; ++row)
  {
    def.pins.push_back(gridIndex(0, row));
    def.pins.push_back(gridIndex(kColumns - 1, row));
  }
  def.integrator.type = integrator;
  def.tear_strain = tear_strain;
  return def;
}

Environment noGravity()
{
  Environment env;
  env.gravity.setZero();
  env.ground.enabled = false;
  return env;
}

// Moves the right gripper by one step of the pull.
void pullRightGripper(SpringNetworkBody& body)
{
  for (int row = 0; row < kRows; ++row)
  {
    const int index = gridIndex(kColumns - 1, row);
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

// Grippers that stop at the first tear do no more work; the tear runs on through the cloth, and
// the mechanical energy never grows (a broken spring takes its energy with it).
TEST(Tearing, ATearNeverAddsEnergy)
{
  for (IntegratorType type : {kImplicitEulerIntegrator, kSymplecticEulerIntegrator})
  {
    SCOPED_TRACE(toString(type));
    SpringNetworkBody body(buildClothGrid(grippedCloth(type)));
    const Environment env = noGravity();
    int step = 0;
    for (; body.tornSprings() == 0; ++step)
    {
      ASSERT_LT(step, kPullSteps) << "the cloth never tore";
      pullRightGripper(body);
      body.step(kDt, env);
    }
    const long long torn_while_pulling = body.tornSprings();
    double energy = mechanicalEnergy(body, env);
    for (int hold = 0; hold < 600; ++hold)
    {
      body.step(kDt, env);
      const double after = mechanicalEnergy(body, env);
      EXPECT_LE(after, energy + 1e-12 * std::abs(energy))
          << "hold step " << hold << ", " << body.lastTornSprings() << " springs torn in it";
      energy = after;
    }
    EXPECT_GT(body.tornSprings(), torn_while_pulling) << "no tear while the grippers held still";
  }
}

// The surface a tear leaves: every edge of a triangle in at most two triangles and every directed
// edge in at most one (consistently oriented), every edge of a kept triangle still joined by a
// spring, and every triangle that went had an edge with none left.
TEST(Tearing, TornSurfaceIsAManifoldWhoseEdgesAllHaveSprings)
{
  SpringNetworkBody body(buildClothGrid(grippedCloth(kImplicitEulerIntegrator)));
  const Environment env = noGravity();
  for (int step = 0; step < kPullSteps; ++step)
  {
    pullRightGripper(body);
    body.step(kDt, env);
  }
  const std::vector<Eigen::Vector3i>& surface = body.surfaceTriangles();
  const std::vector<Eigen::Vector3i>& built = body.definition().triangles;
  ASSERT_LT(surface.size(), built.size());
  ASSERT_GT(surface.size(), 0u);

  std::set<std::pair<int, int>> joined;
  for (const Spring& spring : body.springs())
    joined.insert(ordered(spring.i, spring.j));
  auto has_spring = [&](int a, int b) { return joined.count(ordered(a, b)) == 1; };
  std::map<std::pair<int, int>, int> uses, directed_uses;
  for (const Eigen::Vector3i& t : surface)
  {
    for (int c = 0; c < 3; ++c)
    {
      const int a = t[c], b = t[(c + 1) % 3];
      EXPECT_TRUE(has_spring(a, b)) << "kept edge " << a << "-" << b;
      ++uses[ordered(a, b)];
      ++directed_uses[{a, b}];
    }
  }
  for (const auto& [edge, count] : uses)
    EXPECT_LE(count, 2) << edge.first << "-" << edge.second;
  for (const auto& [edge, count] : directed_uses)
    EXPECT_EQ(count, 1) << edge.first << "->" << edge.second;

  std::set<std::array<int, 3>> kept;
  for (const Eigen::Vector3i& t : surface)
    kept.insert({t[0], t[1], t[2]});
  for (const Eigen::Vector3i& t : built)
  {
    if (kept.count({t[0], t[1], t[2]})) continue;
    EXPECT_FALSE(has_spring(t[0], t[1]) && has_spring(t[1], t[2]) && has_spring(t[2], t[0]))
        << "triangle " << t.transpose() << " went with all its springs";
  }
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

// A spring at exactly the tear strain holds; a hair past it breaks, in the step that took it there.
TEST(Tearing, BreaksPastTheTearStrainOnly)
{
  for (double stretch : {0.5, 0.5 + 1e-9})
  {
    SpringNetworkDef def;
    def.name = "pair";
    def.positions = {Eigen::Vector3d::Zero(), Eigen::Vector3d(1.0, 0.0, 0.0)};
    def.masses = {1.0, 1.0};
    def.springs = {Spring{0, 1, 1.0, 100.0, 0.0, SpringClass::Stretch}};
    def.pins = {0, 1};
    def.tear_strain = 0.5;
    SpringNetworkBody body(def);
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
    EXPECT_NE(status.message.find("100"), std::string::npos) << status.message;
  }
  ClothGridDef bw = grippedCloth(kImplicitEulerIntegrator);
  bw.model = ClothModel::BaraffWitkin;
  bw.stretch = ClothConstants::unset(ClothModel::BaraffWitkin, SpringClass::Stretch);
  bw.shear = ClothConstants::unset(ClothModel::BaraffWitkin, SpringClass::Shear);
  bw.bend = ClothConstants::unset(ClothModel::BaraffWitkin, SpringClass::Bend);
  const Status status = validate(buildClothGrid(bw), 100000);
  EXPECT_FALSE(status);
  EXPECT_NE(status.message.find("Baraff"), std::string::npos) << status.message;
}
