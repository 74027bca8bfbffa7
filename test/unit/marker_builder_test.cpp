// Markers built from the world pass rviz's own validity rules (rviz marker_utils.cpp
// checkMarkerMsg): unit quaternion, non-zero scale, alpha > 0, one colour per point, finite
// values, non-empty point lists; DELETEALL first and only when asked; DELETE for removed bodies.

#include "particle_sim/ros/marker_builder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "torn_square.h"

using namespace particle_sim;
using visualization_msgs::Marker;

namespace
{
void expectRvizValid(const Marker& m)
{
  SCOPED_TRACE("marker " + m.ns + "/" + std::to_string(m.id));
  EXPECT_FALSE(m.header.frame_id.empty());
  if (m.action != Marker::ADD) return;
  if (m.type == Marker::SPHERE)
  {
    EXPECT_GT(m.scale.x, 0.0);
    EXPECT_GT(m.color.a, 0.0f);
    return;
  }
  const auto& q = m.pose.orientation;
  EXPECT_NEAR(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w, 1.0, 1e-9);
  EXPECT_TRUE(std::isfinite(m.scale.x) && std::isfinite(m.scale.y) && std::isfinite(m.scale.z));
  EXPECT_GT(m.color.a, 0.0f);
  if (m.type == Marker::POINTS)
  {
    EXPECT_GT(m.scale.x, 0.0);
    EXPECT_GT(m.scale.y, 0.0);
  }
  if (m.type == Marker::CUBE || m.type == Marker::CYLINDER)  // shapes: a size on every axis, no points
  {
    EXPECT_GT(m.scale.x, 0.0);
    EXPECT_GT(m.scale.y, 0.0);
    EXPECT_GT(m.scale.z, 0.0);
    return;
  }
  EXPECT_FALSE(m.points.empty());
  EXPECT_TRUE(m.colors.empty() || m.colors.size() == m.points.size());
  for (const auto& p : m.points)
    EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
  for (const auto& c : m.colors)
    EXPECT_GT(c.a, 0.0f);
}

core::World makeWorld()
{
  core::WorldDef def;
  core::SphereColliderDef ball;
  ball.center = {1, 2, 3};
  ball.radius = 0.25;
  def.spheres.push_back(ball);
  core::World world{def};
  core::EmitterDef e;
  e.name = "fountain";
  e.rate = 500.0;
  EXPECT_TRUE(world.addEmitter(e).ok);
  e.name = "idle";  // emits nothing for a long time: an empty pool
  e.rate = 0.001;
  EXPECT_TRUE(world.addEmitter(e).ok);
  for (int k = 0; k < 200; ++k)
    world.step();
  return world;
}

// An emitter "f" of 100 particles/s living `lifetime` seconds.
core::EmitterDef fountainF(double lifetime)
{
  core::EmitterDef e;
  e.name = "f";
  e.rate = 100.0;
  e.lifetime = lifetime;
  return e;
}

// A network "n" of 10 particles in a row, the first pinned: 9 free particles.
core::SpringNetworkDef rowOfTen()
{
  core::SpringNetworkDef net;
  net.name = "n";
  for (int i = 0; i < 10; ++i)
  {
    net.positions.emplace_back(0.1 * i, 0.0, 1.0);
    net.masses.push_back(0.1);
  }
  net.pins = {0};
  return net;
}
}  // namespace

TEST(MarkerBuilder, EveryMarkerPassesRvizChecksWithOneNamespacePerBody)
{
  const core::World world = makeWorld();
  ros_interface::MarkerStyle style;
  const auto array = ros_interface::buildMarkers(world, ros::Time(1.0), style, false, {});
  ASSERT_EQ(array.markers.size(), 3u);
  for (const Marker& m : array.markers)
    expectRvizValid(m);

  const Marker& ball = array.markers[0];
  EXPECT_EQ(ball.ns, ros_interface::kCollidersNamespace);
  EXPECT_EQ(ball.type, Marker::SPHERE);
  EXPECT_EQ(ball.pose.position.z, 3.0);
  EXPECT_EQ(ball.scale.x, 0.5);  // the diameter

  const Marker& fountain = array.markers[1];
  EXPECT_EQ(fountain.ns, "fountain");
  EXPECT_EQ(fountain.action, Marker::ADD);
  EXPECT_EQ(fountain.type, Marker::POINTS);
  EXPECT_EQ(static_cast<int>(fountain.points.size()), world.findBody("fountain")->particles().size());
  EXPECT_EQ(fountain.points[0].x, world.findBody("fountain")->particles().position(0, 0));
  // The empty emitter sends DELETE rather than an empty POINTS list.
  EXPECT_EQ(array.markers[2].ns, "idle");
  EXPECT_EQ(array.markers[2].action, Marker::DELETE);
}

