// Jelly: buildJelly lays out the lattice, its stretch (axis), shear (face and body diagonal) and
// bend (two apart) springs at their initial lengths and an outward-facing boundary surface,
// validate refuses every bad field by name, a jelly cube dropped on the ground never goes below
// it and comes to rest there with its shape, and without external forces its momentum is
// conserved and a uniform motion is a rigid translation.

#include "particle_sim/core/builders/jelly.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/symplectic_euler.h"
#include "particle_sim/core/integrators/verlet.h"
#include "particle_sim/core/world.h"
#include "test_helpers.h"

using namespace particle_sim::core;

using particle_sim_test::countClass;
using particle_sim_test::kNaN;
using particle_sim_test::mentions;

namespace
{

JellyDef boxJelly(int nx, int ny, int nz)
{
  JellyDef def;
  def.name = "jelly";
  def.origin = {0.5, -1.0, 0.2};
  def.size = {0.6, 0.4, 0.5};
  def.nx = nx;
  def.ny = ny;
  def.nz = nz;
  def.mass = 2.0;
  def.stretch = {1500.0, 0.8};
  def.shear = {700.0, 0.4};
  def.bend = {150.0, 0.1};
  return def;
}

// Lattice coordinates (a, b, c) of index (c ny + b) nx + a.
std::array<int, 3> lattice(int index, int nx, int ny)
{
  return {index % nx, (index / nx) % ny, index / (nx * ny)};
}

double maxSpeed(const SpringNetworkBody& body)
{
  const ParticlePool& p = body.particles();
  return p.velocity.leftCols(p.size()).colwise().norm().maxCoeff();
}
}  // namespace

// ---------------------------------------------------------------------------------------------
// Layout

TEST(Jelly, BuildPlacesTheLatticeWithEqualMassesAndTheInitialVelocity)
{
  JellyDef def = boxJelly(4, 3, 5);
  def.velocity = {0.5, -0.25, 2.0};
  def.pins = {0, -1};
  def.integrator.type = kVerletIntegrator;
  def.strain_limit.max_strain = 0.2;
  ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
  const SpringNetworkDef net = buildJelly(def);
  EXPECT_EQ(net.name, "jelly");
  EXPECT_EQ(net.shape, NetworkShape::Jelly);
  EXPECT_EQ(net.integrator.type, kVerletIntegrator);
  EXPECT_EQ(net.strain_limit.max_strain, 0.2);
  ASSERT_EQ(net.positions.size(), 60u);
  ASSERT_EQ(net.masses.size(), 60u);
  ASSERT_EQ(net.velocities.size(), 60u);
  double total = 0.0;
  for (int c = 0; c < 5; ++c)
    for (int b = 0; b < 3; ++b)
      for (int a = 0; a < 4; ++a)
      {
        const int index = (c * 3 + b) * 4 + a;
        const Eigen::Vector3d expected = def.origin + Eigen::Vector3d(0.6 * a / 3.0, 0.4 * b / 2.0, 0.5 * c / 4.0);
        EXPECT_LE((net.positions[index] - expected).norm(), 1e-12)
            << "particle (" << a << ", " << b << ", " << c << ")";
        EXPECT_EQ(net.velocities[index], def.velocity);
        EXPECT_NEAR(net.masses[index], 2.0 / 60, 1e-15);
        total += net.masses[index];
      }
  EXPECT_NEAR(total, 2.0, 1e-12);
  EXPECT_LE((net.positions.back() - (def.origin + def.size)).norm(), 1e-12);
  std::vector<int> pins = net.pins;
  std::sort(pins.begin(), pins.end());
  EXPECT_EQ(pins, (std::vector<int>{0, 59}));
  EXPECT_TRUE(validate(net, 100).ok) << validate(net, 100).message;
}

