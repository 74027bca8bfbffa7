// Baraff–Witkin cloth as a body: its forces are the negative gradient of its energy, zero at rest
// and under rigid motion; a stretched sheet relaxes to its rest size and a folded one to its rest
// angle; a stiff hanging cloth is stable at dt = 1/60 and converges as dt shrinks; the same scene
// runs with both cloth models.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/world.h"
#include "particle_sim/scene/scene.h"
#include "test_helpers.h"

using namespace particle_sim::core;
using particle_sim_test::noGravity;

namespace
{
ClothGridDef bwSheet(int n = 6)
{
  ClothGridDef def;
  def.name = "bw";
  def.model = ClothModel::BaraffWitkin;
  def.origin = {0, 0, 1};
  def.edge_u = {1, 0, 0};
  def.edge_v = {0, 0.8, 0};
  def.nu = n;
  def.nv = n;
  def.mass = 0.2;
  def.stretch = {1000.0, 1.0};
  def.shear = {100.0, 0.1};
  def.bend = {0.01, 1e-4};
  return def;
}

double sheetArea(const ParticlePool& p, const std::vector<Eigen::Vector3i>& triangles)
{
  double area = 0.0;
  for (const auto& t : triangles)
    area +=
        0.5 * (p.position.col(t[1]) - p.position.col(t[0])).cross(p.position.col(t[2]) - p.position.col(t[0])).norm();
  return area;
}
}  // namespace

TEST(BaraffWitkinCloth, GridCarriesTrianglesAndBendsButNoSprings)
{
  const SpringNetworkDef net = buildClothGrid(bwSheet(5));
  EXPECT_TRUE(net.springs.empty());
  ASSERT_NE(net.baraff_witkin.triangles.size(), 0u);
  EXPECT_EQ(net.baraff_witkin.triangles.size(), 2u * 4u * 4u);
  // Interior edges of a 4 x 4 cell grid split into triangles: the 16 diagonals, and the 3 inner
  // rows and 3 inner columns of 4 edges each.
  EXPECT_EQ(net.baraff_witkin.bends.size(), 16u + 3u * 4u + 3u * 4u);
  for (const BwBend& b : net.baraff_witkin.bends)
    EXPECT_NEAR(b.rest_angle, 0.0, 1e-12);
  double area = 0.0;
  for (const BwTriangle& t : net.baraff_witkin.triangles)
    area += t.area;
  EXPECT_NEAR(area, 0.8, 1e-12);  // the rest (u, v) sheet is the 1 m x 0.8 m start
}

TEST(BaraffWitkinCloth, ForcesAreTheNegativeEnergyGradientAndVanishAtRest)
{
  SpringNetworkBody body(buildClothGrid(bwSheet(4)));
  const Environment env = noGravity();
  Eigen::Matrix3Xd force(3, body.particles().size()), zero = Eigen::Matrix3Xd::Zero(3, body.particles().size());
  body.computeForces(body.particles().position, zero, env.gravity, force);
  EXPECT_LT(force.cwiseAbs().maxCoeff(), 1e-10) << "force at rest";

  // Deform randomly; f = −∂E/∂x by central differences of the body's potential energy.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal(0.0, 0.05);
  Eigen::Matrix3Xd x = body.particles().position;
  for (int i = 0; i < x.cols(); ++i)
    x.col(i) += Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  const BaraffWitkinModel& model = *body.baraffWitkin();
  model.addForces(x, zero, force.setZero());
  const double h = 1e-6;
  double worst = 0.0;
  for (int i = 0; i < x.cols(); ++i)
    for (int a = 0; a < 3; ++a)
    {
      Eigen::Matrix3Xd plus = x, minus = x;
      plus(a, i) += h;
      minus(a, i) -= h;
      const double numeric = -(model.energy(plus) - model.energy(minus)) / (2 * h);
      worst = std::max(worst, std::abs(numeric - force(a, i)) / (1.0 + std::abs(force(a, i))));
    }
  EXPECT_LT(worst, 1e-5);
}