TEST(MarkerBuilder, BoxesAndCapsulesAreDrawnWhereTheyAreTurnedAsTheyAre)
{
  // A turned box is a CUBE of its full size and orientation; a capsule is a CYLINDER whose z axis
  // (rviz's) lies along the capsule's axis, between two spheres on the axis' ends.
  core::WorldDef def;
  core::BoxColliderDef box;
  box.name = "table";
  box.center = {0.5, 0.0, 0.4};
  box.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  box.half_extents = {0.6, 0.4, 0.025};
  def.boxes = {box};
  core::CapsuleColliderDef capsule;
  capsule.name = "finger";
  capsule.center = {1.0, 0.0, 1.0};
  capsule.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2.0, Eigen::Vector3d::UnitZ()));  // axis along y
  capsule.half_length = 0.15;
  capsule.radius = 0.02;
  def.capsules = {capsule};
  const core::World world{def};
  const auto array = ros_interface::buildMarkers(world, ros::Time(1.0), ros_interface::MarkerStyle(), false, {});
  ASSERT_EQ(array.markers.size(), 4u);
  for (const Marker& m : array.markers)
  {
    expectRvizValid(m);
    EXPECT_EQ(m.ns, ros_interface::kCollidersNamespace);
  }
  const Marker& cube = array.markers[0];
  EXPECT_EQ(cube.type, Marker::CUBE);
  EXPECT_EQ(cube.pose.position.x, 0.5);
  EXPECT_NEAR(cube.pose.orientation.z, std::sin(0.15), 1e-15);
  EXPECT_EQ(cube.scale.x, 1.2);
  EXPECT_EQ(cube.scale.z, 0.05);
  const Marker& cylinder = array.markers[1];
  EXPECT_EQ(cylinder.type, Marker::CYLINDER);
  const Eigen::Quaterniond q(cylinder.pose.orientation.w, cylinder.pose.orientation.x, cylinder.pose.orientation.y,
                             cylinder.pose.orientation.z);
  EXPECT_LT((q * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitY()).norm(), 1e-12) << "rviz's axis is the capsule's";
  EXPECT_NEAR(cylinder.scale.z, 0.3, 1e-15);
  EXPECT_NEAR(cylinder.scale.x, 0.04, 1e-15);
  EXPECT_EQ(array.markers[2].type, Marker::SPHERE);
  EXPECT_NEAR(array.markers[2].pose.position.y, -0.15, 1e-12);
  EXPECT_NEAR(array.markers[3].pose.position.y, 0.15, 1e-12);
  std::set<int> ids;
  for (const Marker& m : array.markers)
    ids.insert(m.id);
  EXPECT_EQ(ids.size(), 4u) << "one id per marker";
}

TEST(MarkerBuilder, DeleteAllComesFirstOnlyWhenAskedAndRemovedBodiesGetDelete)
{
  const core::World world = makeWorld();
  const auto array = ros_interface::buildMarkers(world, ros::Time(2.0), {}, true, {"gone"});
  ASSERT_GE(array.markers.size(), 3u);
  EXPECT_EQ(array.markers[0].action, Marker::DELETEALL);
  EXPECT_EQ(array.markers[0].ns, "");
  EXPECT_EQ(array.markers[1].action, Marker::DELETE);
  EXPECT_EQ(array.markers[1].ns, "gone");
  for (std::size_t i = 1; i < array.markers.size(); ++i)
    EXPECT_NE(array.markers[i].action, Marker::DELETEALL);
  for (const Marker& m : array.markers)
    EXPECT_EQ(m.header.stamp, ros::Time(2.0));
}

TEST(MarkerBuilder, ParticlesAreColouredByAge)
{
  core::World world{core::WorldDef{}};
  ASSERT_TRUE(world.addEmitter(fountainF(1.0)).ok);
  for (int k = 0; k < 900; ++k)
    world.step();
  const auto array = ros_interface::buildMarkers(world, ros::Time(1.0), {}, false, {});
  const auto& p = world.findBody("f")->particles();
  const Marker& m = array.markers[0];
  // Older particles are less green.
  int oldest = 0, youngest = 0;
  for (int i = 0; i < p.size(); ++i)
  {
    if (p.age[i] > p.age[oldest]) oldest = i;
    if (p.age[i] < p.age[youngest]) youngest = i;
  }
  EXPECT_LT(m.colors[oldest].g, m.colors[youngest].g);
}