TEST(Jelly, SpringCountsPerClassMatchTheLatticeNeighbourCounts)
{
  const std::array<int, 3> sizes[] = {{2, 2, 2}, {3, 2, 2}, {2, 3, 4}, {4, 4, 4}, {5, 3, 2}, {3, 4, 5}};
  for (const std::array<int, 3>& size : sizes)
  {
    for (double bend_stiffness : {150.0, 0.0})
    {
      const int nx = size[0], ny = size[1], nz = size[2];
      JellyDef def = boxJelly(nx, ny, nz);
      def.bend.stiffness = bend_stiffness;
      ASSERT_TRUE(validate(def, 1000).ok) << validate(def, 1000).message;
      const SpringNetworkDef net = buildJelly(def);
      const std::string where = std::to_string(nx) + "x" + std::to_string(ny) + "x" + std::to_string(nz) + " bend " +
                                std::to_string(bend_stiffness);

      // Axis neighbours: along x there are (nx − 1) ny nz pairs, and likewise along y and z.
      const int stretch = (nx - 1) * ny * nz + nx * (ny - 1) * nz + nx * ny * (nz - 1);
      // Two diagonals per face of every cell-face plane, four body diagonals per cell.
      const int face_diagonals = 2 * ((nx - 1) * (ny - 1) * nz + nx * (ny - 1) * (nz - 1) + (nx - 1) * ny * (nz - 1));
      const int body_diagonals = 4 * (nx - 1) * (ny - 1) * (nz - 1);
      // Two apart along an axis: (nx − 2) ny nz along x, and so on.
      const int bend =
          bend_stiffness > 0.0
              ? (std::max(0, nx - 2) * ny * nz + nx * std::max(0, ny - 2) * nz + nx * ny * std::max(0, nz - 2))
              : 0;
      EXPECT_EQ(countClass(net.springs, SpringClass::Stretch), stretch) << where;
      EXPECT_EQ(countClass(net.springs, SpringClass::Shear), face_diagonals + body_diagonals) << where;
      EXPECT_EQ(countClass(net.springs, SpringClass::Bend), bend) << where;

      // Each spring once, joining the lattice offsets of its class at its initial length.
      std::set<std::pair<int, int>> seen;
      int face = 0, body = 0;
      for (const Spring& s : net.springs)
      {
        ASSERT_TRUE(s.i >= 0 && s.i < nx * ny * nz && s.j >= 0 && s.j < nx * ny * nz) << where;
        EXPECT_TRUE(seen.insert({std::min(s.i, s.j), std::max(s.i, s.j)}).second) << where << ": duplicate";
        EXPECT_NEAR(s.rest_length, (net.positions[s.j] - net.positions[s.i]).norm(), 1e-12) << where;
        const std::array<int, 3> li = lattice(s.i, nx, ny), lj = lattice(s.j, nx, ny);
        std::array<int, 3> d;
        for (int k = 0; k < 3; ++k)
          d[k] = std::abs(li[k] - lj[k]);
        const int ones = static_cast<int>(std::count(d.begin(), d.end(), 1));
        const int twos = static_cast<int>(std::count(d.begin(), d.end(), 2));
        const int zeros = static_cast<int>(std::count(d.begin(), d.end(), 0));
        switch (s.spring_class)
        {
          case SpringClass::Stretch:
            EXPECT_TRUE(ones == 1 && zeros == 2) << where;
            EXPECT_EQ(s.stiffness, 1500.0);
            EXPECT_EQ(s.damping, 0.8);
            break;
          case SpringClass::Shear:
            EXPECT_TRUE((ones == 2 && zeros == 1) || ones == 3) << where;
            face += ones == 2;
            body += ones == 3;
            EXPECT_EQ(s.stiffness, 700.0);
            EXPECT_EQ(s.damping, 0.4);
            break;
          case SpringClass::Bend:
            EXPECT_TRUE(twos == 1 && zeros == 2) << where;
            EXPECT_EQ(s.stiffness, 150.0);
            EXPECT_EQ(s.damping, 0.1);
            break;
        }
      }
      EXPECT_EQ(face, face_diagonals) << where;
      EXPECT_EQ(body, body_diagonals) << where;
    }
  }
}

