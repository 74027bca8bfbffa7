// The world's default integrator: every integrator field a body definition does not set (its
// method, verlet_damping, cg_tolerance, cg_max_iterations, max_substeps) is the world's, for every
// spring body kind added to a World (rope, spring network, grid cloth, mesh cloth, jelly). A body
// that sets a field keeps it; a body built without a World uses the built-in defaults.

#include <gtest/gtest.h>

#include <string>

#include "particle_sim/core/integrators/rk4.h"
#include "particle_sim/core/integrators/symplectic_euler.h"
#include "particle_sim/core/integrators/verlet.h"
#include "particle_sim/core/world.h"

using namespace particle_sim::core;

namespace
{
// A world default that differs from IntegratorDef's built-in one in every field.
IntegratorDef worldDefault()
{
  IntegratorDef integrator;
  integrator.type = kVerletIntegrator;
  integrator.verlet_damping = 0.97;
  integrator.cg_tolerance = 1e-5;
  integrator.cg_velocity_tolerance = 3e-4;
  integrator.cg_max_iterations = 123;
  integrator.max_substeps = 7;
  return integrator;
}

void expectSettings(const IntegratorDef& actual, const IntegratorDef& expected, const std::string& body)
{
  EXPECT_EQ(actual.type, expected.type) << body << ": " << toString(actual.type);
  EXPECT_EQ(actual.verlet_damping, expected.verlet_damping) << body;
  EXPECT_EQ(actual.cg_tolerance, expected.cg_tolerance) << body;
  EXPECT_EQ(actual.cg_velocity_tolerance, expected.cg_velocity_tolerance) << body;
  EXPECT_EQ(actual.cg_max_iterations, expected.cg_max_iterations) << body;
  EXPECT_EQ(actual.max_substeps, expected.max_substeps) << body;
}

// One body of each spring kind, small, named after its kind, each given `integrator`.
void addOneOfEachKind(World& world, const BodyIntegratorDef& integrator)
{
  RopeDef rope;
  rope.name = "rope";
  rope.integrator = integrator;
  ASSERT_TRUE(world.addRope(rope).ok);

  SpringNetworkDef network;
  network.name = "network";
  network.positions = {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 0, 1)};
  network.masses = {0.1, 0.1};
  network.springs = {Spring{0, 1, 1.0, 50.0, 0.0, SpringClass::Stretch}};
  network.integrator = integrator;
  ASSERT_TRUE(world.addSpringNetwork(network).ok);

  ClothGridDef grid;
  grid.name = "grid";
  grid.nu = grid.nv = 4;
  grid.integrator = integrator;
  ASSERT_TRUE(world.addClothGrid(grid).ok);

  MeshClothDef mesh;
  mesh.name = "mesh";
  mesh.vertices = {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 0, 1), Eigen::Vector3d(1, 1, 1),
                   Eigen::Vector3d(0, 1, 1)};
  mesh.triangles = {Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(0, 2, 3)};
  mesh.integrator = integrator;
  ASSERT_TRUE(world.addMeshCloth(mesh).ok);

  JellyDef jelly;
  jelly.name = "jelly";
  jelly.nx = jelly.ny = jelly.nz = 3;
  jelly.integrator = integrator;
  ASSERT_TRUE(world.addJelly(jelly).ok);
}

const char* const kKinds[] = {"rope", "network", "grid", "mesh", "jelly"};

WorldDef worldWithDefault()
{
  WorldDef def;
  def.integrator = worldDefault();
  EXPECT_TRUE(validate(def).ok);
  return def;
}
}  // namespace

TEST(WorldIntegrator, EveryBodyThatSetsNoneGetsTheWorldsMethodAndSettings)
{
  World world(worldWithDefault());
  addOneOfEachKind(world, BodyIntegratorDef{});
  for (const char* kind : kKinds)
  {
    const SpringNetworkBody* body = world.findSpringBody(kind);
    ASSERT_NE(body, nullptr) << kind;
    expectSettings(body->integrator(), worldDefault(), kind);
  }
  // Steps run the world's method, and reset keeps the world's settings.
  world.step();
  world.reset();
  for (const char* kind : kKinds)
  {
    EXPECT_EQ(world.findSpringBody(kind)->lastIntegrator(), kVerletIntegrator) << kind;
    expectSettings(world.findSpringBody(kind)->integrator(), worldDefault(), kind);
  }
}

