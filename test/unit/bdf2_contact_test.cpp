// BDF2 (src/core/integrators/bdf2.cpp) in contact: a particle whose state the collision response
// changed restarts its history from the changed state, so BDF2 does not carry the motion from
// before the contact on, and it converges as the step shrinks.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/integrators/bdf2.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/rk4.h"
#include "particle_sim/core/spring_network.h"

using namespace particle_sim::core;

namespace
{
// Steps `def` with `type` for `duration` at dt [s] (no substeps); the positions at the end.
Eigen::Matrix3Xd finalPositions(SpringNetworkDef def, IntegratorType type, const Environment& env, double dt,
                                double duration)
{
  def.integrator.type = type;
  def.integrator.max_substeps = 1;
  SpringNetworkBody body(def);
  const long steps = std::lround(duration / dt);
  for (long k = 0; k < steps; ++k)
    body.step(dt, env);
  EXPECT_FALSE(body.frozen()) << toString(type) << " dt = " << dt << ": " << body.frozenReason();
  return body.particles().position.leftCols(body.particles().size());
}

// RMS over the particles of |x − x_ref| [m].
double rmsError(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& reference)
{
  return std::sqrt((x - reference).colwise().squaredNorm().mean());
}
}  // namespace

// A 6 × 6 spring cloth dropped 0.1 m onto a sphere (restitution 0, friction 0.3), draped over it
// at T = 0.3 s. Against RK4 at 1e-5 s, BDF2's error shrinks at least twice per halving of the
// step (it used to stall at about 1.4 mm) and stays at or below implicit Euler's.
TEST(Bdf2Contact, ClothOnASphereConvergesAndIsNoWorseThanImplicitEuler)
{
  ClothGridDef cloth(ClothModel::Springs);
  cloth.name = "cloth";
  cloth.origin = {-0.4, -0.4, 0.9};
  cloth.edge_u = {0.8, 0, 0};
  cloth.edge_v = {0, 0.8, 0};
  cloth.nu = 6;
  cloth.nv = 6;
  cloth.mass = 0.1;
  cloth.stretch = {200.0, 0.05};
  cloth.shear = {50.0, 0.02};
  cloth.bend = {5.0, 0.005};
  ASSERT_TRUE(validate(cloth, 1000).ok) << validate(cloth, 1000).message;
  const SpringNetworkDef def = buildClothGrid(cloth);
  Environment env;
  env.ground.enabled = false;
  SphereColliderDef ball;
  ball.name = "ball";
  ball.center = {0, 0, 0.5};
  ball.radius = 0.3;
  ball.contact.restitution = 0.0;
  ball.contact.friction = 0.3;
  env.spheres.push_back(ball);
  const double duration = 0.3;

  const Eigen::Matrix3Xd reference = finalPositions(def, kRk4Integrator, env, 1e-5, duration);
  // The reference is good to well below the errors compared (first order in contact: about 1.5e-6 m).
  EXPECT_LT(rmsError(finalPositions(def, kRk4Integrator, env, 2e-5, duration), reference), 1e-5);
  // It is a contact scene: the middle of the cloth lies on the sphere.
  int touching = 0;
  for (int i = 0; i < reference.cols(); ++i)
    touching += (reference.col(i) - ball.center).norm() < ball.radius + 1e-6;
  EXPECT_GE(touching, 4);

  std::vector<double> bdf2_errors;
  for (double steps_per_second : {320.0, 640.0, 1280.0, 2560.0, 5120.0})
  {
    const double dt = 1.0 / steps_per_second;
    const double bdf2 = rmsError(finalPositions(def, kBdf2Integrator, env, dt, duration), reference);
    const double implicit_euler = rmsError(finalPositions(def, kImplicitEulerIntegrator, env, dt, duration), reference);
    EXPECT_LE(bdf2, implicit_euler) << "dt = " << dt;
    bdf2_errors.push_back(bdf2);
  }
  for (std::size_t k = 0; k + 1 < bdf2_errors.size(); ++k)
    EXPECT_GE(bdf2_errors[k] / bdf2_errors[k + 1], 2.0)
        << "errors " << bdf2_errors[k] << " -> " << bdf2_errors[k + 1] << " m as the step halves";
}