TEST(Jelly, SurfaceTrianglesCoverTheBoundaryFacingOutwards)
{
  const std::array<int, 3> sizes[] = {{2, 2, 2}, {4, 3, 5}, {3, 3, 3}};
  for (const std::array<int, 3>& size : sizes)
  {
    const int nx = size[0], ny = size[1], nz = size[2];
    const JellyDef def = boxJelly(nx, ny, nz);
    const SpringNetworkDef net = buildJelly(def);
    const std::string where = std::to_string(nx) + "x" + std::to_string(ny) + "x" + std::to_string(nz);
    ASSERT_EQ(static_cast<int>(net.triangles.size()),
              4 * ((nx - 1) * (ny - 1) + (ny - 1) * (nz - 1) + (nx - 1) * (nz - 1)))
        << where;

    const Eigen::Vector3d centre = def.origin + 0.5 * def.size;
    std::vector<bool> on_surface(net.positions.size(), false);
    std::set<std::vector<int>> unique;
    double area = 0.0;
    for (const Eigen::Vector3i& t : net.triangles)
    {
      ASSERT_TRUE((t.array() >= 0).all() && (t.array() < nx * ny * nz).all()) << where;
      const Eigen::Vector3d x0 = net.positions[t[0]], x1 = net.positions[t[1]], x2 = net.positions[t[2]];
      const Eigen::Vector3d area_normal = 0.5 * (x1 - x0).cross(x2 - x0);
      EXPECT_GT(area_normal.dot((x0 + x1 + x2) / 3.0 - centre), 0.0) << where << ": triangle faces inwards";
      // Flat on one face of the box: the normal is along a single axis.
      Eigen::Index axis = 0;
      area_normal.cwiseAbs().maxCoeff(&axis);
      EXPECT_LE((area_normal - area_normal[axis] * Eigen::Vector3d::Unit(axis)).norm(), 1e-12 * area_normal.norm());
      area += area_normal.norm();
      for (int c = 0; c < 3; ++c)
      {
        const std::array<int, 3> l = lattice(t[c], nx, ny);
        const bool boundary = l[0] == 0 || l[0] == nx - 1 || l[1] == 0 || l[1] == ny - 1 || l[2] == 0 || l[2] == nz - 1;
        EXPECT_TRUE(boundary) << where << ": interior particle " << t[c] << " in a surface triangle";
        on_surface[t[c]] = true;
      }
      std::vector<int> key = {t[0], t[1], t[2]};
      std::sort(key.begin(), key.end());
      EXPECT_TRUE(unique.insert(key).second) << where << ": triangle listed twice";
    }
    // The triangles tile the box's six faces exactly, and every boundary particle is on them.
    const Eigen::Vector3d s = def.size;
    EXPECT_NEAR(area, 2.0 * (s.x() * s.y() + s.y() * s.z() + s.x() * s.z()), 1e-12) << where;
    const int interior = std::max(0, nx - 2) * std::max(0, ny - 2) * std::max(0, nz - 2);
    EXPECT_EQ(static_cast<int>(std::count(on_surface.begin(), on_surface.end(), true)), nx * ny * nz - interior)
        << where;
  }
}

