// Service requests to core definitions, without a ROS master: a good request gives the definition
// field by field (in the units the .srv files name), a field left at 0 keeps the definition's
// default, and a bad request is refused with a message naming the field, the value as received
// and what is allowed. Ranges are the core's validate(): the converted definitions are passed
// through it to show that the names in its messages are the request's.

#include "particle_sim/ros/request_conversions.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/rk4.h"
#include "particle_sim/core/integrators/verlet.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/world.h"
#include "test_helpers.h"

using namespace particle_sim;
using namespace particle_sim::ros_interface;
using particle_sim_test::kNaN;

namespace
{
constexpr std::uint32_t kBeyondInt = static_cast<std::uint32_t>(std::numeric_limits<int>::max()) + 1u;  // 2147483648

geometry_msgs::Point point(double x, double y, double z)
{
  geometry_msgs::Point p;
  p.x = x, p.y = y, p.z = z;
  return p;
}

geometry_msgs::Vector3 vector(double x, double y, double z)
{
  geometry_msgs::Vector3 v;
  v.x = x, v.y = y, v.z = z;
  return v;
}

// A world default integrator that differs from IntegratorDef's in every field, so that a test
// sees which one a definition got.
core::IntegratorDef worldDefaultIntegrator()
{
  core::IntegratorDef integrator;
  integrator.type = core::kVerletIntegrator;
  integrator.verlet_damping = 0.99;
  integrator.cg_tolerance = 1e-6;
  integrator.cg_velocity_tolerance = 5e-4;
  integrator.cg_max_iterations = 77;
  integrator.max_substeps = 9;
  return integrator;
}

void expectSameSettings(const core::BodyIntegratorDef& a, const core::IntegratorDef& b)
{
  EXPECT_EQ(a.verlet_damping, b.verlet_damping);
  EXPECT_EQ(a.cg_tolerance, b.cg_tolerance);
  EXPECT_EQ(a.cg_velocity_tolerance, b.cg_velocity_tolerance);
  EXPECT_EQ(a.cg_max_iterations, b.cg_max_iterations);
  EXPECT_EQ(a.max_substeps, b.max_substeps);
}

// A straight rope of 5 particles 1 m apart along x, at z = 2 m.
core::SpringNetworkBody fiveParticleRope()
{
  core::RopeDef rope;
  rope.name = "rope";
  rope.particles = 5;
  rope.start = {0.0, 0.0, 2.0};
  rope.end = {4.0, 0.0, 2.0};
  EXPECT_TRUE(core::validate(rope, 1000).ok);
  return core::SpringNetworkBody(core::buildRope(rope));
}
}  // namespace

TEST(RequestConversions, EmitterRequestGivesItsDefinitionFieldByField)
{
  SpawnEmitter::Request req;
  req.name = "spray";
  req.type = "semi_sphere";
  req.origin = point(1.0, -2.0, 3.5);
  req.rate = 250.0;
  req.burst_count = 40;
  req.speed = 4.5;
  req.spread = 0.25;
  req.lifetime = 1.5;
  req.mass = 0.002;
  req.max_particles = 600;
  req.seed = 1234;
  core::EmitterDef def;
  ASSERT_TRUE(toEmitterDef(req, 99, def).ok);
  EXPECT_EQ(def.name, "spray");
  EXPECT_EQ(def.type, core::EmitterType::SemiSphere);
  EXPECT_EQ(def.origin, Eigen::Vector3d(1.0, -2.0, 3.5));  // [m]
  EXPECT_EQ(def.rate, 250.0);                              // [particles/s]
  EXPECT_EQ(def.burst_count, 40);
  EXPECT_EQ(def.speed, 4.5);            // [m/s]
  EXPECT_EQ(def.spread, 0.25);          // [m/s]
  EXPECT_EQ(def.lifetime, 1.5);         // [s]
  EXPECT_EQ(def.particle_mass, 0.002);  // [kg]
  EXPECT_EQ(def.max_particles, 600);
  EXPECT_EQ(def.seed, 1234u);             // given: used as is
  EXPECT_EQ(def.contact_thickness, 0.0);  // not in the request: the default
  EXPECT_TRUE(core::validate(def).ok);
}

