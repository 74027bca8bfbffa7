// Contact thickness: a body keeps its particles at least contact_thickness outside the ground and
// every sphere. With the thickness clothContactThickness() gives, a cloth draped over a sphere
// keeps every triangle outside it (with none, the flat triangles between particles resting on the
// sphere cut into it, which is what showed the sphere through the cloth in docs/cloth_on_sphere.png).

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/surface.h"
#include "particle_sim/core/world.h"
#include "particle_sim/scene/scene.h"

using namespace particle_sim::core;

namespace
{
SphereColliderDef ball()
{
  SphereColliderDef sphere;
  sphere.name = "ball";
  sphere.center = {0.0, 0.0, 0.6};
  sphere.radius = 0.5;
  sphere.contact.restitution = 0.0;
  sphere.contact.friction = 0.4;
  return sphere;
}

// A 1.6 m square sheet of 15 x 15 particles dropped centred onto ball().
ClothGridDef sheet(double contact_thickness)
{
  ClothGridDef def;
  def.name = "sheet";
  def.origin = {-0.8, -0.8, 1.2};
  def.edge_u = {1.6, 0.0, 0.0};
  def.edge_v = {0.0, 1.6, 0.0};
  def.nu = def.nv = 15;
  def.mass = 0.3;
  def.bend = {3.0, 0.01};
  def.strain_limit.max_strain = 0.1;
  def.integrator.type = kImplicitEulerIntegrator;
  def.contact_thickness = contact_thickness;
  return def;
}

struct DrapeResult
{
  int centroids_inside = 0;     // triangles whose centroid is inside the sphere
  double deepest = 0.0;         // [m] deepest centroid below the sphere's surface
  double closest_particle = 0;  // [m] smallest particle distance to the sphere's surface, over the last step
};

DrapeResult drape(double contact_thickness)
{
  WorldDef world_def;
  world_def.dt = 0.005;
  world_def.spheres = {ball()};
  world_def.ground.contact.restitution = 0.0;
  EXPECT_TRUE(validate(world_def).ok);
  World world(world_def);
  EXPECT_TRUE(world.addClothGrid(sheet(contact_thickness)).ok);
  const SpringNetworkBody& body = *world.findSpringBody("sheet");
  for (int k = 0; k < 600; ++k)  // 3 s: it lies still on the sphere by then
    world.step();
  EXPECT_FALSE(body.frozen()) << body.frozenReason();

  DrapeResult result;
  const SphereColliderDef& sphere = world.environment().spheres[0];
  const Eigen::Matrix3Xd& x = body.particles().position;
  result.closest_particle = std::numeric_limits<double>::infinity();
  for (int i = 0; i < body.particles().size(); ++i)
    result.closest_particle = std::min(result.closest_particle, (x.col(i) - sphere.center).norm() - sphere.radius);
  for (const Eigen::Vector3i& t : body.definition().triangles)
  {
    const Eigen::Vector3d centroid = (x.col(t[0]) + x.col(t[1]) + x.col(t[2])) / 3.0;
    const double depth = sphere.radius - (centroid - sphere.center).norm();
    if (depth > 0.0) ++result.centroids_inside;
    result.deepest = std::max(result.deepest, depth);
  }
  return result;
}
}  // namespace

TEST(ContactThickness, DrapedClothKeepsEveryTriangleCentroidOutsideTheSphere)
{
  const SpringNetworkDef net = buildClothGrid(sheet(0.0));
  const double thickness = clothContactThickness(net.positions, net.triangles, {ball()});
  // The longest rest edge is a cell diagonal, L = √2 · 1.6/14 m; ρ² = L²/3; depth ρ²/(R + √(R² − ρ²)).
  const double longest = std::sqrt(2.0) * 1.6 / 14.0, rho2 = longest * longest / 3.0;
  EXPECT_NEAR(thickness, rho2 / (0.5 + std::sqrt(0.25 - rho2)), 1e-12);

  const DrapeResult with = drape(thickness);
  EXPECT_EQ(with.centroids_inside, 0) << "deepest centroid " << with.deepest << " m inside";
  EXPECT_GE(with.closest_particle, thickness - 1e-9) << "particles keep the thickness from the sphere";

  // Without a thickness the same drape has centroids inside the sphere: the test above can fail.
  const DrapeResult without = drape(0.0);
  EXPECT_GT(without.centroids_inside, 0);
  EXPECT_GE(without.closest_particle, -1e-9);
}