TEST(Jelly, ValidateRefusesBadFieldsNamingThem)
{
  const JellyDef good = boxJelly(3, 4, 5);
  ASSERT_TRUE(validate(good, 60).ok) << validate(good, 60).message;  // exactly at the cap

  struct Case
  {
    const char* what;
    void (*edit)(JellyDef&);
    std::vector<std::string> words;
  };
  const Case cases[] = {
      {"zero size", [](JellyDef& d) { d.size.y() = 0.0; }, {"size[1]", "0"}},
      {"negative size", [](JellyDef& d) { d.size.z() = -0.5; }, {"size[2]", "-0.5"}},
      {"NaN size", [](JellyDef& d) { d.size.x() = kNaN; }, {"size[0]"}},
      {"nx < 2", [](JellyDef& d) { d.nx = 1; }, {"resolution[0]", "1"}},
      {"ny < 2", [](JellyDef& d) { d.ny = 0; }, {"resolution[1]", "0"}},
      {"nz < 2", [](JellyDef& d) { d.nz = -3; }, {"resolution[2]", "-3"}},
      {"negative stretch stiffness", [](JellyDef& d) { d.stretch.stiffness = -1.0; }, {"stretch.stiffness", "-1"}},
      {"negative shear stiffness", [](JellyDef& d) { d.shear.stiffness = -2.0; }, {"shear.stiffness", "-2"}},
      {"negative bend stiffness", [](JellyDef& d) { d.bend.stiffness = -3.0; }, {"bend.stiffness", "-3"}},
      {"negative bend damping", [](JellyDef& d) { d.bend.damping = -0.1; }, {"bend.damping"}},
      {"too many particles", [](JellyDef& d) { d.nz = 6; }, {"resolution", "72", "60"}},
      {"zero mass", [](JellyDef& d) { d.mass = 0.0; }, {"mass"}},
      {"NaN origin", [](JellyDef& d) { d.origin.y() = kNaN; }, {"origin"}},
      {"NaN velocity", [](JellyDef& d) { d.velocity.z() = kNaN; }, {"velocity"}},
      {"pin out of range", [](JellyDef& d) { d.pins = {60}; }, {"pins[0]", "60"}},
      {"negative max_strain", [](JellyDef& d) { d.strain_limit.max_strain = -1.0; }, {"max_strain"}},
      {"no strain-limit pass", [](JellyDef& d) { d.strain_limit.iterations = 0; }, {"strain_iterations"}},
      {"bad name", [](JellyDef& d) { d.name = "_hidden"; }, {"name"}},
  };
  for (const Case& c : cases)
  {
    JellyDef def = good;
    c.edit(def);
    const Status status = validate(def, 60);
    EXPECT_FALSE(status.ok) << c.what;
    for (const std::string& word : c.words)
      EXPECT_TRUE(mentions(status, word)) << c.what << ": " << status.message;
  }

  WorldDef world_def;
  world_def.max_particles_per_body = 60;
  World world(world_def);
  JellyDef big = good;
  big.nx = 4;
  EXPECT_FALSE(world.addJelly(big).ok);
  EXPECT_TRUE(world.bodies().empty());
  EXPECT_TRUE(world.addJelly(good).ok);
  ASSERT_NE(world.findSpringBody("jelly"), nullptr);
  EXPECT_EQ(world.findSpringBody("jelly")->shape(), NetworkShape::Jelly);
}

// ---------------------------------------------------------------------------------------------
// Dynamics