TEST(RequestConversions, EmitterFieldsLeftAtZeroKeepTheDefaultsAndTheSeedIsDerived)
{
  SpawnEmitter::Request req;
  req.name = "fountain";
  req.type = "fountain";
  req.rate = 10.0;
  core::EmitterDef def;
  ASSERT_TRUE(toEmitterDef(req, 7, def).ok);
  EXPECT_EQ(def.lifetime, 3.0);        // README: 0 = the default, 3 s
  EXPECT_EQ(def.particle_mass, 0.01);  // 0 = the default, 0.01 kg
  EXPECT_EQ(def.max_particles, 2000);  // 0 = the default, 2000
  EXPECT_EQ(def.burst_count, 0);       // 0 is a value here, not "the default"
  EXPECT_EQ(def.speed, 0.0);           // so are speed and spread
  EXPECT_EQ(def.spread, 0.0);
  // Seed 0: derived from the world seed and the name, as a scene file's emitter without a seed.
  EXPECT_EQ(def.seed, core::deriveSeed(7, "fountain"));
  EXPECT_NE(def.seed, core::deriveSeed(8, "fountain"));
}

TEST(RequestConversions, EmitterRefusesAnUnknownTypeAndCountsBeyondInt)
{
  SpawnEmitter::Request req;
  req.name = "e";
  req.type = "geyser";
  core::EmitterDef def;
  core::Status s = toEmitterDef(req, 1, def);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "type = 'geyser' is not an emitter type; allowed: fountain, waterfall, semi_sphere, explosion");

  req.type = "fountain";
  req.burst_count = kBeyondInt;
  s = toEmitterDef(req, 1, def);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "burst_count = 2147483648 is out of range: must be at most 2147483647");

  req.burst_count = 0;
  req.max_particles = 4294967295u;
  s = toEmitterDef(req, 1, def);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "max_particles = 4294967295 is out of range: must be at most 2147483647");
}

TEST(RequestConversions, EmitterRangesAreTheCoresAndNameTheRequestField)
{
  SpawnEmitter::Request req;
  req.name = "e";
  req.type = "explosion";
  req.rate = -3.0;
  core::EmitterDef def;
  ASSERT_TRUE(toEmitterDef(req, 1, def).ok);  // a number is converted as received...
  EXPECT_EQ(def.rate, -3.0);
  const core::Status s = core::validate(def);  // ...and refused by the core's range
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "rate = -3 is out of range: must be >= 0");

  req.rate = 10.0;
  req.speed = kNaN;
  ASSERT_TRUE(toEmitterDef(req, 1, def).ok);
  EXPECT_EQ(core::validate(def).message, "speed = nan is not a finite number");
}

TEST(RequestConversions, RopeRequestGivesItsDefinitionFieldByField)
{
  SpawnRope::Request req;
  req.name = "line";
  req.particles = 12;
  req.start = point(0.0, 1.0, 3.0);
  req.end = point(2.0, 1.0, 3.0);
  req.mass = 0.6;
  req.rest_length = 2.5;
  req.stretch_stiffness = 800.0;
  req.stretch_damping = 0.7;
  req.bend_stiffness = 30.0;
  req.bend_damping = 0.1;
  req.pins = {0, -1};
  req.tear_strain = 0.4;
  req.self_collision = true;
  req.self_collision_thickness = 0.01;
  req.integrator = "rk4";
  core::RopeDef def;
  ASSERT_TRUE(toRopeDef(req, worldDefaultIntegrator(), def).ok);
  EXPECT_EQ(def.tear_strain, 0.4);
  EXPECT_TRUE(def.self_collision.enabled);
  EXPECT_EQ(def.self_collision.thickness, 0.01);  // [m]
  EXPECT_EQ(def.name, "line");
  EXPECT_EQ(def.particles, 12);
  EXPECT_EQ(def.start, Eigen::Vector3d(0.0, 1.0, 3.0));  // [m]
  EXPECT_EQ(def.end, Eigen::Vector3d(2.0, 1.0, 3.0));    // [m]
  EXPECT_EQ(def.mass, 0.6);                              // [kg] total
  EXPECT_EQ(def.rest_length, 2.5);                       // [m]
  EXPECT_EQ(def.stretch_stiffness, 800.0);               // [N/m]
  EXPECT_EQ(def.stretch_damping, 0.7);                   // [N·s/m]
  EXPECT_EQ(def.bend_stiffness, 30.0);
  EXPECT_EQ(def.bend_damping, 0.1);
  EXPECT_EQ(def.pins, (std::vector<int>{0, -1}));
  // The named integrator, with the world default's other settings.
  EXPECT_EQ(def.integrator.type, core::kRk4Integrator);
  expectSameSettings(def.integrator, worldDefaultIntegrator());
  EXPECT_TRUE(core::validate(def, 1000).ok);
}