TEST(WorldIntegrator, ABodyThatSetsItsMethodKeepsItAndInheritsTheRest)
{
  World world(worldWithDefault());
  BodyIntegratorDef rk4;
  rk4.type = kRk4Integrator;
  addOneOfEachKind(world, rk4);
  IntegratorDef expected = worldDefault();
  expected.type = kRk4Integrator;
  for (const char* kind : kKinds)
    expectSettings(world.findSpringBody(kind)->integrator(), expected, kind);

  // A body that sets one setting and not the method: the world's method, its own setting.
  RopeDef rope;
  rope.name = "tolerant";
  rope.integrator.cg_tolerance = 1e-3;
  ASSERT_TRUE(world.addRope(rope).ok);
  expected = worldDefault();
  expected.cg_tolerance = 1e-3;
  expectSettings(world.findSpringBody("tolerant")->integrator(), expected, "tolerant");
}

TEST(WorldIntegrator, ABodySetsOnlyValidFieldsAndWithoutAWorldUsesTheBuiltInDefaults)
{
  // A set field out of range is refused with validate(IntegratorDef)'s message; unset fields are
  // not checked (they come from a world whose own values passed).
  RopeDef rope;
  rope.name = "rope";
  EXPECT_TRUE(validate(rope, 100).ok);
  rope.integrator.cg_tolerance = 0.0;
  const Status refused = validate(rope, 100);
  IntegratorDef same_value;
  same_value.cg_tolerance = 0.0;
  EXPECT_FALSE(refused.ok);
  EXPECT_EQ(refused.message, validate(same_value).message);
  EXPECT_NE(refused.message.find("cg_tolerance = 0"), std::string::npos) << refused.message;
  World world(worldWithDefault());
  EXPECT_FALSE(world.addRope(rope).ok);
  // The velocity tolerance: 0 (off) to 1 m/s, in its unit.
  rope.integrator = BodyIntegratorDef{};
  for (double tolerance : {0.0, 1.0})
  {
    rope.integrator.cg_velocity_tolerance = tolerance;
    EXPECT_TRUE(validate(rope, 100).ok) << tolerance;
  }
  for (double tolerance : {-1e-6, 1.5})
  {
    rope.integrator.cg_velocity_tolerance = tolerance;
    const Status out_of_range = validate(rope, 100);
    EXPECT_FALSE(out_of_range.ok) << tolerance;
    EXPECT_NE(out_of_range.message.find("cg_velocity_tolerance = "), std::string::npos) << out_of_range.message;
    EXPECT_NE(out_of_range.message.find("must be in [0, 1] m/s"), std::string::npos) << out_of_range.message;
  }

  // Built without a World: the method it sets, the rest built in.
  rope.integrator = BodyIntegratorDef{};
  rope.integrator.type = kSymplecticEulerIntegrator;
  const SpringNetworkBody alone(buildRope(rope));
  IntegratorDef expected;
  expected.type = kSymplecticEulerIntegrator;
  expectSettings(alone.integrator(), expected, "alone");
  RopeDef plain_def;
  plain_def.name = "plain";
  const SpringNetworkBody plain(buildRope(plain_def));
  expectSettings(plain.integrator(), IntegratorDef{}, "plain");
}

TEST(WorldIntegrator, SettingSomeFieldsOfABodyKeepsTheOthers)
{
  World world(worldWithDefault());
  RopeDef rope;
  rope.name = "rope";
  ASSERT_TRUE(world.addRope(rope).ok);
  SpringNetworkBody& body = *world.findSpringBody("rope");
  BodyIntegratorDef change;
  change.type = kRk4Integrator;
  change.max_substeps = 3;
  ASSERT_TRUE(body.setIntegrator(change).ok);
  IntegratorDef expected = worldDefault();
  expected.type = kRk4Integrator;
  expected.max_substeps = 3;
  expectSettings(body.integrator(), expected, "rope");
  change.max_substeps = 0;
  EXPECT_FALSE(body.setIntegrator(change).ok);
  expectSettings(body.integrator(), expected, "rope");  // refused: nothing changed
}