TEST(ContactThickness, ParticlesRestThatFarAboveTheGroundAndOutsideSpheres)
{
  WorldDef world_def;
  world_def.ground.contact.restitution = 0.0;
  SphereColliderDef sphere;
  sphere.name = "ball";
  sphere.center = {5.0, 0.0, 0.0};
  sphere.radius = 1.0;
  world_def.spheres = {sphere};
  World world(world_def);

  // A rope lying above the ground falls and rests at the thickness.
  RopeDef rope;
  rope.name = "rope";
  rope.particles = 5;
  rope.start = {-1.0, 0.0, 0.5};
  rope.end = {1.0, 0.0, 0.5};
  rope.contact_thickness = 0.05;
  ASSERT_TRUE(world.addRope(rope).ok);
  // A particle shot straight at the sphere stays thickness outside it.
  EmitterDef shot;
  shot.name = "shot";
  shot.type = EmitterType::Fountain;
  shot.origin = {5.0, 0.0, 3.0};
  shot.rate = 0.0;
  shot.burst_count = 1;
  shot.spread = 0.0;
  shot.speed = -5.0;
  shot.max_particles = 1;
  shot.lifetime = 100.0;
  shot.contact_thickness = 0.2;
  ASSERT_TRUE(world.addEmitter(shot).ok);

  const ParticlePool& rope_particles = world.findBody("rope")->particles();
  const ParticlePool& shot_particles = world.findBody("shot")->particles();
  for (int k = 0; k < 3000; ++k)
  {
    world.step();
    for (int i = 0; i < rope_particles.size(); ++i)
      ASSERT_GE(rope_particles.position(2, i), 0.05 - 1e-12) << "step " << k;
    ASSERT_GE((shot_particles.position.col(0) - sphere.center).norm(), 1.2 - 1e-9) << "step " << k;
  }
  for (int i = 0; i < rope_particles.size(); ++i)
    EXPECT_NEAR(rope_particles.position(2, i), 0.05, 1e-6);
}

TEST(ContactThickness, IsValidatedAndDefaultsToZeroInTheCoreAndToTheDrapeBoundForSceneCloth)
{
  RopeDef rope;
  rope.name = "r";
  rope.contact_thickness = -0.1;
  const Status s = validate(rope, 1000);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("contact_thickness = -0.1 is out of range: must be in [0, 1] m"), std::string::npos)
      << s.message;
  EXPECT_EQ(RopeDef().contact_thickness, 0.0);
  EXPECT_EQ(EmitterDef().contact_thickness, 0.0);
  EXPECT_EQ(JellyDef().contact_thickness, 0.0);
  EXPECT_EQ(ClothGridDef().contact_thickness, 0.0);

  using particle_sim::scene::parseScene;
  using particle_sim::scene::SceneDef;
  const std::string world = "world:\n  spheres: [{center: [0, 0, 0.6], radius: 0.5}]\n";
  const std::string cloth =
      "bodies:\n  - {name: c, kind: cloth, origin: [-0.8, -0.8, 1.2], edge_u: [1.6, 0, 0], "
      "edge_v: [0, 1.6, 0], resolution: [15, 15]";
  SceneDef scene;
  ASSERT_TRUE(parseScene(world + cloth + "}\n", "test.yaml", scene).ok);
  const SpringNetworkDef net = buildClothGrid(std::get<ClothGridDef>(scene.bodies[0]));
  const double drape_bound = clothContactThickness(net.positions, net.triangles, scene.world.spheres);
  EXPECT_GT(drape_bound, 0.0);
  EXPECT_EQ(std::get<ClothGridDef>(scene.bodies[0]).contact_thickness, drape_bound);
  ASSERT_TRUE(parseScene(world + cloth + ", contact_thickness: auto}\n", "test.yaml", scene).ok);
  EXPECT_EQ(std::get<ClothGridDef>(scene.bodies[0]).contact_thickness, drape_bound);
  ASSERT_TRUE(parseScene(world + cloth + ", contact_thickness: 0.02}\n", "test.yaml", scene).ok);
  EXPECT_EQ(std::get<ClothGridDef>(scene.bodies[0]).contact_thickness, 0.02);
  ASSERT_TRUE(parseScene(cloth + "}\n", "test.yaml", scene).ok);  // no sphere: a flat ground needs none
  EXPECT_EQ(std::get<ClothGridDef>(scene.bodies[0]).contact_thickness, 0.0);
  ASSERT_TRUE(parseScene(world + "bodies:\n  - {name: r, kind: rope}\n", "test.yaml", scene).ok);
  EXPECT_EQ(std::get<RopeDef>(scene.bodies[0]).contact_thickness, 0.0);
}