TEST(RequestConversions, RopeFieldsLeftAtZeroKeepTheDefaultsAndTheWorldsIntegrator)
{
  SpawnRope::Request req;
  req.name = "line";
  core::RopeDef def;
  ASSERT_TRUE(toRopeDef(req, worldDefaultIntegrator(), def).ok);
  EXPECT_EQ(def.particles, 20);           // 0 = the default, 20
  EXPECT_EQ(def.mass, 1.0);               // 0 = the default, 1 kg
  EXPECT_EQ(def.rest_length, 0.0);        // 0 = |end − start|, kept as 0
  EXPECT_EQ(def.stretch_stiffness, 0.0);  // a constant of 0 is a value
  EXPECT_TRUE(def.pins.empty());
  EXPECT_EQ(def.integrator.type, core::kVerletIntegrator);  // empty: the world's default
  expectSameSettings(def.integrator, worldDefaultIntegrator());
}

TEST(RequestConversions, RopeRefusesAnUnknownIntegratorAndTooManyParticles)
{
  SpawnRope::Request req;
  req.name = "line";
  req.integrator = "leapfrog";
  core::RopeDef def;
  core::Status s = toRopeDef(req, worldDefaultIntegrator(), def);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message,
            std::string("integrator = 'leapfrog' is not an integrator; allowed: ") + core::integratorTypeNames());

  req.integrator.clear();
  req.particles = kBeyondInt;
  s = toRopeDef(req, worldDefaultIntegrator(), def);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "particles = 2147483648 is out of range: must be at most 2147483647");

  // One particle is an int: the core's range refuses it, naming the request's field.
  req.particles = 1;
  ASSERT_TRUE(toRopeDef(req, worldDefaultIntegrator(), def).ok);
  s = core::validate(def, 1000);
  EXPECT_FALSE(s.ok);
  EXPECT_TRUE(particle_sim_test::mentions(s, "particles = 1")) << s.message;
}

TEST(RequestConversions, ClothRequestGivesItsDefinitionFieldByField)
{
  SpawnCloth::Request req;
  req.name = "flag";
  req.model = "baraff_witkin";
  req.origin = point(-1.0, 0.0, 2.0);
  req.edge_u = vector(2.0, 0.0, 0.0);
  req.edge_v = vector(0.0, 0.0, -1.0);
  req.nu = 9;
  req.nv = 6;
  req.mass = 0.3;
  req.stretch_stiffness = 1500.0;
  req.stretch_damping = 2.0;
  req.shear_stiffness = 120.0;
  req.shear_damping = 0.5;
  req.bend_stiffness = 0.01;
  req.bend_damping = 0.001;
  req.pins = {3};
  req.named_pins = {"edge_v0"};
  req.b_u = 1.1;
  req.b_v = 0.9;
  req.max_strain = 0.1;
  req.tear_strain = 0.5;
  req.self_collision = true;
  req.self_collision_thickness = 0.02;
  req.integrator = "implicit_euler";
  core::ClothGridDef def;
  ASSERT_TRUE(toClothGridDef(req, worldDefaultIntegrator(), def).ok);
  EXPECT_EQ(def.name, "flag");
  EXPECT_EQ(def.model, core::ClothModel::BaraffWitkin);
  EXPECT_EQ(def.origin, Eigen::Vector3d(-1.0, 0.0, 2.0));  // [m]
  EXPECT_EQ(def.edge_u, Eigen::Vector3d(2.0, 0.0, 0.0));   // [m]
  EXPECT_EQ(def.edge_v, Eigen::Vector3d(0.0, 0.0, -1.0));  // [m]
  EXPECT_EQ(def.nu, 9);
  EXPECT_EQ(def.nv, 6);
  EXPECT_EQ(def.mass, 0.3);  // [kg] total
  EXPECT_EQ(def.stretch.stiffness, 1500.0);
  EXPECT_EQ(def.stretch.damping, 2.0);
  EXPECT_EQ(def.shear.stiffness, 120.0);
  EXPECT_EQ(def.shear.damping, 0.5);
  EXPECT_EQ(def.bend.stiffness, 0.01);
  EXPECT_EQ(def.bend.damping, 0.001);
  EXPECT_EQ(def.pins, (std::vector<int>{3}));
  EXPECT_EQ(def.named_pins, (std::vector<std::string>{"edge_v0"}));
  EXPECT_EQ(def.b_u, 1.1);
  EXPECT_EQ(def.b_v, 0.9);
  EXPECT_EQ(def.strain_limit.max_strain, 0.1);
  EXPECT_EQ(def.tear_strain, 0.5);
  EXPECT_TRUE(def.self_collision.enabled);
  EXPECT_EQ(def.self_collision.thickness, 0.02);  // [m]
  EXPECT_EQ(def.integrator.type, core::kImplicitEulerIntegrator);
  expectSameSettings(def.integrator, worldDefaultIntegrator());
}