TEST(MarkerBuilder, AParticleMarkerHoldsAtMostMaxPointsEveryKthParticle)
{
  // An emitter with about 100 live particles, markers capped at 30 points: every ⌈n/30⌉ = 4th
  // particle, 25 points, each where its particle is; a cap at the count draws them all.
  core::World world{core::WorldDef{}};
  ASSERT_TRUE(world.addEmitter(fountainF(10.0)).ok);
  for (int k = 0; k < 1000; ++k)
    world.step();
  const auto& p = world.findBody("f")->particles();
  ASSERT_GT(p.size(), 90);
  ASSERT_LE(p.size(), 120);
  ros_interface::MarkerStyle style;
  style.max_points = 30;
  const Marker capped = ros_interface::buildMarkers(world, ros::Time(1.0), style, false, {}).markers[0];
  const std::size_t expected = (p.size() + 3) / 4;  // ⌈n / 4⌉ points
  ASSERT_EQ(capped.points.size(), expected);
  ASSERT_EQ(capped.colors.size(), expected);
  for (std::size_t k = 0; k < capped.points.size(); ++k)
  {
    EXPECT_EQ(capped.points[k].x, p.position(0, 4 * k));
    EXPECT_EQ(capped.points[k].z, p.position(2, 4 * k));
  }
  style.max_points = p.size();
  EXPECT_EQ(ros_interface::buildMarkers(world, ros::Time(1.0), style, false, {}).markers[0].points.size(),
            static_cast<std::size_t>(p.size()));

  // A network's free particles alike (its pinned ones always all drawn).
  core::World net_world{core::WorldDef{}};
  ASSERT_TRUE(net_world.addSpringNetwork(rowOfTen()).ok);
  style.max_points = 4;  // 9 free particles: every 3rd, 3 points
  const auto markers = ros_interface::buildMarkers(net_world, ros::Time(1.0), style, false, {}).markers;
  EXPECT_EQ(markers[ros_interface::kParticlesMarkerId].points.size(), 3u);
  EXPECT_EQ(markers[ros_interface::kPinsMarkerId].points.size(), 1u);
}

TEST(MarkerBuilder, DeferredMarkersShowTheWorldAsItWasWhenBuiltWhateverItDoesMeanwhile)
{
  // The node builds the array at a tick and the publishing thread writes the emitters' points while
  // the physics steps on: finished after 50 more steps, the array still equals, field by field, the
  // one built whole at the tick; and the samples' vectors serve the next array, of another size.
  core::World world = makeWorld();
  ros_interface::MarkerStyle style;
  style.max_points = 40;  // the fountain's particles decimated
  ros_interface::MarkerSamples samples;
  auto deferred = ros_interface::buildMarkersDeferred(world, ros::Time(3.0), style, true, {"gone"}, samples);
  const auto whole = ros_interface::buildMarkers(world, ros::Time(3.0), style, true, {"gone"});
  const core::Body& fountain = *world.findBody("fountain");
  const Eigen::Vector3d first_then = fountain.particles().position.col(0);
  for (int k = 0; k < 50; ++k)
    world.step();
  ASSERT_NE(fountain.particles().position.col(0), first_then);
  ros_interface::finishMarkers(samples, deferred);
  ASSERT_EQ(deferred.markers.size(), whole.markers.size());
  for (std::size_t m = 0; m < whole.markers.size(); ++m)
  {
    SCOPED_TRACE("marker " + whole.markers[m].ns);
    EXPECT_EQ(deferred.markers[m], whole.markers[m]);
  }
  const Marker& fountain_marker = whole.markers[samples.emitters[0].marker];
  EXPECT_EQ(fountain_marker.ns, "fountain");
  ASSERT_FALSE(fountain_marker.points.empty());
  EXPECT_EQ(fountain_marker.points[0].x, first_then.x());

  style.max_points = 1000000;  // all of them now: longer sample vectors
  auto next = ros_interface::buildMarkersDeferred(world, ros::Time(4.0), style, false, {}, samples);
  ros_interface::finishMarkers(samples, next);
  const auto next_whole = ros_interface::buildMarkers(world, ros::Time(4.0), style, false, {});
  EXPECT_EQ(next, next_whole);
  EXPECT_EQ(samples.used, 2u);  // the fountain and the idle emitter
}