namespace
{
struct DropResult
{
  double lowest_ever = std::numeric_limits<double>::infinity();  // lowest particle over every step
  double lowest_end = 0.0;
  double highest_end = 0.0;
  Eigen::Vector3d extent_end = Eigen::Vector3d::Zero();  // bounding box size at the end
  Eigen::Vector3d centre_end = Eigen::Vector3d::Zero();  // mean position at the end
  double max_speed_end = 0.0;
  double moved_last = 0.0;                                   // largest displacement of a particle over the last 0.25 s
  double fell_to = std::numeric_limits<double>::infinity();  // lowest mean height reached
  bool frozen = false;
};

DropResult dropJelly(IntegratorType type, double dt, double duration)
{
  WorldDef world_def;
  world_def.dt = dt;
  EXPECT_TRUE(validate(world_def).ok);
  World world(world_def);
  JellyDef def;
  def.name = "cube";
  def.origin = {-0.15, -0.15, 0.5};
  def.size = {0.3, 0.3, 0.3};
  def.nx = def.ny = def.nz = 4;
  def.mass = 1.0;
  def.integrator.type = type;
  EXPECT_TRUE(world.addJelly(def).ok);
  const SpringNetworkBody& body = *world.findSpringBody("cube");

  DropResult r;
  const int steps = static_cast<int>(std::lround(duration / dt));
  const int last = static_cast<int>(std::lround(0.25 / dt));
  Eigen::Matrix3Xd before = body.particles().position;
  for (int k = 0; k < steps; ++k)
  {
    if (k == steps - last) before = body.particles().position;
    world.step();
    const ParticlePool& p = body.particles();
    r.lowest_ever = std::min(r.lowest_ever, p.position.row(2).head(p.size()).minCoeff());
    r.fell_to = std::min(r.fell_to, p.position.row(2).head(p.size()).mean());
  }
  const ParticlePool& p = body.particles();
  const Eigen::Matrix3Xd x = p.position.leftCols(p.size());
  r.lowest_end = x.row(2).minCoeff();
  r.highest_end = x.row(2).maxCoeff();
  r.extent_end = x.rowwise().maxCoeff() - x.rowwise().minCoeff();
  r.centre_end = x.rowwise().mean();
  r.max_speed_end = maxSpeed(body);
  r.moved_last = (x - before.leftCols(p.size())).colwise().norm().maxCoeff();
  r.frozen = body.frozen();
  return r;
}

void expectRestsOnTheGround(const DropResult& r, const std::string& where)
{
  EXPECT_FALSE(r.frozen) << where;
  EXPECT_GE(r.lowest_ever, -1e-9) << where << ": a particle went below the ground";
  // It fell: its mean height went from 0.65 m to about half its size, 0.15 m.
  EXPECT_LT(r.fell_to, 0.2) << where;
  // It rests on the ground...
  EXPECT_GE(r.lowest_end, 0.0) << where;
  EXPECT_LT(r.lowest_end, 0.01) << where;
  EXPECT_LT(r.moved_last, 1e-3) << where << ": still moving";
  // A body lying still reports small speeds too (0.05 m/s would carry a particle 1.25 cm in 0.25 s).
  EXPECT_LT(r.max_speed_end, 0.05) << where << ": particles that moved at most " << r.moved_last
                                   << " m in the last 0.25 s report speeds up to " << r.max_speed_end << " m/s";
  // ... in its shape (the 0.3 m cube sags a little under its weight) ...
  for (int axis = 0; axis < 3; ++axis)
    EXPECT_NEAR(r.extent_end[axis], 0.3, 0.045) << where << ": axis " << axis;
  EXPECT_NEAR(r.highest_end - r.lowest_end, 0.3, 0.045) << where;
  // ... where it fell: straight down.
  EXPECT_LE(r.centre_end.head<2>().norm(), 0.01) << where;
}
}  // namespace

TEST(JellyDrop, ImplicitEulerCubeFallsAndComesToRestOnTheGroundInShape)
{
  expectRestsOnTheGround(dropJelly(kImplicitEulerIntegrator, 1.0 / 200.0, 3.0), "implicit Euler dt = 1/200");
}

TEST(JellyDrop, SymplecticEulerCubeFallsAndComesToRestOnTheGroundInShape)
{
  expectRestsOnTheGround(dropJelly(kSymplecticEulerIntegrator, 5e-4, 3.0), "symplectic Euler dt = 5e-4");
}