TEST(RequestConversions, ClothFieldsLeftAtZeroKeepTheDefaults)
{
  SpawnCloth::Request req;
  req.name = "sheet";
  core::ClothGridDef def;
  ASSERT_TRUE(toClothGridDef(req, worldDefaultIntegrator(), def).ok);
  EXPECT_EQ(def.model, core::ClothModel::Springs);  // empty = springs
  EXPECT_EQ(def.nu, 15);                            // 0 = the default, 15
  EXPECT_EQ(def.nv, 15);
  EXPECT_EQ(def.mass, 0.5);  // 0 = the default, 0.5 kg
  EXPECT_EQ(def.b_u, 1.0);   // 0 = the default, 1
  EXPECT_EQ(def.b_v, 1.0);
  EXPECT_EQ(def.strain_limit.max_strain, 0.0);  // off
  EXPECT_EQ(def.tear_strain, 0.0);              // never
  EXPECT_FALSE(def.self_collision.enabled);     // off
  // 0 = the default thickness, 0.005 m.
  EXPECT_EQ(def.self_collision.thickness, core::SelfCollisionDef{}.thickness);
  EXPECT_EQ(def.integrator.type, core::kVerletIntegrator);
}

TEST(RequestConversions, ClothRefusesAnUnknownModelIntegratorOrCount)
{
  SpawnCloth::Request req;
  req.name = "sheet";
  req.model = "silk";
  core::ClothGridDef def;
  core::Status s = toClothGridDef(req, worldDefaultIntegrator(), def);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "model = 'silk' is not a cloth model; allowed: springs, baraff_witkin");

  req.model = "springs";
  req.nv = kBeyondInt;
  s = toClothGridDef(req, worldDefaultIntegrator(), def);
  EXPECT_EQ(s.message, "nv = 2147483648 is out of range: must be at most 2147483647");

  req.nv = 0;
  req.integrator = "Verlet";  // names are lower case
  s = toClothGridDef(req, worldDefaultIntegrator(), def);
  EXPECT_FALSE(s.ok);
  EXPECT_TRUE(particle_sim_test::mentions(s, "integrator = 'Verlet' is not an integrator")) << s.message;
}

TEST(RequestConversions, JellyRequestGivesItsDefinitionFieldByField)
{
  SpawnJelly::Request req;
  req.name = "cube";
  req.origin = point(0.0, 0.0, 1.0);
  req.size = vector(0.4, 0.3, 0.2);
  req.nx = 4;
  req.ny = 3;
  req.nz = 2;
  req.mass = 2.0;
  req.stretch_stiffness = 900.0;
  req.stretch_damping = 0.9;
  req.shear_stiffness = 400.0;
  req.shear_damping = 0.4;
  req.bend_stiffness = 50.0;
  req.bend_damping = 0.05;
  req.velocity = vector(1.0, 0.0, -0.5);
  req.pins = {-1};
  req.max_strain = 0.2;
  req.tear_strain = 0.6;
  req.self_collision = true;
  req.self_collision_thickness = 0.03;
  core::JellyDef def;
  ASSERT_TRUE(toJellyDef(req, worldDefaultIntegrator(), def).ok);
  EXPECT_EQ(def.name, "cube");
  EXPECT_EQ(def.origin, Eigen::Vector3d(0.0, 0.0, 1.0));  // [m]
  EXPECT_EQ(def.size, Eigen::Vector3d(0.4, 0.3, 0.2));    // [m]
  EXPECT_EQ(def.nx, 4);
  EXPECT_EQ(def.ny, 3);
  EXPECT_EQ(def.nz, 2);
  EXPECT_EQ(def.mass, 2.0);
  EXPECT_EQ(def.stretch.stiffness, 900.0);
  EXPECT_EQ(def.stretch.damping, 0.9);
  EXPECT_EQ(def.shear.stiffness, 400.0);
  EXPECT_EQ(def.shear.damping, 0.4);
  EXPECT_EQ(def.bend.stiffness, 50.0);
  EXPECT_EQ(def.bend.damping, 0.05);
  EXPECT_EQ(def.velocity, Eigen::Vector3d(1.0, 0.0, -0.5));  // [m/s]
  EXPECT_EQ(def.pins, (std::vector<int>{-1}));
  EXPECT_EQ(def.strain_limit.max_strain, 0.2);
  EXPECT_EQ(def.tear_strain, 0.6);
  EXPECT_TRUE(def.self_collision.enabled);
  EXPECT_EQ(def.self_collision.thickness, 0.03);  // [m]
  EXPECT_EQ(def.integrator.type, core::kVerletIntegrator);
  EXPECT_TRUE(core::validate(def, 1000).ok);
}