TEST(MarkerBuilder, TheEmittersOwnStepSnapshotsTheParticlesTheMarkersDraw)
{
  // Asked before a step, each emitter copies its drawn particles as it steps; the array built from
  // those copies equals the one built from the world after the step. The copy is what the array
  // uses (a value changed in it shows); a request taken back before the step is not used, and the
  // particles are copied from the world instead.
  core::World world = makeWorld();
  ros_interface::MarkerStyle style;
  style.max_points = 40;
  ros_interface::MarkerSamples samples;
  ros_interface::snapshotNextStep(world, style, samples);
  world.step();
  ros_interface::forgetSnapshotRequests(world);
  ASSERT_GE(samples.emitters.size(), 2u);
  const int fountain_count = world.findBody("fountain")->particles().size();
  EXPECT_EQ(samples.emitters[0].particles.stride, ros_interface::decimationStride(fountain_count, 40));
  auto from_step = ros_interface::buildMarkersDeferred(world, ros::Time(5.0), style, false, {}, samples);
  ros_interface::finishMarkers(samples, from_step);
  EXPECT_EQ(from_step, ros_interface::buildMarkers(world, ros::Time(5.0), style, false, {}));

  ros_interface::snapshotNextStep(world, style, samples);
  world.step();
  ros_interface::forgetSnapshotRequests(world);
  samples.emitters[0].particles.position[0] = 123.0;
  auto marked = ros_interface::buildMarkersDeferred(world, ros::Time(6.0), style, false, {}, samples);
  ros_interface::finishMarkers(samples, marked);
  EXPECT_EQ(marked.markers[samples.emitters[0].marker].points[0].x, 123.0);

  ros_interface::snapshotNextStep(world, style, samples);
  ros_interface::forgetSnapshotRequests(world);
  world.step();
  auto copied = ros_interface::buildMarkersDeferred(world, ros::Time(7.0), style, false, {}, samples);
  ros_interface::finishMarkers(samples, copied);
  EXPECT_EQ(copied, ros_interface::buildMarkers(world, ros::Time(7.0), style, false, {}));
}

TEST(MarkerBuilder, BodiesShareMaxPointsFairlyAndASmallBodyIsDrawnWhole)
{
  // A fountain of about 100 live particles beside a 10-particle network with one pin (9 free), and
  // 40 points for both: the network fits in its half and is drawn whole; the fountain gets the 31
  // points left, every ⌈n / 31⌉-th particle.
  core::World world{core::WorldDef{}};
  ASSERT_TRUE(world.addEmitter(fountainF(10.0)).ok);
  ASSERT_TRUE(world.addSpringNetwork(rowOfTen()).ok);
  for (int k = 0; k < 1000; ++k)
    world.step();
  const int live = world.findBody("f")->particles().size();
  ASSERT_GT(live, 90);
  ros_interface::MarkerStyle style;
  style.max_points = 40;
  const auto markers = ros_interface::buildMarkers(world, ros::Time(1.0), style, false, {}).markers;
  std::size_t fountain_points = 0, network_points = 0;
  for (const Marker& m : markers)
  {
    if (m.ns == "f") fountain_points += m.points.size();
    if (m.ns == "n" && m.id == ros_interface::kParticlesMarkerId) network_points += m.points.size();
  }
  EXPECT_EQ(network_points, 9u);
  const int stride = (live + 30) / 31;  // ⌈live / 31⌉
  EXPECT_EQ(fountain_points, static_cast<std::size_t>((live + stride - 1) / stride));
  EXPECT_LE(fountain_points + network_points, 40u);
}

TEST(MarkerBuilder, SharedStridesStayWithinTheBudgetAndDrawWholeEveryBodyUnderAnEqualShare)
{
  // Bodies of many sizes against many budgets, checked against what the strides promise: the
  // points drawn add up to at most the budget (when it allows one point per body), a body no larger
  // than an equal share is drawn whole, and no stride is larger than the one an equal share gives.
  const std::vector<int> counts = {0, 7, 100000, 250, 3, 99999, 1, 40000, 12, 0, 600};
  const int bodies = static_cast<int>(std::count_if(counts.begin(), counts.end(), [](int c) { return c > 0; }));
  for (int budget : {9, 10, 37, 1000, 20000, 200000, 300000, 10000000})
  {
    const std::vector<int> strides = ros_interface::decimationStrides(counts, budget);
    ASSERT_EQ(strides.size(), counts.size());
    long long drawn = 0;
    for (std::size_t b = 0; b < counts.size(); ++b)
    {
      ASSERT_GE(strides[b], 1);
      drawn += (counts[b] + strides[b] - 1) / strides[b];
      if (counts[b] <= budget / bodies)
      {
        EXPECT_EQ(strides[b], 1) << "count " << counts[b] << " budget " << budget;
      }
      EXPECT_LE(strides[b], ros_interface::decimationStride(counts[b], std::max(1, budget / bodies)));
    }
    if (budget >= bodies)
    {
      EXPECT_LE(drawn, budget) << "budget " << budget;
    }
  }
  // One body keeps the single-marker rule.
  EXPECT_EQ(ros_interface::decimationStrides({1000}, 30), std::vector<int>{34});
}

