// The force at the pins (issue 14, item 2): the reaction r_i = m_i a_i − f_i each pin exerts on its
// particle (SpringNetworkBody::pinReactions, pinLoad), against statics and Newton's second law.

#include <gtest/gtest.h>

#include <cmath>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/spring_network.h"

using namespace particle_sim::core;

namespace
{
constexpr double kGravity = 9.81;

Environment withoutGround()
{
  Environment env;
  env.ground.enabled = false;
  return env;
}

double totalMass(const SpringNetworkBody& body)
{
  double mass = 0.0;
  for (double m : body.definition().masses)
    mass += m;
  return mass;
}
}  // namespace

TEST(PinForce, TwoPinsOfAClothAtRestCarryItsWeight)
{
  // A 0.5 m cotton cloth (Baraff–Witkin, 21 x 21) hanging from two corners settles to rest; the pins'
  // reactions then balance gravity on the whole cloth: they sum to (0, 0, M g), within the rest
  // state's residual (the test settles to 1e-9 m/s: far below the 1 % the issue allows).
  ClothGridDef def(ClothModel::BaraffWitkin);
  def.name = "towel";
  def.origin = {0.0, 0.0, 2.0};
  def.edge_u = {0.5, 0.0, 0.0};
  def.edge_v = {0.0, 0.5, 0.0};
  def.nu = def.nv = 21;
  def.material = *findClothPreset("cotton");
  def.named_pins = {"corner_00", "corner_10"};
  def.integrator.type = kImplicitEulerIntegrator;
  ASSERT_TRUE(validate(def, 10000).ok);
  SpringNetworkBody body(buildClothGrid(def));
  Environment env = withoutGround();
  env.damping = 10.0;  // [1/s] settles the swing (a force on the free particles only at rest: 0)
  for (int step = 0; step < 1000; ++step)
    body.step(0.02, env);
  const ParticlePool& p = body.particles();
  ASSERT_LT(p.velocity.leftCols(p.size()).colwise().norm().maxCoeff(), 1e-6);
  const SpringNetworkBody::PinLoad load = body.pinLoad({}, Eigen::Vector3d::Zero());
  const double weight = totalMass(body) * kGravity;
  EXPECT_NEAR(load.force.z(), weight, 1e-4 * weight);
  EXPECT_NEAR(load.force.x(), 0.0, 1e-4 * weight);
  EXPECT_NEAR(load.force.y(), 0.0, 1e-4 * weight);
  // Each corner carries about half of it (the grid's diagonals all run one way, so the cloth is not
  // quite mirror-symmetric: 0.13 % apart here).
  Eigen::Matrix3Xd reactions;
  reactions.resize(3, p.size());
  body.pinReactions(reactions);
  EXPECT_NEAR(reactions(2, 0), weight / 2.0, 0.01 * weight);
  EXPECT_NEAR(reactions(2, 20), weight / 2.0, 0.01 * weight);
  EXPECT_EQ(reactions.col(10).norm(), 0.0) << "a free particle has no pin force";
}