TEST(RequestConversions, JellyKeepsDefaultsForZeroAndRefusesCountsBeyondInt)
{
  SpawnJelly::Request req;
  req.name = "cube";
  core::JellyDef def;
  ASSERT_TRUE(toJellyDef(req, worldDefaultIntegrator(), def).ok);
  EXPECT_EQ(def.nx, 5);  // 0 = the default, 5
  EXPECT_EQ(def.ny, 5);
  EXPECT_EQ(def.nz, 5);
  EXPECT_EQ(def.mass, 1.0);  // 0 = the default, 1 kg

  req.nz = kBeyondInt;
  const core::Status s = toJellyDef(req, worldDefaultIntegrator(), def);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "nz = 2147483648 is out of range: must be at most 2147483647");
}

TEST(RequestConversions, SpringClassSelectionIsOneClassOrAll)
{
  std::optional<core::SpringClass> selection = core::SpringClass::Stretch;
  ASSERT_TRUE(parseSpringClassSelection("all", selection).ok);
  EXPECT_FALSE(selection.has_value());
  ASSERT_TRUE(parseSpringClassSelection("bend", selection).ok);
  EXPECT_EQ(selection, core::SpringClass::Bend);
  ASSERT_TRUE(parseSpringClassSelection("shear", selection).ok);
  EXPECT_EQ(selection, core::SpringClass::Shear);

  const core::Status s = parseSpringClassSelection("twist", selection);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "spring_class = 'twist' is not a spring class; allowed: stretch, shear, bend, all");
  EXPECT_EQ(selection, core::SpringClass::Shear);  // unchanged by a refusal
  EXPECT_FALSE(parseSpringClassSelection("", selection).ok);
}

TEST(RequestConversions, WindIsTheRequestsVectorAndTheWorldChecksItsRange)
{
  SetWind::Request req;
  req.wind = vector(3.0, -1.5, 0.25);
  EXPECT_EQ(toWind(req), Eigen::Vector3d(3.0, -1.5, 0.25));  // [m/s]

  core::World world{core::WorldDef{}};
  req.wind = vector(1e308, 0.0, 0.0);
  const core::Status s = world.setWind(toWind(req));
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "wind.x = 1e+308 is out of range: must be in [-100, 100] m/s (wind = [1e+308, 0, 0])");
}

