// Isotropic plate bending (forces/plate_bending.h) on a body-fitted disc: nothing on a flat sheet
// moved rigidly, forces = −gradient of the energy (finite differences), one implicit Euler step that
// solves its linear system exactly (so the Jacobian blocks are the forces' own), and a cylinder bent
// at any angle to the mesh storing the plate's B/2 κ² per area, converging at second order; a mesh
// cloth built from a material bends with it and has no hinges.

#include "particle_sim/core/forces/plate_bending.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <random>

#include "disc_mesh.h"
#include "particle_sim/core/builders/mesh_cloth.h"
#include "particle_sim/core/materials/cloth_material.h"
#include "particle_sim/core/spring_network.h"

using namespace particle_sim::core;
using particle_sim_test::DiscMesh;
using particle_sim_test::discMesh;

namespace
{
constexpr double kRigidity = 7.8e-6;  // [N·m], the cotton preset's

PlateBendingDef plateOf(const DiscMesh& mesh, double rigidity, double damping = 0.0)
{
  PlateBendingDef def;
  std::string error;
  EXPECT_TRUE(buildPlateBending(mesh.uvs, mesh.triangles, rigidity, damping, def, error)) << error;
  return def;
}

Eigen::Matrix3Xd positionsOf(const DiscMesh& mesh)
{
  Eigen::Matrix3Xd x(3, mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    x.col(i) = mesh.vertices[i];
  return x;
}

struct Probe
{
  Eigen::VectorXd mass;
  std::vector<char> pinned;
  explicit Probe(int n) : mass(Eigen::VectorXd::Ones(n)), pinned(n, 0) {}
  ForceContext context() const { return ForceContext{mass, pinned, Eigen::Vector3d::Zero(), AirDef(), 0.0}; }
};

double energy(const PlateBendingForce& element, const Probe& probe, const Eigen::Matrix3Xd& x)
{
  double e = 0.0;
  element.addEnergy(probe.context(), x, e);
  return e;
}

Eigen::Matrix3Xd forces(const PlateBendingForce& element, const Probe& probe, const Eigen::Matrix3Xd& x,
                        const Eigen::Matrix3Xd& v)
{
  Eigen::Matrix3Xd f = Eigen::Matrix3Xd::Zero(3, x.cols());
  element.addForces(probe.context(), x, v, f);
  return f;
}

// The disc rolled isometrically onto a cylinder of radius rho whose axis lies in the plane at
// `angle` to the x axis: arc length across the axis is kept.
Eigen::Matrix3Xd rolled(const DiscMesh& mesh, double rho, double angle)
{
  const Eigen::Vector3d across(std::cos(angle), std::sin(angle), 0.0), along(-std::sin(angle), std::cos(angle), 0.0);
  Eigen::Matrix3Xd x(3, mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
  {
    const double s = mesh.vertices[i].dot(across), w = mesh.vertices[i].dot(along);
    x.col(i) =
        rho * std::sin(s / rho) * across + w * along + rho * (1.0 - std::cos(s / rho)) * Eigen::Vector3d::UnitZ();
  }
  return x;
}
}  // namespace

TEST(PlateBending, AFlatSheetMovedRigidlyFeelsNothing)
{
  const DiscMesh mesh = discMesh(0.15, 6);
  const PlateBendingForce element(plateOf(mesh, kRigidity, 1e-7));
  const Probe probe(static_cast<int>(mesh.vertices.size()));
  // Turned about a skew axis and moved, and spinning about another: no energy, no force.
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d spin(0.3, -1.0, 2.0);
  Eigen::Matrix3Xd x = turn * positionsOf(mesh), v(3, x.cols());
  for (int i = 0; i < x.cols(); ++i)
  {
    v.col(i) = spin.cross(x.col(i)) + Eigen::Vector3d(1, 1, 1);
    x.col(i) += Eigen::Vector3d(0.5, -2.0, 1.0);
  }
  // Scales: B / A_v |y|² with |y| ~ the rounding of x (1e-16 m) is far below 1e-25 J; forces alike.
  EXPECT_LT(energy(element, probe, x), 1e-25);
  EXPECT_LT(forces(element, probe, x, v).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(PlateBending, ForcesAreMinusTheGradientOfTheEnergy)
{
  const DiscMesh mesh = discMesh(0.15, 4);
  const PlateBendingForce element(plateOf(mesh, kRigidity));
  const Probe probe(static_cast<int>(mesh.vertices.size()));
  std::mt19937 random(7);
  std::uniform_real_distribution<double> wobble(-0.01, 0.01);
  Eigen::Matrix3Xd x = positionsOf(mesh);
  for (int i = 0; i < x.cols(); ++i)
    x.col(i) += Eigen::Vector3d(wobble(random), wobble(random), 3.0 * wobble(random));
  const Eigen::Matrix3Xd f = forces(element, probe, x, Eigen::Matrix3Xd::Zero(3, x.cols()));
  // E is quadratic: central differences are exact but for rounding (E ~ 1e-5 J, step 1e-6 m).
  const double step = 1e-6;
  double worst = 0.0;
  for (int i = 0; i < x.cols(); ++i)
    for (int c = 0; c < 3; ++c)
    {
      Eigen::Matrix3Xd plus = x, minus = x;
      plus(c, i) += step;
      minus(c, i) -= step;
      const double gradient = (energy(element, probe, plus) - energy(element, probe, minus)) / (2.0 * step);
      worst = std::max(worst, std::abs(f(c, i) + gradient));
    }
  EXPECT_LT(worst, 1e-7 * f.cwiseAbs().maxCoeff());
}

TEST(PlateBending, AnImplicitEulerStepSolvesItsLinearSystemExactly)
{
  // The forces are linear in (x, v), so one implicit Euler step solved exactly satisfies
  // M (v₁ − v₀) = h f(x₁, v₁): it can only when the Jacobian blocks are the forces' own.
  const DiscMesh mesh = discMesh(0.15, 5);
  SpringNetworkDef def;
  def.name = "plate";
  def.shape = NetworkShape::Cloth;
  def.positions = mesh.vertices;
  def.triangles = mesh.triangles;
  def.masses.assign(mesh.vertices.size(), 1e-4);
  def.plate_bending = plateOf(mesh, kRigidity, 3e-7);
  def.integrator.type = kImplicitEulerIntegrator;
  def.integrator.linear_solver = LinearSolverType::Direct;
  def.integrator.cg_tolerance = 1e-14;
  std::mt19937 random(3);
  std::uniform_real_distribution<double> wobble(-0.01, 0.01);
  for (Eigen::Vector3d& x : def.positions)
  {
    x.z() += wobble(random);
    def.velocities.emplace_back(0.0, 0.0, 10.0 * wobble(random));
  }
  ASSERT_TRUE(validate(def, 100000).ok);
  SpringNetworkBody body(def);
  const ParticlePool& p = body.particles();
  const Eigen::Matrix3Xd v0 = p.velocity.leftCols(p.size());
  Environment env;
  env.gravity.setZero();
  env.ground.enabled = false;
  const double h = 0.01;
  body.step(h, env);
  ASSERT_EQ(body.lastSubsteps(), 1);
  Eigen::Matrix3Xd f(3, p.size());
  body.computeForces(p.position.leftCols(p.size()), p.velocity.leftCols(p.size()), Eigen::Vector3d::Zero(), f);
  const Eigen::Matrix3Xd momentum = 1e-4 * (p.velocity.leftCols(p.size()) - v0);
  EXPECT_LT((momentum - h * f).cwiseAbs().maxCoeff(), 1e-9 * momentum.cwiseAbs().maxCoeff());
}

TEST(PlateBending, ACylinderStoresThePlatesEnergyAtAnyAngleToTheMeshConvergingAtSecondOrder)
{
  // Rolled onto a cylinder of radius ρ (isometric: κ₁ = 1/ρ, κ₂ = 0), the sheet's interior stores
  // B/2 κ² per area, whatever the angle between the axis and the mesh. The discrete energy's error is
  // second order in the ring spacing: it must fall by about 4 per halving, and it must not depend on
  // the angle by more than the error itself (no preferred direction).
  const double rho = 0.2;
  const std::vector<int> rings = {8, 16, 32};
  const std::vector<double> angles = {0.0, 0.3, 0.7, 1.2, 2.0};
  std::vector<double> worst;
  for (int n : rings)
  {
    const DiscMesh mesh = discMesh(0.15, n);
    const PlateBendingDef def = plateOf(mesh, kRigidity);
    double interior_area = 0.0;
    for (double inverse : def.inverse_area)
      interior_area += 1.0 / inverse;
    const PlateBendingForce element(def);
    const Probe probe(static_cast<int>(mesh.vertices.size()));
    const double expected = 0.5 * kRigidity * interior_area / (rho * rho);
    double low = 1e300, high = -1e300;
    for (double angle : angles)
    {
      const double error = energy(element, probe, rolled(mesh, rho, angle)) / expected - 1.0;
      low = std::min(low, error);
      high = std::max(high, error);
    }
    std::printf("%2d rings: relative error of the energy %+.3e to %+.3e over %zu angles\n", n, low, high,
                angles.size());
    worst.push_back(std::max(std::abs(low), std::abs(high)));
    EXPECT_LT(high - low, std::max(std::abs(low), std::abs(high))) << n << " rings: the energy depends on the angle";
  }
  for (std::size_t i = 0; i + 1 < worst.size(); ++i)
  {
    const double ratio = worst[i] / worst[i + 1];
    EXPECT_GT(ratio, 3.0) << "from " << rings[i] << " to " << rings[i + 1] << " rings";
    EXPECT_LT(ratio, 5.0) << "from " << rings[i] << " to " << rings[i + 1] << " rings";
  }
  EXPECT_LT(worst.back(), 1e-2);
}

TEST(PlateBending, AMeshClothOfAMaterialBendsWithThePlateAndHasNoHinges)
{
  const DiscMesh mesh = discMesh(0.15, 6);
  MeshClothDef def(ClothModel::BaraffWitkin);
  def.name = "disc";
  def.vertices = mesh.vertices;
  def.triangles = mesh.triangles;
  def.uvs = mesh.uvs;
  def.material = *findClothPreset("cotton");
  ASSERT_TRUE(validate(def, 100000).ok);
  const SpringNetworkDef net = buildMeshCloth(def);
  EXPECT_TRUE(net.baraff_witkin.bends.empty());
  EXPECT_FALSE(net.baraff_witkin.triangles.empty());
  // One stencil per vertex off the rim, at the material's rigidity.
  const int interior = mesh.ring_start[6];
  EXPECT_EQ(net.plate_bending.stencils(), interior);
  EXPECT_DOUBLE_EQ(net.plate_bending.rigidity, def.material->bending_rigidity);
  EXPECT_GT(net.plate_bending.damping, 0.0);

  // Its bend class is set at run time (~set_spring_constants), and reset, like Baraff–Witkin's.
  SpringNetworkBody body(net);
  ASSERT_TRUE(body.hasSpringClass(SpringClass::Bend));
  const Eigen::Matrix3Xd bent = rolled(mesh, 0.2, 0.5);
  const ForceContext context{Eigen::VectorXd::Ones(bent.cols()), std::vector<char>(bent.cols(), 0),
                             Eigen::Vector3d::Zero(), AirDef(), 0.0};
  const PlateBendingForce built(net.plate_bending);
  double before = 0.0;
  built.addEnergy(context, bent, before);
  PlateBendingForce element(net.plate_bending);
  element.setClassConstants(SpringClass::Bend, 3.0 * def.material->bending_rigidity, 0.0);
  double tripled = 0.0;
  element.addEnergy(context, bent, tripled);
  EXPECT_NEAR(tripled, 3.0 * before, 1e-12 * before);
  element.setClassConstants(SpringClass::Stretch, 1.0, 0.0);  // not its class: unchanged
  double still = 0.0;
  element.addEnergy(context, bent, still);
  EXPECT_EQ(still, tripled);
  element.resetConstants();
  double reset = 0.0;
  element.addEnergy(context, bent, reset);
  EXPECT_EQ(reset, before);
  EXPECT_TRUE(body.setSpringConstants(SpringClass::Bend, 2e-5, 1e-7).ok);
}