TEST(PinForce, ARopeLiftedWithAccelerationANeedsMTimesGPlusA)
{
  // A 1 kg rope hanging from its top pin, lifted with constant upward acceleration a = 3 m/s²
  // (the pin's target at z0 + a t²/2) for 2 s. Once the rope's stretch oscillation has died
  // (material damping, internal: it moves no momentum), Newton's second law for the whole rope gives
  // the pin force F = m (g + a); the issue asks for 2 %, the test allows 0.5 % (the remaining
  // oscillation, averaged over the last 0.5 s).
  RopeDef def;
  def.name = "lifted";
  def.particles = 21;
  def.start = {0.0, 0.0, 3.0};
  def.end = {0.0, 0.0, 1.0};
  def.mass = 1.0;
  def.stretch_stiffness = 2000.0;
  def.stretch_damping = 20.0;
  def.pins = {0};
  def.integrator.type = kImplicitEulerIntegrator;
  ASSERT_TRUE(validate(def, 1000).ok);
  SpringNetworkBody body(buildRope(def));
  const Environment env = withoutGround();
  const double a = 3.0, dt = 0.005;
  const Eigen::Vector3d top = body.particles().position.col(0);
  // Let it hang still first.
  for (int step = 0; step < 400; ++step)
    body.step(dt, env);
  double sum = 0.0;
  int samples = 0;
  for (int step = 1; step <= 400; ++step)
  {
    const double t = step * dt;
    ASSERT_TRUE(body.setPinTarget(0, top + Eigen::Vector3d(0.0, 0.0, 0.5 * a * t * t)).ok);
    body.step(dt, env);
    if (step > 300)
    {
      sum += body.pinLoad({0}, top).force.z();
      ++samples;
    }
  }
  const double expected = totalMass(body) * (kGravity + a);
  EXPECT_NEAR(sum / samples, expected, 0.005 * expected);
}

TEST(PinForce, TheClampOfACantileverCarriesItsWeightAndItsMoment)
{
  // A stiff, short strip (4 cm over the edge, B = 1e-3 N·m) clamped by its two pinned columns sags by far
  // less than its length: the clamp carries its weight W and the moment W L/2 about the clamp line
  // (the weight's lever is the centre of the free part, to first order in the small sag). About the
  // point on the clamp line at x = −h/2 (where the discrete strip is clamped, between the pinned
  // columns), the pins' torque is −W (L/2) about y (the strip lies along +x), within 1 %.
  const ClothMaterial stiff{"", 0.2, 1e5, 1e3, 1e-3, 0.5};  // bending length (B / ρ_A g)^(1/3) = 8 cm
  const int cells = 16;
  const double length = 0.04, width = 0.02, h = length / (cells + 0.5);
  ClothGridDef def(ClothModel::BaraffWitkin);
  def.name = "strip";
  def.origin = {-h, -width / 2, 0.0};
  def.edge_u = {(cells + 1) * h, 0.0, 0.0};
  def.edge_v = {0.0, width, 0.0};
  def.nu = cells + 2;
  def.nv = 9;
  def.material = stiff;
  for (int b = 0; b < def.nv; ++b)
    def.pins.insert(def.pins.end(), {b * def.nu, b * def.nu + 1});
  def.integrator.type = kImplicitEulerIntegrator;
  def.integrator.linear_solver = LinearSolverType::Direct;
  ASSERT_TRUE(validate(def, 10000).ok);
  SpringNetworkBody body(buildClothGrid(def));
  Environment env = withoutGround();
  env.damping = 50.0;
  for (int step = 0; step < 400; ++step)
    body.step(0.01, env);
  // The free part's weight and its centre (the pinned particles' own weight rests on the clamp
  // without a lever: it is in the force, not the moment).
  const ParticlePool& p = body.particles();
  double free_weight = 0.0, pinned_weight = 0.0, moment = 0.0;
  for (int i = 0; i < p.size(); ++i)
  {
    const double w = body.definition().masses[i] * kGravity;
    (body.isPinned(i) ? pinned_weight : free_weight) += w;
    moment += w * (p.position(0, i) + h / 2);  // about the clamp line
  }
  ASSERT_LT(-p.position(2, p.size() - 1), 0.05 * length) << "the strip should sag little";
  const SpringNetworkBody::PinLoad load = body.pinLoad({}, Eigen::Vector3d(-h / 2, 0.0, 0.0));
  EXPECT_NEAR(load.force.z(), free_weight + pinned_weight, 1e-6 * free_weight);
  // r × F about the clamp with F up: a holding torque about −y of size Σ w x.
  EXPECT_NEAR(load.torque.y(), -moment, 0.01 * moment);
  EXPECT_NEAR(moment / free_weight, length / 2, 0.05 * length);  // the lever is about L/2
}