TEST(RequestConversions, PinByIndexOrNearestToAPoint)
{
  const core::SpringNetworkBody rope = fiveParticleRope();
  PinParticle::Request req;
  req.index = 3;
  req.target = PinParticle::Request::TARGET_CURRENT;
  PinSpec spec;
  ASSERT_TRUE(toPinSpec(req, rope, spec).ok);
  EXPECT_EQ(spec.index, 3);
  EXPECT_EQ(spec.target, PinTarget::Current);
  EXPECT_EQ(spec.point, Eigen::Vector3d(3.0, 0.0, 2.0));  // where particle 3 is

  // Index -1: the particle nearest to the point (1.2 m along the rope is particle 1), held there.
  req.index = -1;
  req.target = PinParticle::Request::TARGET_POINT;
  req.point = point(1.2, 0.3, 2.0);
  ASSERT_TRUE(toPinSpec(req, rope, spec).ok);
  EXPECT_EQ(spec.index, 1);
  EXPECT_EQ(spec.target, PinTarget::Point);
  EXPECT_EQ(spec.point, Eigen::Vector3d(1.2, 0.3, 2.0));

  // A frame: its name and the offset on it.
  req.index = 4;
  req.target = PinParticle::Request::TARGET_FRAME;
  req.frame = "gripper";
  req.offset = vector(0.0, 0.0, -0.1);
  ASSERT_TRUE(toPinSpec(req, rope, spec).ok);
  EXPECT_EQ(spec.index, 4);
  EXPECT_EQ(spec.target, PinTarget::Frame);
  EXPECT_EQ(spec.frame, "gripper");
  EXPECT_EQ(spec.offset, Eigen::Vector3d(0.0, 0.0, -0.1));  // [m]
}

TEST(RequestConversions, PinRefusesBadIndexPointTargetFrameAndOffset)
{
  const core::SpringNetworkBody rope = fiveParticleRope();
  PinParticle::Request req;
  PinSpec spec;
  req.index = 5;
  EXPECT_EQ(toPinSpec(req, rope, spec).message,
            "index = 5 is out of range: must be in [0, 4], or -1 for the particle nearest to point");
  req.index = -2;
  EXPECT_EQ(toPinSpec(req, rope, spec).message,
            "index = -2 is out of range: must be in [0, 4], or -1 for the particle nearest to point");

  req.index = -1;
  req.point = point(kNaN, 0.0, -std::numeric_limits<double>::infinity());
  EXPECT_EQ(toPinSpec(req, rope, spec).message, "point = [nan, 0, -inf] m is not finite");

  req.index = 0;
  req.target = 3;
  EXPECT_EQ(toPinSpec(req, rope, spec).message, "target = 3 is out of range: 0 (current), 1 (point) or 2 (frame)");

  req.target = PinParticle::Request::TARGET_FRAME;
  EXPECT_EQ(toPinSpec(req, rope, spec).message, "frame is empty: name the tf frame to follow");
  req.frame = "gripper";
  req.offset = vector(0.0, kNaN, 0.0);
  EXPECT_EQ(toPinSpec(req, rope, spec).message, "offset = [0, nan, 0] m is not finite");
  EXPECT_FALSE(toPinSpec(req, rope, spec).ok);
}

TEST(RequestConversions, CoreRefusalsOfSpawnsNameTheRequestsFieldNotTheDefinitions)
{
  // Each request with one field out of the core's range: the core names its definition's field,
  // inRequestTerms the request's, with the value as received and the range kept.
  SpawnRope::Request rope;
  rope.name = "line";
  rope.end = point(1.0, 0.0, 0.0);
  rope.stretch_stiffness = 1e200;
  core::RopeDef rope_def;
  ASSERT_TRUE(toRopeDef(rope, worldDefaultIntegrator(), rope_def).ok);
  const core::Status rope_refusal = core::validate(rope_def, 1000);
  ASSERT_FALSE(rope_refusal.ok);
  EXPECT_EQ(rope_refusal.message.rfind("stretch.stiffness = 1e+200", 0), 0u) << rope_refusal.message;
  EXPECT_EQ(inRequestTerms(SpawnRequest::Rope, rope_refusal).message,
            "stretch_stiffness" + rope_refusal.message.substr(std::string("stretch.stiffness").size()));

  SpawnCloth::Request cloth;
  cloth.name = "sheet";
  cloth.edge_u = vector(1.0, 0.0, 0.0);
  cloth.edge_v = vector(0.0, 1.0, 0.0);
  cloth.nu = 1;
  core::ClothGridDef cloth_def;
  ASSERT_TRUE(toClothGridDef(cloth, worldDefaultIntegrator(), cloth_def).ok);
  const core::Status cloth_refusal = inRequestTerms(SpawnRequest::Cloth, core::validate(cloth_def, 1000));
  EXPECT_EQ(cloth_refusal.message.rfind("nu = 1 is out of range", 0), 0u) << cloth_refusal.message;

  SpawnJelly::Request jelly;
  jelly.name = "cube";
  jelly.size = vector(0.5, 0.5, 0.5);
  jelly.nz = 1;
  core::JellyDef jelly_def;
  ASSERT_TRUE(toJellyDef(jelly, worldDefaultIntegrator(), jelly_def).ok);
  const core::Status jelly_refusal = inRequestTerms(SpawnRequest::Jelly, core::validate(jelly_def, 1000));
  EXPECT_EQ(jelly_refusal.message.rfind("nz = 1 is out of range", 0), 0u) << jelly_refusal.message;

  SpawnEmitter::Request emitter;
  emitter.name = "jet";
  emitter.type = "fountain";
  emitter.rate = 10.0;
  emitter.mass = -1.0;
  core::EmitterDef emitter_def;
  ASSERT_TRUE(toEmitterDef(emitter, 1, emitter_def).ok);
  const core::Status emitter_refusal = inRequestTerms(SpawnRequest::Emitter, core::validate(emitter_def));
  EXPECT_EQ(emitter_refusal.message.rfind("mass = -1 ", 0), 0u) << emitter_refusal.message;

  // A field named alike in both, and a success, pass unchanged.
  const core::Status rate = core::Status::failure("rate = -3 is out of range: must be >= 0");
  EXPECT_EQ(inRequestTerms(SpawnRequest::Emitter, rate).message, rate.message);
  EXPECT_TRUE(inRequestTerms(SpawnRequest::Rope, core::Status::success()).ok);
}