TEST(JellyFree, UniformVelocityIsARigidTranslationWithConstantMomentum)
{
  for (IntegratorType type : {kSymplecticEulerIntegrator, kImplicitEulerIntegrator})
  {
    JellyDef def = boxJelly(3, 4, 3);
    def.velocity = {1.0, -2.0, 0.5};
    def.integrator.type = type;
    ASSERT_TRUE(validate(def, 100).ok);
    SpringNetworkBody body(buildJelly(def));
    Environment env;
    env.gravity.setZero();
    env.ground.enabled = false;
    const Eigen::Matrix3Xd start = body.particles().position;
    const double dt = 1e-3;
    const int steps = 300;
    for (int k = 0; k < steps; ++k)
      body.step(dt, env);
    ASSERT_FALSE(body.frozen()) << toString(type);

    EXPECT_LE((body.momentum() - def.mass * def.velocity).norm(), 1e-12) << toString(type);
    const ParticlePool& p = body.particles();
    const double t = steps * dt;
    double worst_position = 0.0, worst_distance = 0.0;
    for (int i = 0; i < p.size(); ++i)
    {
      worst_position = std::max(worst_position, (p.position.col(i) - (start.col(i) + t * def.velocity)).norm());
      EXPECT_LE((p.velocity.col(i) - def.velocity).norm(), 1e-12) << toString(type) << " particle " << i;
      for (int j = i + 1; j < p.size(); ++j)
        worst_distance = std::max(worst_distance, std::abs((p.position.col(j) - p.position.col(i)).norm() -
                                                           (start.col(j) - start.col(i)).norm()));
    }
    EXPECT_LE(worst_position, 1e-12) << toString(type);
    EXPECT_LE(worst_distance, 1e-12) << toString(type);
  }
}

TEST(JellyFree, InternalForcesConserveMomentumUnderRandomVelocities)
{
  for (IntegratorType type : {kSymplecticEulerIntegrator, kImplicitEulerIntegrator})
  {
    const JellyDef def = boxJelly(4, 3, 3);
    SpringNetworkDef net = buildJelly(def);
    net.integrator.type = type;
    net.integrator.cg_tolerance = 1e-12;
    std::mt19937 rng(7);
    std::normal_distribution<double> normal(0.0, 0.5);
    net.velocities.assign(net.positions.size(), Eigen::Vector3d::Zero());
    for (Eigen::Vector3d& v : net.velocities)
      v = Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    SpringNetworkBody body(net);
    const Eigen::Vector3d initial = body.momentum();
    ASSERT_GT(initial.norm(), 0.1);
    Environment env;
    env.gravity.setZero();
    env.ground.enabled = false;
    double largest_deformation = 0.0;
    for (int k = 0; k < 500; ++k)
    {
      body.step(1e-3, env);
      largest_deformation = std::max(largest_deformation, body.maxStrain());
      ASSERT_LE((body.momentum() - initial).norm(), 1e-9 * (1.0 + initial.norm())) << toString(type) << " step " << k;
    }
    ASSERT_FALSE(body.frozen()) << toString(type);
    EXPECT_GT(largest_deformation, 1e-3) << toString(type) << ": the jelly should wobble";
  }
}

// A jelly that blows up under symplectic Euler even at its substep cap is frozen, and reports the
// method that ran (it used to report implicit_euler, the value before any step) and why it froze.
TEST(JellyFrozen, ReportsTheIntegratorThatRanAndItsReason)
{
  WorldDef world_def;
  world_def.dt = 0.01;
  World world(world_def);
  JellyDef def;
  def.name = "cube";
  def.nx = def.ny = def.nz = 3;
  def.mass = 0.01;
  def.stretch = {1e9, 0.0};
  def.velocity = {0.0, 0.0, -5.0};
  def.origin = {-0.25, -0.25, 0.01};
  def.integrator.type = kSymplecticEulerIntegrator;
  def.integrator.max_substeps = 1;
  ASSERT_TRUE(world.addJelly(def).ok);
  const SpringNetworkBody& body = *world.findSpringBody("cube");
  for (int k = 0; k < 50 && !body.frozen(); ++k)
    world.step();
  ASSERT_TRUE(body.frozen()) << "the guard should have frozen this jelly";
  EXPECT_EQ(body.lastIntegrator(), kSymplecticEulerIntegrator);
  EXPECT_NE(body.frozenReason().find("symplectic_euler blew up"), std::string::npos) << body.frozenReason();
}