TEST(BaraffWitkinCloth, RigidMotionChangesNoEnergyAndRotatesTheForces)
{
  SpringNetworkBody body(buildClothGrid(bwSheet(4)));
  const BaraffWitkinModel& model = *body.baraffWitkin();
  std::mt19937_64 rng(6);
  std::normal_distribution<double> normal(0.0, 0.05);
  Eigen::Matrix3Xd x = body.particles().position;
  for (int i = 0; i < x.cols(); ++i)
    x.col(i) += Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(1.1, Eigen::Vector3d(-1, 2, 0.5).normalized()).toRotationMatrix();
  const Eigen::Matrix3Xd moved = (rotation * x).colwise() + Eigen::Vector3d(3, -1, 2);
  EXPECT_NEAR(model.energy(moved), model.energy(x), 1e-12 * (1.0 + model.energy(x)));
  const Eigen::Matrix3Xd zero = Eigen::Matrix3Xd::Zero(3, x.cols());
  Eigen::Matrix3Xd f = zero, f_moved = zero;
  model.addForces(x, zero, f);
  model.addForces(moved, zero, f_moved);
  EXPECT_LT((rotation * f - f_moved).cwiseAbs().maxCoeff(), 1e-9 * (1.0 + f.cwiseAbs().maxCoeff()));
  // The sum of internal forces is zero (momentum) and so is their torque.
  EXPECT_LT(f.rowwise().sum().norm(), 1e-9);
}

TEST(BaraffWitkinCloth, StretchedSheetRelaxesToItsRestSize)
{
  ClothGridDef def = bwSheet(6);
  def.integrator.type = kImplicitEulerIntegrator;
  SpringNetworkDef net = buildClothGrid(def);
  const double rest_area = sheetArea(SpringNetworkBody(net).particles(), net.triangles);
  for (Eigen::Vector3d& x : net.positions)
    x = Eigen::Vector3d(1.3 * x.x(), 1.2 * x.y(), x.z());  // stretched start
  SpringNetworkBody body(net);
  ASSERT_GT(sheetArea(body.particles(), net.triangles), 1.5 * rest_area);
  const Environment env = noGravity();
  for (int k = 0; k < 600; ++k)
    body.step(1.0 / 100.0, env);
  ASSERT_FALSE(body.frozen()) << body.frozenReason();
  EXPECT_NEAR(sheetArea(body.particles(), net.triangles), rest_area, 1e-3 * rest_area);
  EXPECT_LT(body.maxStrain(), 1e-3);
}

TEST(BaraffWitkinCloth, FoldedSheetRelaxesToItsRestAngle)
{
  // A strip of two cells folded 60 degrees about its middle row: bending unfolds it to flat (the
  // rest angle 0).
  ClothGridDef def = bwSheet(3);
  def.bend = {0.5, 0.01};
  SpringNetworkDef net = buildClothGrid(def);
  for (Eigen::Vector3d& x : net.positions)
  {
    if (x.y() > 0.4 + 1e-9)  // the far half, rotated about the line y = 0.4, z = 1
    {
      const double r = x.y() - 0.4;
      x = Eigen::Vector3d(x.x(), 0.4 + r * std::cos(M_PI / 3), 1.0 + r * std::sin(M_PI / 3));
    }
  }
  SpringNetworkBody body(net);
  const BaraffWitkinModel& model = *body.baraffWitkin();
  auto largestAngle = [&] {
    double angle = 0.0;
    for (const BwBend& b : model.definition().bends)
    {
      Eigen::Matrix<double, 3, 4> x;
      for (int m = 0; m < 4; ++m)
        x.col(m) = body.particles().position.col(b.v[m]);
      angle = std::max(angle, std::abs(dihedralAngle(x)));
    }
    return angle;
  };
  ASSERT_GT(largestAngle(), 1.0);
  const Environment env = noGravity();
  for (int k = 0; k < 2000; ++k)
    body.step(1.0 / 200.0, env);
  ASSERT_FALSE(body.frozen()) << body.frozenReason();
  EXPECT_LT(largestAngle(), 0.01);
}