TEST(RequestConversions, SpawnColliderGivesABoxOrACapsuleAndRefusesTheOtherShapesFields)
{
  SpawnCollider::Request req;
  req.name = "table";
  req.shape = "box";
  req.pose.position = point(1, 2, 0.4);  // orientation all zero: no turn
  req.size = vector(1.2, 0.8, 0.05);
  req.friction = 0.6;
  bool is_box = false;
  core::BoxColliderDef box;
  core::CapsuleColliderDef capsule;
  ASSERT_TRUE(toColliderDef(req, is_box, box, capsule).ok);
  EXPECT_TRUE(is_box);
  EXPECT_EQ(box.name, "table");
  EXPECT_EQ(box.center, Eigen::Vector3d(1, 2, 0.4));
  EXPECT_EQ(box.half_extents, Eigen::Vector3d(0.6, 0.4, 0.025));
  EXPECT_EQ(box.orientation.coeffs(), Eigen::Quaterniond::Identity().coeffs());
  EXPECT_EQ(box.contact.friction, 0.6);
  EXPECT_EQ(box.contact.restitution, 0.0);  // taken as given
  EXPECT_TRUE(core::validate(box).ok);

  req.shape = "capsule";
  req.size = vector(0, 0, 0);
  req.length = 0.3;
  req.radius = 0.02;
  req.pose.orientation.z = std::sin(0.25);
  req.pose.orientation.w = std::cos(0.25);
  ASSERT_TRUE(toColliderDef(req, is_box, box, capsule).ok);
  EXPECT_FALSE(is_box);
  EXPECT_EQ(capsule.half_length, 0.15);
  EXPECT_EQ(capsule.radius, 0.02);
  EXPECT_NEAR(capsule.orientation.angularDistance(Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()))),
              0.0, 1e-12);

  // Refusals name the field, the value and what is allowed.
  req.shape = "cone";
  core::Status s = toColliderDef(req, is_box, box, capsule);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("shape = 'cone' is not a collider shape; allowed: box, capsule"), std::string::npos)
      << s.message;
  req.shape = "capsule";
  req.size = vector(1, 1, 1);
  s = toColliderDef(req, is_box, box, capsule);
  EXPECT_NE(s.message.find("size = [1, 1, 1] is a box's"), std::string::npos) << s.message;
  req.shape = "box";
  s = toColliderDef(req, is_box, box, capsule);
  EXPECT_NE(s.message.find("length and radius are a capsule's"), std::string::npos) << s.message;
  // A non-unit quaternion passes the conversion and is refused by the core, by name.
  req.length = req.radius = 0.0;
  req.pose.orientation.w = 3.0;
  ASSERT_TRUE(toColliderDef(req, is_box, box, capsule).ok);
  s = core::validate(box);
  EXPECT_NE(s.message.find("box 'table'.orientation"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("is not a unit quaternion"), std::string::npos) << s.message;
}