TEST(MarkerBuilder, RopeIsALineStripWithFreeAndPinnedParticlesApart)
{
  core::World world{core::WorldDef{}};
  core::RopeDef rope;
  rope.name = "rope";
  rope.particles = 7;
  rope.pins = {0, -1};
  ASSERT_TRUE(world.addRope(rope).ok);
  core::SpringNetworkDef net;
  net.name = "net";
  net.positions = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  net.masses = {1, 1, 1};
  net.springs = {{0, 1, 1.0, 10, 0, core::SpringClass::Stretch}, {1, 2, 1.4, 10, 0, core::SpringClass::Shear}};
  ASSERT_TRUE(world.addSpringNetwork(net).ok);
  world.step();

  const auto array = ros_interface::buildMarkers(world, ros::Time(1.0), {}, false, {});
  ASSERT_EQ(array.markers.size(), 6u);
  for (const Marker& m : array.markers)
    expectRvizValid(m);
  const Marker& free = array.markers[0];
  const Marker& line = array.markers[1];
  const Marker& pins = array.markers[2];
  EXPECT_EQ(free.type, Marker::SPHERE_LIST);
  EXPECT_EQ(free.points.size(), 5u);
  EXPECT_EQ(line.type, Marker::LINE_STRIP);
  ASSERT_EQ(line.points.size(), 7u);
  EXPECT_EQ(line.points[3].x, world.findBody("rope")->particles().position(0, 3));
  EXPECT_EQ(pins.id, ros_interface::kPinsMarkerId);
  EXPECT_EQ(pins.points.size(), 2u);
  EXPECT_EQ(pins.points[1].x, 2.0);  // the last particle, at the rope's end

  // The network: LINE_LIST with a pair of points per spring, and no pinned particle (DELETE).
  EXPECT_EQ(array.markers[4].type, Marker::LINE_LIST);
  EXPECT_EQ(array.markers[4].points.size(), 4u);
  EXPECT_EQ(array.markers[5].action, Marker::DELETE);

  // Removing a body deletes all its marker ids.
  const auto removed = ros_interface::buildMarkers(world, ros::Time(1.0), {}, false, {"rope"});
  for (int id = 0; id < ros_interface::kMarkerIdsPerBody; ++id)
  {
    EXPECT_EQ(removed.markers[id].ns, "rope");
    EXPECT_EQ(removed.markers[id].id, id);
    EXPECT_EQ(removed.markers[id].action, Marker::DELETE);
  }
}

TEST(MarkerBuilder, ClothAndJellySurfacesAreShadedTriangleListsThatPassRvizChecks)
{
  core::World world{core::WorldDef{}};
  core::ClothGridDef cloth;
  cloth.name = "cloth";
  cloth.nu = 4;
  cloth.nv = 3;
  cloth.named_pins = {"corner_00"};
  ASSERT_TRUE(world.addClothGrid(cloth).ok);
  core::JellyDef jelly;
  jelly.name = "jelly";
  jelly.nx = jelly.ny = jelly.nz = 3;
  ASSERT_TRUE(world.addJelly(jelly).ok);
  world.step();

  for (bool by_strain : {false, true})
  {
    ros_interface::MarkerStyle style;
    style.color_by_strain = by_strain;
    const auto array = ros_interface::buildMarkers(world, ros::Time(1.0), style, false, {});
    ASSERT_EQ(array.markers.size(), 6u);
    for (const Marker& m : array.markers)
      expectRvizValid(m);
    const Marker& surface = array.markers[1];
    EXPECT_EQ(surface.type, Marker::TRIANGLE_LIST);
    EXPECT_EQ(surface.points.size() % 3, 0u);
    EXPECT_EQ(surface.points.size(), 3u * 2u * 2u * 3u);  // 3 x 2 cells, 2 triangles, 3 points
    ASSERT_EQ(surface.colors.size(), surface.points.size());
    // A sheet still nearly flat after one step: every vertex nearly the same normal, so the same
    // shade (or strain colour, blue for no strain).
    for (const auto& c : surface.colors)
    {
      EXPECT_NEAR(c.r, surface.colors[0].r, 1e-3);
      EXPECT_NEAR(c.b, surface.colors[0].b, 1e-3);
    }
    if (by_strain)
    {
      EXPECT_NEAR(surface.colors[0].b, 1.0f, 1e-3);
    }
    EXPECT_EQ(array.markers[0].action, Marker::DELETE);  // no particle spheres for a surface body
    EXPECT_EQ(array.markers[2].points.size(), 1u);       // the pinned corner
    EXPECT_EQ(array.markers[4].type, Marker::TRIANGLE_LIST);
    EXPECT_EQ(array.markers[4].points.size(), 6u * 4u * 2u * 3u);  // 6 faces of 2 x 2 quads
  }
}