TEST(BaraffWitkinCloth, StiffHangingClothIsStableAtOneSixtiethAndConvergesAsDtShrinks)
{
  // Pinned at two corners, stiff stretch; the free corner's position after 0.5 s.
  auto freeCorner = [](double dt) {
    ClothGridDef def = bwSheet(6);
    def.stretch = {20000.0, 20.0};
    def.named_pins = {"corner_00", "corner_10"};
    def.integrator.cg_tolerance = 1e-9;
    def.integrator.cg_max_iterations = 2000;
    SpringNetworkBody body(buildClothGrid(def));
    Environment env;
    env.ground.enabled = false;
    const int steps = static_cast<int>(std::lround(0.5 / dt));
    for (int k = 0; k < steps; ++k)
      body.step(dt, env);
    EXPECT_FALSE(body.frozen()) << body.frozenReason();
    EXPECT_LT(body.maxStrain(), 0.05) << "dt " << dt;  // stiff: it hangs without stretching much
    return Eigen::Vector3d(body.particles().position.col(35));
  };
  const Eigen::Vector3d reference = freeCorner(1.0 / 1920.0);
  const double e60 = (freeCorner(1.0 / 60.0) - reference).norm();
  const double e120 = (freeCorner(1.0 / 120.0) - reference).norm();
  const double e240 = (freeCorner(1.0 / 240.0) - reference).norm();
  EXPECT_TRUE(std::isfinite(e60));
  EXPECT_LT(e120, e60);
  EXPECT_LT(e240, e120);
  EXPECT_LT(e240, 0.75 * e120);  // first order: about halving
}

TEST(BaraffWitkinCloth, SameSceneRunsWithBothClothModels)
{
  for (const char* model : {"springs", "baraff_witkin"})
  {
    particle_sim::scene::SceneDef def;
    const std::string text = std::string(
                                 "world: {dt: 0.01}\n"
                                 "bodies:\n  - {name: c, kind: cloth, model: ") +
                             model + ", resolution: [8, 8], pins: [corner_00, corner_10]}\n";
    const Status parsed = particle_sim::scene::parseScene(text, "both.yaml", def);
    ASSERT_TRUE(parsed.ok) << parsed.message;
    std::unique_ptr<World> world;
    ASSERT_TRUE(particle_sim::scene::buildWorld(def, world).ok);
    for (int k = 0; k < 100; ++k)
      world->step();
    const SpringNetworkBody& body = *world->findSpringBody("c");
    EXPECT_FALSE(body.frozen()) << model;
    EXPECT_LT(body.particles().position(2, 63), 1.9) << model << ": the free corner fell";
    EXPECT_EQ(body.baraffWitkin() != nullptr, std::string(model) == "baraff_witkin");
  }
}

TEST(BaraffWitkinCloth, SpringConstantsChangeTheConditionsAndMeshesNeedTextureCoordinates)
{
  SpringNetworkBody body(buildClothGrid(bwSheet(4)));
  ASSERT_TRUE(body.hasSpringClass(SpringClass::Shear));
  ASSERT_TRUE(body.setSpringConstants(SpringClass::Shear, 7.0, 0.5).ok);
  EXPECT_EQ(body.baraffWitkin()->constants(SpringClass::Shear).stiffness, 7.0);
  EXPECT_EQ(body.baraffWitkin()->constants(SpringClass::Stretch).stiffness, 1000.0);
  body.reset();
  EXPECT_EQ(body.baraffWitkin()->constants(SpringClass::Shear).stiffness, 100.0);

  MeshClothDef mesh;
  mesh.name = "m";
  mesh.model = ClothModel::BaraffWitkin;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles = {{0, 1, 2}};
  const Status refused = validate(mesh, 100);
  EXPECT_FALSE(refused.ok);
  EXPECT_NE(refused.message.find("needs texture coordinates"), std::string::npos) << refused.message;
  mesh.uvs = {{0, 0}, {2, 0}, {0, 2}};  // scaled to the mesh's area when built
  ASSERT_TRUE(validate(mesh, 100).ok);
  SpringNetworkBody from_mesh(buildMeshCloth(mesh));
  EXPECT_NEAR(from_mesh.baraffWitkin()->definition().triangles[0].area, 0.5, 1e-12);
  EXPECT_LT(from_mesh.maxStrain(), 1e-12);  // starts at rest
  mesh.uvs = {{0, 0}, {1, 1}, {2, 2}};
  EXPECT_NE(validate(mesh, 100).message.find("degenerate"), std::string::npos);
}