// A spawn request's tear strain out of range is refused when the body is added, as a scene's is, by
// a message that names the field, the value and the range; the world keeps what it had.
TEST(RequestConversions, SpawnedClothWithATearStrainOutOfRangeIsRefused)
{
  SpawnCloth::Request req;
  req.name = "sheet";
  req.edge_u.x = 1.0;  // [m]
  req.edge_v.y = 1.0;
  req.tear_strain = -0.5;
  core::ClothGridDef def;
  ASSERT_TRUE(toClothGridDef(req, worldDefaultIntegrator(), def).ok);
  core::World world(core::WorldDef{});
  const core::Status status = world.addClothGrid(def);
  EXPECT_FALSE(status.ok);
  EXPECT_NE(status.message.find("tear_strain = -0.5"), std::string::npos) << status.message;
  EXPECT_NE(status.message.find("[0, 100]"), std::string::npos) << status.message;
  EXPECT_TRUE(world.bodies().empty());
  req.tear_strain = 0.3;
  ASSERT_TRUE(toClothGridDef(req, worldDefaultIntegrator(), def).ok);
  EXPECT_TRUE(world.addClothGrid(def).ok);
}

// A spawn request's self-collision thickness out of range is refused when the body is added, as a
// scene's is, by a message that names the request's field, the value, the range and the unit; the
// world keeps what it had. 0 is the default thickness; a thickness beside self_collision false is
// not used, and not checked.
TEST(RequestConversions, SpawnedBodiesWithASelfCollisionThicknessOutOfRangeAreRefused)
{
  const std::string expected = "self_collision_thickness = 0.9 is out of range: must be in [0.0001, 0.5] m";
  core::World world(core::WorldDef{});

  SpawnRope::Request rope;
  rope.name = "line";
  rope.end = point(1.0, 0.0, 0.0);
  rope.self_collision = true;
  rope.self_collision_thickness = 0.9;
  core::RopeDef rope_def;
  ASSERT_TRUE(toRopeDef(rope, worldDefaultIntegrator(), rope_def).ok);
  core::Status status = inRequestTerms(SpawnRequest::Rope, world.addRope(rope_def));
  EXPECT_EQ(status.message.rfind(expected, 0), 0u) << status.message;

  SpawnCloth::Request cloth;
  cloth.name = "sheet";
  cloth.edge_u.x = 1.0;  // [m]
  cloth.edge_v.y = 1.0;
  cloth.self_collision = true;
  cloth.self_collision_thickness = 0.9;
  core::ClothGridDef cloth_def;
  ASSERT_TRUE(toClothGridDef(cloth, worldDefaultIntegrator(), cloth_def).ok);
  status = inRequestTerms(SpawnRequest::Cloth, world.addClothGrid(cloth_def));
  EXPECT_EQ(status.message.rfind(expected, 0), 0u) << status.message;

  SpawnJelly::Request jelly;
  jelly.name = "cube";
  jelly.size = vector(0.5, 0.5, 0.5);
  jelly.self_collision = true;
  jelly.self_collision_thickness = 0.9;
  core::JellyDef jelly_def;
  ASSERT_TRUE(toJellyDef(jelly, worldDefaultIntegrator(), jelly_def).ok);
  status = inRequestTerms(SpawnRequest::Jelly, world.addJelly(jelly_def));
  EXPECT_EQ(status.message.rfind(expected, 0), 0u) << status.message;
  EXPECT_TRUE(world.bodies().empty());

  // The default thickness (0), and a thickness left unused, are accepted.
  cloth.self_collision_thickness = 0.0;
  core::ClothGridDef default_thickness;
  ASSERT_TRUE(toClothGridDef(cloth, worldDefaultIntegrator(), default_thickness).ok);
  status = world.addClothGrid(default_thickness);
  EXPECT_TRUE(status.ok) << status.message;
  ASSERT_NE(world.findSpringBody("sheet"), nullptr);
  EXPECT_EQ(world.findSpringBody("sheet")->definition().self_collision.thickness, core::SelfCollisionDef{}.thickness);
  jelly.self_collision = false;
  core::JellyDef unused_thickness;
  ASSERT_TRUE(toJellyDef(jelly, worldDefaultIntegrator(), unused_thickness).ok);
  status = world.addJelly(unused_thickness);
  EXPECT_TRUE(status.ok) << status.message;
  ASSERT_NE(world.findSpringBody("cube"), nullptr);
  EXPECT_FALSE(world.findSpringBody("cube")->definition().self_collision.enabled);
}