TEST(MarkerBuilder, ATornSurfaceAndATornRopeAreDrawnAsTheyAreLeft)
{
  // The square's surface: only the triangle (0, 1, 2) is left.
  const core::World square = particle_sim_test::tornSquareWorld();
  const auto drawn = ros_interface::buildMarkers(square, ros::Time(1.0), {}, false, {});
  ASSERT_EQ(drawn.markers.size(), 3u);
  for (const Marker& m : drawn.markers)
    expectRvizValid(m);
  const Marker& surface = drawn.markers[1];
  EXPECT_EQ(surface.type, Marker::TRIANGLE_LIST);
  ASSERT_EQ(surface.points.size(), 3u);
  const core::ParticlePool& p = square.bodies()[0]->particles();
  for (int c = 0; c < 3; ++c)
    EXPECT_EQ(surface.points[c].z, p.position(2, c));
  EXPECT_EQ(drawn.markers[2].points.size(), 3u);       // the pins, particle 3's too
  EXPECT_EQ(drawn.markers[0].action, Marker::DELETE);  // no free particle is off the surface

  // Released, particle 3 (in no triangle now, still held by the bend spring 1-3) is drawn as a sphere.
  core::World released = particle_sim_test::tornSquareWorld();
  ASSERT_TRUE(released.findSpringBody("square")->unpin(3).ok);
  const auto loose = ros_interface::buildMarkers(released, ros::Time(1.0), {}, false, {});
  ASSERT_EQ(loose.markers.size(), 3u);
  expectRvizValid(loose.markers[0]);
  ASSERT_EQ(loose.markers[0].points.size(), 1u);
  EXPECT_EQ(loose.markers[0].points[0].z, released.bodies()[0]->particles().position(2, 3));
  EXPECT_EQ(loose.markers[2].points.size(), 2u);

  // A rope whose last segment tore: a LINE_LIST of the segments left, no line across the break.
  core::World world{core::WorldDef{}};
  core::RopeDef rope;
  rope.name = "rope";
  rope.particles = 7;
  rope.pins = {0, -1};
  rope.tear_strain = 0.5;
  ASSERT_TRUE(world.addRope(rope).ok);
  core::SpringNetworkBody& body = *world.findSpringBody("rope");
  ASSERT_TRUE(body.setPinTarget(6, body.pinTarget(6) + Eigen::Vector3d(1.0, 0.0, 0.0)).ok);
  world.step();
  ASSERT_EQ(body.tornSprings(), 1);
  const auto array = ros_interface::buildMarkers(world, ros::Time(1.0), {}, false, {});
  ASSERT_EQ(array.markers.size(), 3u);
  for (const Marker& m : array.markers)
    expectRvizValid(m);
  const Marker& line = array.markers[1];
  EXPECT_EQ(line.type, Marker::LINE_LIST);
  ASSERT_EQ(line.points.size(), 2u * 5u);  // segments 0-1 ... 4-5
  EXPECT_EQ(line.points[9].x, body.particles().position(0, 5));
}

TEST(MarkerBuilder, StrainColoursGoFromBlueToRed)
{
  const auto none = ros_interface::strainColor(0.0, 0.1);
  const auto half = ros_interface::strainColor(0.05, 0.1);
  const auto full = ros_interface::strainColor(0.3, 0.1);
  EXPECT_EQ(none.b, 1.0f);
  EXPECT_EQ(none.r, 0.0f);
  EXPECT_EQ(half.g, 1.0f);
  EXPECT_EQ(full.r, 1.0f);
  EXPECT_EQ(full.b, 0.0f);
}