// The Baraff–Witkin defaults are defined once: a C++ caller choosing the model through the
// definition's constructor, a scene file and BaraffWitkinDef all get the documented constants
// (stretch 1000 N/m, shear 100 N/m, bend 0.005 N·m), never the spring cloth's 20 N/m bend.
TEST(BaraffWitkinDefaults, GridMeshSceneAndModelAgreeOnTheDocumentedConstants)
{
  const SpringConstants stretch{1000.0, 1.0}, shear{100.0, 0.1}, bend{0.005, 5e-5};
  auto expectConstants = [&](const BaraffWitkinModel& model, const std::string& where) {
    EXPECT_EQ(model.constants(SpringClass::Stretch).stiffness, stretch.stiffness) << where;
    EXPECT_EQ(model.constants(SpringClass::Stretch).damping, stretch.damping) << where;
    EXPECT_EQ(model.constants(SpringClass::Shear).stiffness, shear.stiffness) << where;
    EXPECT_EQ(model.constants(SpringClass::Shear).damping, shear.damping) << where;
    EXPECT_EQ(model.constants(SpringClass::Bend).stiffness, bend.stiffness) << where;
    EXPECT_EQ(model.constants(SpringClass::Bend).damping, bend.damping) << where;
  };

  World world{WorldDef{}};
  ClothGridDef grid(ClothModel::BaraffWitkin);
  grid.name = "grid";
  ASSERT_TRUE(world.addClothGrid(grid).ok);
  ASSERT_NE(world.findSpringBody("grid")->baraffWitkin(), nullptr);
  expectConstants(*world.findSpringBody("grid")->baraffWitkin(), "ClothGridDef(BaraffWitkin)");

  MeshClothDef mesh(ClothModel::BaraffWitkin);
  mesh.name = "mesh";
  mesh.vertices = {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  mesh.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  ASSERT_TRUE(world.addMeshCloth(mesh).ok);
  expectConstants(*world.findSpringBody("mesh")->baraffWitkin(), "MeshClothDef(BaraffWitkin)");

  particle_sim::scene::SceneDef scene;
  ASSERT_TRUE(
      particle_sim::scene::parseScene("bodies:\n  - {name: c, kind: cloth, model: baraff_witkin}\n", "test.yaml", scene)
          .ok);
  std::unique_ptr<World> from_scene;
  ASSERT_TRUE(particle_sim::scene::buildWorld(scene, from_scene).ok);
  expectConstants(*from_scene->findSpringBody("c")->baraffWitkin(), "scene file");

  const BaraffWitkinDef plain;
  EXPECT_EQ(plain.bend.stiffness, bend.stiffness);
  EXPECT_EQ(plain.stretch.stiffness, stretch.stiffness);
  EXPECT_EQ(plain.shear.stiffness, shear.stiffness);

  // The spring model keeps the spring cloth's defaults.
  const ClothGridDef springs(ClothModel::Springs);
  EXPECT_EQ(springs.bend.stiffness, 20.0);
  EXPECT_EQ(ClothGridDef().bend.stiffness, 20.0);
}
