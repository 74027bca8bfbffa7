// Cloth: buildClothGrid lays out Provot's grid (particles, masses, stretch/shear/bend springs,
// triangles, named pins) and buildMeshCloth one spring per mesh edge and one bend spring per
// interior edge, validate refuses every bad field by name, vertex normals and strains match
// closed forms, Provot's strain limit holds after every step without moving pins, cloth drapes
// over a sphere without ever entering it or the ground (and lies there with no speed), a moved
// sphere pushes it out, the air pushes with drag·A·((wind − v)·n) along the normal only, and a
// hanging cloth settles to a dt-independent equilibrium that implicit Euler approaches at first
// order.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/builders/mesh_cloth.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/rk4.h"
#include "particle_sim/core/integrators/symplectic_euler.h"
#include "particle_sim/core/surface.h"
#include "particle_sim/core/world.h"
#include "test_helpers.h"

using namespace particle_sim::core;

using particle_sim_test::countClass;
using particle_sim_test::kNaN;
using particle_sim_test::mentions;

namespace
{

std::pair<int, int> sortedPair(int i, int j)
{
  return {std::min(i, j), std::max(i, j)};
}

double maxSpeed(const SpringNetworkBody& body)
{
  const ParticlePool& p = body.particles();
  return p.velocity.leftCols(p.size()).colwise().norm().maxCoeff();
}

// A valid, non-axis-aligned grid.
ClothGridDef tiltedGrid(int nu, int nv)
{
  ClothGridDef def;
  def.name = "cloth";
  def.origin = {1.0, -2.0, 3.0};
  def.edge_u = {2.0, 0.0, 0.5};
  def.edge_v = {0.3, 1.5, -0.2};
  def.nu = nu;
  def.nv = nv;
  def.mass = 1.3;
  def.stretch = {800.0, 0.4};
  def.shear = {150.0, 0.15};
  def.bend = {12.0, 0.03};
  return def;
}

// The particle (a, b) of a grid def, computed from the documented layout.
Eigen::Vector3d gridPoint(const ClothGridDef& def, int a, int b)
{
  return def.origin + def.edge_u * (static_cast<double>(a) / (def.nu - 1)) +
         def.edge_v * (static_cast<double>(b) / (def.nv - 1));
}

Eigen::Vector3d triangleAreaNormal(const std::vector<Eigen::Vector3d>& x, const Eigen::Vector3i& t)
{
  return 0.5 * (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
}

// A flat n x n vertex grid of unit cells in the xy plane, each cell split along its (0,0)-(1,1)
// diagonal, as a triangle mesh.
MeshClothDef meshGrid(int n)
{
  MeshClothDef def;
  def.name = "mesh";
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < n; ++a)
      def.vertices.emplace_back(a, b, 1.0);
  for (int b = 0; b + 1 < n; ++b)
    for (int a = 0; a + 1 < n; ++a)
    {
      const int i00 = b * n + a, i10 = i00 + 1, i01 = i00 + n, i11 = i01 + 1;
      def.triangles.emplace_back(i00, i10, i11);
      def.triangles.emplace_back(i00, i11, i01);
    }
  return def;
}

// Spring pairs of one class as a set of sorted index pairs.
std::set<std::pair<int, int>> pairsOfClass(const std::vector<Spring>& springs, SpringClass spring_class)
{
  std::set<std::pair<int, int>> out;
  for (const Spring& s : springs)
    if (s.spring_class == spring_class) out.insert(sortedPair(s.i, s.j));
  return out;
}

// Brute force over triangle pairs: two triangles sharing exactly two vertices (an interior edge)
// give the pair of their two unshared vertices.
std::set<std::pair<int, int>> expectedBendPairs(const std::vector<Eigen::Vector3i>& triangles)
{
  std::set<std::pair<int, int>> out;
  for (std::size_t p = 0; p < triangles.size(); ++p)
    for (std::size_t q = p + 1; q < triangles.size(); ++q)
    {
      std::vector<int> only_p, only_q;
      for (int c = 0; c < 3; ++c)
      {
        const int vp = triangles[p][c], vq = triangles[q][c];
        if ((triangles[q].array() != vp).all()) only_p.push_back(vp);
        if ((triangles[p].array() != vq).all()) only_q.push_back(vq);
      }
      if (only_p.size() == 1 && only_q.size() == 1) out.insert(sortedPair(only_p[0], only_q[0]));
    }
  return out;
}

// Unique undirected edges of a triangle list.
std::set<std::pair<int, int>> meshEdges(const std::vector<Eigen::Vector3i>& triangles)
{
  std::set<std::pair<int, int>> out;
  for (const Eigen::Vector3i& t : triangles)
    for (int c = 0; c < 3; ++c)
      out.insert(sortedPair(t[c], t[(c + 1) % 3]));
  return out;
}
}  // namespace

// ---------------------------------------------------------------------------------------------
// Grid cloth: layout

TEST(ClothGrid, BuildPlacesParticlesOnTheGridWithEqualMasses)
{
  ClothGridDef def = tiltedGrid(5, 4);
  def.integrator.type = kRk4Integrator;
  def.strain_limit.max_strain = 0.07;
  def.strain_limit.iterations = 33;
  ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
  const SpringNetworkDef net = buildClothGrid(def);
  EXPECT_EQ(net.name, "cloth");
  EXPECT_EQ(net.shape, NetworkShape::Cloth);
  EXPECT_EQ(net.integrator.type, kRk4Integrator);
  EXPECT_EQ(net.strain_limit.max_strain, 0.07);
  EXPECT_EQ(net.strain_limit.iterations, 33);
  ASSERT_EQ(net.positions.size(), 20u);
  ASSERT_EQ(net.masses.size(), 20u);
  for (const Eigen::Vector3d& v : net.velocities)
    EXPECT_EQ(v.norm(), 0.0);
  double total = 0.0;
  for (int b = 0; b < 4; ++b)
    for (int a = 0; a < 5; ++a)
    {
      const int index = b * 5 + a;
      EXPECT_LE((net.positions[index] - gridPoint(def, a, b)).norm(), 1e-12) << "particle (" << a << ", " << b << ")";
      EXPECT_NEAR(net.masses[index], 1.3 / 20, 1e-15);
      total += net.masses[index];
    }
  EXPECT_NEAR(total, 1.3, 1e-12);
  // The four corners are origin, origin + edge_u, origin + edge_v and origin + edge_u + edge_v.
  EXPECT_LE((net.positions[0] - def.origin).norm(), 1e-12);
  EXPECT_LE((net.positions[4] - (def.origin + def.edge_u)).norm(), 1e-12);
  EXPECT_LE((net.positions[15] - (def.origin + def.edge_v)).norm(), 1e-12);
  EXPECT_LE((net.positions[19] - (def.origin + def.edge_u + def.edge_v)).norm(), 1e-12);
  EXPECT_TRUE(net.pins.empty());
  EXPECT_TRUE(validate(net, 100).ok) << validate(net, 100).message;
}

TEST(ClothGrid, SpringCountsPerClassFollowProvotsLayout)
{
  const std::pair<int, int> sizes[] = {{2, 2}, {3, 2}, {2, 3}, {4, 5}, {7, 3}, {6, 6}};
  for (const auto& [nu, nv] : sizes)
  {
    for (double bend_stiffness : {12.0, 0.0})
    {
      ClothGridDef def = tiltedGrid(nu, nv);
      def.bend.stiffness = bend_stiffness;
      ASSERT_TRUE(validate(def, 1000).ok) << validate(def, 1000).message;
      const SpringNetworkDef net = buildClothGrid(def);
      const std::string where =
          std::to_string(nu) + "x" + std::to_string(nv) + " bend " + std::to_string(bend_stiffness);

      const int stretch = (nu - 1) * nv + nu * (nv - 1);
      const int shear = 2 * (nu - 1) * (nv - 1);
      const int bend = bend_stiffness > 0.0 ? std::max(0, nu - 2) * nv + nu * std::max(0, nv - 2) : 0;
      EXPECT_EQ(countClass(net.springs, SpringClass::Stretch), stretch) << where;
      EXPECT_EQ(countClass(net.springs, SpringClass::Shear), shear) << where;
      EXPECT_EQ(countClass(net.springs, SpringClass::Bend), bend) << where;
      EXPECT_EQ(static_cast<int>(net.springs.size()), stretch + shear + bend) << where;

      // Each spring joins the grid offsets of its class once, at its initial length, with its
      // class's constants.
      std::set<std::pair<int, int>> seen;
      for (const Spring& s : net.springs)
      {
        ASSERT_TRUE(s.i >= 0 && s.i < nu * nv && s.j >= 0 && s.j < nu * nv) << where;
        EXPECT_TRUE(seen.insert(sortedPair(s.i, s.j)).second) << where << ": duplicate spring " << s.i << "-" << s.j;
        const int da = std::abs(s.i % nu - s.j % nu), db = std::abs(s.i / nu - s.j / nu);
        EXPECT_NEAR(s.rest_length, (net.positions[s.j] - net.positions[s.i]).norm(), 1e-12) << where;
        switch (s.spring_class)
        {
          case SpringClass::Stretch:
            EXPECT_EQ(da + db, 1) << where;
            EXPECT_EQ(s.stiffness, 800.0);
            EXPECT_EQ(s.damping, 0.4);
            break;
          case SpringClass::Shear:
            EXPECT_TRUE(da == 1 && db == 1) << where;
            EXPECT_EQ(s.stiffness, 150.0);
            EXPECT_EQ(s.damping, 0.15);
            break;
          case SpringClass::Bend:
            EXPECT_TRUE((da == 2 && db == 0) || (da == 0 && db == 2)) << where;
            EXPECT_EQ(s.stiffness, 12.0);
            EXPECT_EQ(s.damping, 0.03);
            break;
        }
      }
    }
  }
}

TEST(ClothGrid, TwoTrianglesPerCellAllFacingEdgeUCrossEdgeV)
{
  for (const auto& [nu, nv] : {std::pair<int, int>{2, 2}, {5, 4}, {3, 7}})
  {
    const ClothGridDef def = tiltedGrid(nu, nv);
    const SpringNetworkDef net = buildClothGrid(def);
    ASSERT_EQ(static_cast<int>(net.triangles.size()), 2 * (nu - 1) * (nv - 1));
    const Eigen::Vector3d plane_normal = def.edge_u.cross(def.edge_v);
    double area = 0.0;
    std::set<std::vector<int>> unique;
    for (const Eigen::Vector3i& t : net.triangles)
    {
      ASSERT_TRUE((t.array() >= 0).all() && (t.array() < nu * nv).all());
      const Eigen::Vector3d an = triangleAreaNormal(net.positions, t);
      // Parallel to edge_u x edge_v and pointing the same way.
      EXPECT_GT(an.dot(plane_normal), 0.0);
      EXPECT_LE(an.cross(plane_normal).norm(), 1e-12 * an.norm() * plane_normal.norm());
      area += an.norm();
      std::vector<int> key = {t[0], t[1], t[2]};
      std::sort(key.begin(), key.end());
      EXPECT_TRUE(unique.insert(key).second) << "triangle listed twice";
    }
    // The triangles tile the parallelogram exactly.
    EXPECT_NEAR(area, plane_normal.norm(), 1e-12);
  }
}

TEST(ClothGrid, NamedPinsCoverTheDocumentedCornersAndEdges)
{
  const int nu = 4, nv = 3;  // index = b * 4 + a
  const std::vector<std::pair<std::string, std::vector<int>>> expected = {
      {"corner_00", {0}},        {"corner_10", {3}},          {"corner_01", {8}},
      {"corner_11", {11}},       {"edge_u0", {0, 4, 8}},      {"edge_u1", {3, 7, 11}},  // the sides at u = 0 and u = 1
      {"edge_v0", {0, 1, 2, 3}}, {"edge_v1", {8, 9, 10, 11}},                           // the sides at v = 0 and v = 1
  };
  for (const auto& [name, indices] : expected)
  {
    std::vector<int> got = {99};  // must be replaced, not appended to
    ASSERT_TRUE(namedGridPins(name, nu, nv, got)) << name;
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, indices) << name;
    EXPECT_NE(std::string(namedGridPinNames()).find(name), std::string::npos) << name;
  }
  std::vector<int> unknown;
  EXPECT_FALSE(namedGridPins("corner_22", nu, nv, unknown));
  EXPECT_FALSE(namedGridPins("", nu, nv, unknown));

  // Named and indexed pins together, each particle once, negative indices from the end.
  ClothGridDef def = tiltedGrid(nu, nv);
  def.named_pins = {"edge_v1", "corner_11", "corner_00"};
  def.pins = {-1, 0, 5, 5};
  ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
  std::vector<int> pins = buildClothGrid(def).pins;
  std::sort(pins.begin(), pins.end());
  EXPECT_EQ(pins, (std::vector<int>{0, 5, 8, 9, 10, 11}));

  // A built body holds exactly those particles.
  SpringNetworkBody body(buildClothGrid(def));
  EXPECT_EQ(body.pinnedCount(), 6);
  for (int i : {0, 5, 8, 9, 10, 11})
    EXPECT_TRUE(body.isPinned(i)) << i;
}

TEST(ClothGrid, ValidateRefusesBadFieldsNamingThem)
{
  const ClothGridDef good = tiltedGrid(5, 4);
  ASSERT_TRUE(validate(good, 20).ok) << validate(good, 20).message;  // exactly at the cap

  struct Case
  {
    const char* what;
    void (*edit)(ClothGridDef&);
    std::vector<std::string> words;  // the message must name all of these
  };
  const Case cases[] = {
      {"nu < 2", [](ClothGridDef& d) { d.nu = 1; }, {"resolution[0]", "1"}},
      {"nv < 2", [](ClothGridDef& d) { d.nv = 0; }, {"resolution[1]", "0"}},
      {"parallel edges", [](ClothGridDef& d) { d.edge_v = -2.5 * d.edge_u; }, {"edge_u", "edge_v", "parallel"}},
      {"zero edge_u", [](ClothGridDef& d) { d.edge_u.setZero(); }, {"edge_u"}},
      {"NaN edge_v", [](ClothGridDef& d) { d.edge_v.x() = kNaN; }, {"edge_v"}},
      {"NaN origin", [](ClothGridDef& d) { d.origin.z() = kNaN; }, {"origin"}},
      {"negative stretch stiffness", [](ClothGridDef& d) { d.stretch.stiffness = -1.0; }, {"stretch.stiffness", "-1"}},
      {"negative shear stiffness", [](ClothGridDef& d) { d.shear.stiffness = -2.0; }, {"shear.stiffness", "-2"}},
      {"negative bend stiffness", [](ClothGridDef& d) { d.bend.stiffness = -3.0; }, {"bend.stiffness", "-3"}},
      {"negative shear damping", [](ClothGridDef& d) { d.shear.damping = -0.5; }, {"shear.damping"}},
      {"unknown pin name",
       [](ClothGridDef& d) {
         d.named_pins = {"corner_00", "top_left"};
       },
       {"top_left"}},
      {"pin index out of range", [](ClothGridDef& d) { d.pins = {20}; }, {"pins[0]", "20"}},
      {"too many particles", [](ClothGridDef& d) { d.nu = 7; }, {"resolution", "28", "20"}},
      {"zero mass", [](ClothGridDef& d) { d.mass = 0.0; }, {"mass"}},
      {"negative max_strain", [](ClothGridDef& d) { d.strain_limit.max_strain = -0.1; }, {"max_strain"}},
      {"empty name", [](ClothGridDef& d) { d.name.clear(); }, {"name"}},
  };
  for (const Case& c : cases)
  {
    ClothGridDef def = good;
    c.edit(def);
    const Status status = validate(def, 20);
    EXPECT_FALSE(status.ok) << c.what;
    for (const std::string& word : c.words)
      EXPECT_TRUE(mentions(status, word)) << c.what << ": " << status.message;
  }

  // The world refuses the same definitions and adds nothing.
  WorldDef world_def;
  world_def.max_particles_per_body = 20;
  World world(world_def);
  ClothGridDef bad = good;
  bad.named_pins = {"top_left"};
  EXPECT_FALSE(world.addClothGrid(bad).ok);
  EXPECT_TRUE(world.bodies().empty());
  EXPECT_TRUE(world.addClothGrid(good).ok);
  ASSERT_NE(world.findSpringBody("cloth"), nullptr);
  EXPECT_EQ(world.findSpringBody("cloth")->shape(), NetworkShape::Cloth);
}

// ---------------------------------------------------------------------------------------------
// Mesh cloth

TEST(ClothMesh, TwoTrianglesMakeFiveStretchSpringsAndOneBendAcrossTheDiagonal)
{
  MeshClothDef def;
  def.name = "square";
  def.vertices = {{0, 0, 1}, {2, 0, 1}, {2, 1, 1}, {0, 1, 1}};
  def.triangles = {{0, 1, 2}, {0, 2, 3}};
  def.mass = 0.8;
  def.stretch = {500.0, 0.25};
  def.bend = {7.0, 0.01};
  def.pins = {-1};
  ASSERT_TRUE(validate(def, 10).ok) << validate(def, 10).message;
  const SpringNetworkDef net = buildMeshCloth(def);
  EXPECT_EQ(net.shape, NetworkShape::Cloth);
  EXPECT_EQ(net.positions, def.vertices);
  EXPECT_EQ(net.triangles, def.triangles);
  for (double m : net.masses)
    EXPECT_NEAR(m, 0.2, 1e-15);
  EXPECT_EQ(net.pins, std::vector<int>{3});

  EXPECT_EQ(pairsOfClass(net.springs, SpringClass::Stretch),
            (std::set<std::pair<int, int>>{{0, 1}, {1, 2}, {0, 2}, {2, 3}, {0, 3}}));
  EXPECT_EQ(pairsOfClass(net.springs, SpringClass::Bend), (std::set<std::pair<int, int>>{{1, 3}}));
  ASSERT_EQ(net.springs.size(), 6u);
  for (const Spring& s : net.springs)
  {
    EXPECT_NEAR(s.rest_length, (def.vertices[s.j] - def.vertices[s.i]).norm(), 1e-12);
    const SpringConstants& c = s.spring_class == SpringClass::Bend ? def.bend : def.stretch;
    EXPECT_EQ(s.stiffness, c.stiffness);
    EXPECT_EQ(s.damping, c.damping);
  }
  // The bend spring spans the other diagonal: sqrt(5).
  for (const Spring& s : net.springs)
  {
    if (s.spring_class == SpringClass::Bend)
    {
      EXPECT_NEAR(s.rest_length, std::sqrt(5.0), 1e-12);
    }
  }

  // No bend stiffness, no bend springs.
  def.bend.stiffness = 0.0;
  EXPECT_EQ(countClass(buildMeshCloth(def).springs, SpringClass::Bend), 0);
  EXPECT_EQ(buildMeshCloth(def).springs.size(), 5u);
}

TEST(ClothMesh, GridMeshHasOneStretchPerEdgeAndOneBendPerInteriorEdge)
{
  for (int n : {3, 4})
  {
    MeshClothDef def = meshGrid(n);
    // Move the vertices off the plane so that rest lengths differ from spring to spring.
    for (std::size_t k = 0; k < def.vertices.size(); ++k)
      def.vertices[k].z() += 0.1 * std::sin(1.7 * k);
    ASSERT_TRUE(validate(def, 100).ok) << validate(def, 100).message;
    const SpringNetworkDef net = buildMeshCloth(def);

    // Closed forms for an n x n grid split once per cell: 2 n (n − 1) axis edges + (n − 1)²
    // diagonals, of which 4 (n − 1) are on the boundary.
    const int edges = 2 * n * (n - 1) + (n - 1) * (n - 1);
    const int interior = edges - 4 * (n - 1);
    const std::set<std::pair<int, int>> stretch = pairsOfClass(net.springs, SpringClass::Stretch);
    const std::set<std::pair<int, int>> bend = pairsOfClass(net.springs, SpringClass::Bend);
    EXPECT_EQ(countClass(net.springs, SpringClass::Stretch), edges) << n;
    EXPECT_EQ(countClass(net.springs, SpringClass::Bend), interior) << n;
    EXPECT_EQ(stretch, meshEdges(def.triangles)) << n;
    EXPECT_EQ(bend, expectedBendPairs(def.triangles)) << n;
    EXPECT_EQ(static_cast<int>(stretch.size()), edges) << n;  // no edge twice
    EXPECT_EQ(countClass(net.springs, SpringClass::Shear), 0);
    for (const Spring& s : net.springs)
      EXPECT_NEAR(s.rest_length, (def.vertices[s.j] - def.vertices[s.i]).norm(), 1e-12);
    EXPECT_TRUE(validate(net, 100).ok) << validate(net, 100).message;
  }
}

TEST(ClothMesh, ValidateRefusesBadTrianglesAndFields)
{
  MeshClothDef good;
  good.name = "square";
  good.vertices = {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  good.triangles = {{0, 1, 2}, {0, 2, 3}};
  ASSERT_TRUE(validate(good, 10).ok) << validate(good, 10).message;

  struct Case
  {
    const char* what;
    void (*edit)(MeshClothDef&);
    std::vector<std::string> words;
  };
  const Case cases[] = {
      {"index past the end",
       [](MeshClothDef& d) {
         d.triangles[1] = {0, 2, 4};
       },
       {"triangles[1]", "4"}},
      {"negative index",
       [](MeshClothDef& d) {
         d.triangles[1] = {-1, 2, 3};
       },
       {"triangles[1]", "-1"}},
      {"repeated vertex",
       [](MeshClothDef& d) {
         d.triangles[0] = {0, 1, 0};
       },
       {"triangles[0]"}},
      {"all one vertex",
       [](MeshClothDef& d) {
         d.triangles[1] = {2, 2, 2};
       },
       {"triangles[1]"}},
      {"no triangles", [](MeshClothDef& d) { d.triangles.clear(); }, {"triangles"}},
      {"two vertices",
       [](MeshClothDef& d) {
         d.vertices.resize(2);
         d.triangles.clear();
       },
       {"vertices"}},
      {"NaN vertex", [](MeshClothDef& d) { d.vertices[2].y() = kNaN; }, {"vertices[2]"}},
      {"pin out of range", [](MeshClothDef& d) { d.pins = {4}; }, {"pins[0]"}},
      {"negative stretch stiffness", [](MeshClothDef& d) { d.stretch.stiffness = -5.0; }, {"stretch.stiffness"}},
      {"negative bend damping", [](MeshClothDef& d) { d.bend.damping = -1.0; }, {"bend.damping"}},
      {"too many vertices",
       [](MeshClothDef& d) { d.vertices.resize(11, Eigen::Vector3d(3, 3, 3)); },
       {"vertices", "11"}},
  };
  for (const Case& c : cases)
  {
    MeshClothDef def = good;
    c.edit(def);
    const Status status = validate(def, 10);
    EXPECT_FALSE(status.ok) << c.what;
    for (const std::string& word : c.words)
      EXPECT_TRUE(mentions(status, word)) << c.what << ": " << status.message;
  }
  World world(WorldDef{});
  MeshClothDef bad = good;
  bad.triangles[0] = {0, 1, 7};
  EXPECT_FALSE(world.addMeshCloth(bad).ok);
  EXPECT_TRUE(world.bodies().empty());
  EXPECT_TRUE(world.addMeshCloth(good).ok);
}

// ---------------------------------------------------------------------------------------------
// Normals and strains

TEST(ClothNormals, FlatSheetsHaveTheirPlaneNormalAtEveryVertex)
{
  ClothGridDef flat;
  flat.name = "flat";
  flat.nu = 6;
  flat.nv = 4;
  ClothGridDef tilted = tiltedGrid(5, 7);
  for (const ClothGridDef& def : {flat, tilted})
  {
    SpringNetworkBody body(buildClothGrid(def));
    const Eigen::Vector3d expected = def.edge_u.cross(def.edge_v).normalized();
    std::vector<Eigen::Vector3d> normals = {Eigen::Vector3d::Constant(7.0)};
    vertexNormals(body.particles().position, body.particles().size(), body.definition().triangles, normals);
    ASSERT_EQ(static_cast<int>(normals.size()), def.nu * def.nv);
    for (std::size_t i = 0; i < normals.size(); ++i)
    {
      EXPECT_NEAR(normals[i].norm(), 1.0, 1e-12) << def.name << " vertex " << i;
      EXPECT_LE((normals[i] - expected).norm(), 1e-12) << def.name << " vertex " << i;
    }
  }
}

TEST(ClothNormals, FoldedVerticesAverageTheirTrianglesByArea)
{
  // Triangle A = (0, 1, 2), area 2, in the plane z = 0: (x1 − x0) × (x2 − x0) = (0, 0, 4), facing +z.
  // Triangle B = (0, 3, 1), area 3, in the plane y = 0: (x3 − x0) × (x1 − x0) = (0, 6, 0), facing +y.
  // They share the edge 0-1 along x; vertex 4 is in no triangle.
  Eigen::Matrix3Xd x(3, 5);
  x.col(0) = Eigen::Vector3d(0, 0, 0);
  x.col(1) = Eigen::Vector3d(2, 0, 0);
  x.col(2) = Eigen::Vector3d(0, 2, 0);
  x.col(3) = Eigen::Vector3d(0, 0, 3);
  x.col(4) = Eigen::Vector3d(5, 5, 5);
  const std::vector<Eigen::Vector3i> triangles = {{0, 1, 2}, {0, 3, 1}};
  const Eigen::Vector3d na = Eigen::Vector3d::UnitZ(), nb = Eigen::Vector3d::UnitY();
  std::vector<Eigen::Vector3d> normals;
  vertexNormals(x, 5, triangles, normals);
  ASSERT_EQ(normals.size(), 5u);
  // The shared vertices: the area-weighted mean direction (2 na + 3 nb) / |2 na + 3 nb|.
  const Eigen::Vector3d shared = (2.0 * na + 3.0 * nb).normalized();
  EXPECT_LE((normals[0] - shared).norm(), 1e-12);
  EXPECT_LE((normals[1] - shared).norm(), 1e-12);
  EXPECT_LE((normals[2] - na).norm(), 1e-12);
  EXPECT_LE((normals[3] - nb).norm(), 1e-12);
  EXPECT_EQ(normals[4], Eigen::Vector3d::Zero());
}

TEST(ClothStrain, VertexStrainsAreZeroAtRestAndMatchAUniformStretch)
{
  const ClothGridDef def = tiltedGrid(5, 4);
  SpringNetworkDef net = buildClothGrid(def);
  {
    SpringNetworkBody body(net);
    std::vector<double> strains;
    vertexStrains(body, strains);
    ASSERT_EQ(strains.size(), 20u);
    for (double s : strains)
      EXPECT_NEAR(s, 0.0, 1e-12);
    EXPECT_NEAR(body.maxStrain(), 0.0, 1e-12);
  }
  // Rest lengths shortened by 1/1.1: every stretch and shear spring is 10 % long.
  for (Spring& s : net.springs)
    s.rest_length /= 1.1;
  SpringNetworkBody body(net);
  std::vector<double> strains;
  vertexStrains(body, strains);
  ASSERT_EQ(strains.size(), 20u);
  for (double s : strains)
    EXPECT_NEAR(s, 0.1, 1e-12);
  EXPECT_NEAR(body.maxStrain(), 0.1, 1e-12);

  // Only the bend springs shortened: no strain is reported (bend springs are not measured).
  SpringNetworkDef bend_only = buildClothGrid(def);
  for (Spring& s : bend_only.springs)
    if (s.spring_class == SpringClass::Bend) s.rest_length /= 1.5;
  SpringNetworkBody bent(bend_only);
  vertexStrains(bent, strains);
  for (double s : strains)
    EXPECT_NEAR(s, 0.0, 1e-12);
  EXPECT_NEAR(bent.maxStrain(), 0.0, 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Provot's strain limit

namespace
{
// A soft horizontal cloth pinned at two adjacent corners: it falls and swings, and its springs
// near the pins stretch far beyond 10 % unless limited.
ClothGridDef softCloth(IntegratorType type, double max_strain)
{
  ClothGridDef def;
  def.name = "soft";
  def.origin = {0.0, 0.0, 2.0};
  def.edge_u = {1.0, 0.0, 0.0};
  def.edge_v = {0.0, 1.0, 0.0};
  def.nu = 9;
  def.nv = 9;
  def.mass = 0.5;
  def.stretch = {10.0, 0.01};
  def.shear = {5.0, 0.01};
  def.bend = {0.5, 0.0};
  def.named_pins = {"corner_00", "corner_10"};
  def.strain_limit.max_strain = max_strain;
  // Gauss-Seidel relaxation converges slowly on a sheet hanging from two points: 100 passes leave
  // it up to 1.7 % over the limit at dt = 1/60; with enough passes the limit is met exactly.
  def.strain_limit.iterations = 1000;
  def.integrator.type = type;
  return def;
}

struct StrainRun
{
  double largest_strain = 0.0;  // over every step
  double pin_motion = 0.0;      // largest distance of a pinned particle from its start
  bool frozen = false;
};

StrainRun runSoftCloth(IntegratorType type, double max_strain, double dt, double duration)
{
  const ClothGridDef def = softCloth(type, max_strain);
  EXPECT_TRUE(validate(def, 1000).ok) << validate(def, 1000).message;
  SpringNetworkBody body(buildClothGrid(def));
  Environment env;
  env.ground.enabled = false;
  const std::vector<int> pins = body.definition().pins;
  EXPECT_EQ(pins, (std::vector<int>{0, 8}));
  StrainRun run;
  const int steps = static_cast<int>(std::lround(duration / dt));
  for (int k = 0; k < steps; ++k)
  {
    body.step(dt, env);
    run.largest_strain = std::max(run.largest_strain, body.maxStrain());
    for (int pin : pins)
      run.pin_motion =
          std::max(run.pin_motion, (body.particles().position.col(pin) - body.definition().positions[pin]).norm());
  }
  run.frozen = body.frozen();
  return run;
}
}  // namespace

TEST(ClothStrainLimit, ProvotKeepsEveryStepWithinTheLimitUnderSymplecticEuler)
{
  const double dt = 5e-4, duration = 1.0;
  const StrainRun unlimited = runSoftCloth(kSymplecticEulerIntegrator, 0.0, dt, duration);
  ASSERT_FALSE(unlimited.frozen);
  EXPECT_GT(unlimited.largest_strain, 0.3) << "the test cloth must stretch well past the limit without it";

  const StrainRun limited = runSoftCloth(kSymplecticEulerIntegrator, 0.1, dt, duration);
  EXPECT_FALSE(limited.frozen);
  EXPECT_LE(limited.largest_strain, 0.1 * (1.0 + 1e-6));
  EXPECT_GT(limited.largest_strain, 0.09) << "the limit should be reached, not avoided";
  EXPECT_EQ(limited.pin_motion, 0.0);
}

TEST(ClothStrainLimit, ProvotKeepsEveryStepWithinTheLimitUnderImplicitEuler)
{
  const double dt = 1.0 / 60.0, duration = 2.0;
  const StrainRun unlimited = runSoftCloth(kImplicitEulerIntegrator, 0.0, dt, duration);
  ASSERT_FALSE(unlimited.frozen);
  EXPECT_GT(unlimited.largest_strain, 0.3) << "the test cloth must stretch well past the limit without it";

  const StrainRun limited = runSoftCloth(kImplicitEulerIntegrator, 0.1, dt, duration);
  EXPECT_FALSE(limited.frozen);
  EXPECT_LE(limited.largest_strain, 0.1 * (1.0 + 1e-6));
  EXPECT_GT(limited.largest_strain, 0.09) << "the limit should be reached, not avoided";
  EXPECT_EQ(limited.pin_motion, 0.0);
}

// ---------------------------------------------------------------------------------------------
// Colliders

namespace
{
bool insideSomething(const Eigen::Vector3d& x, const Environment& env, std::string& why)
{
  if (env.ground.enabled && x.z() < env.ground.height - 1e-9)
  {
    why = "below the ground at z = " + std::to_string(x.z());
    return true;
  }
  for (const SphereColliderDef& s : env.spheres)
  {
    const double distance = (x - s.center).norm();
    if (distance < s.radius - 1e-9)
    {
      why = "inside sphere '" + s.name + "' at depth " + std::to_string(s.radius - distance);
      return true;
    }
  }
  return false;
}
}  // namespace

namespace
{
// A 2 m sheet dropped centred onto a sphere of radius 0.4 m whose top is at 0.82 m: it drapes over
// it and its corners reach the ground.
struct Drape
{
  explicit Drape(const ContactDef& contact) : world(makeDef(contact))
  {
    ClothGridDef def;
    def.name = "sheet";
    def.origin = {-1.0, -1.0, 0.95};
    def.edge_u = {2.0, 0.0, 0.0};
    def.edge_v = {0.0, 2.0, 0.0};
    def.nu = 11;
    def.nv = 11;
    def.integrator.type = kImplicitEulerIntegrator;
    EXPECT_TRUE(world.addClothGrid(def).ok);
    body = world.findSpringBody("sheet");
  }
  static WorldDef makeDef(const ContactDef& contact)
  {
    WorldDef def;
    def.dt = 1.0 / 200.0;
    SphereColliderDef sphere;
    sphere.name = "ball";
    sphere.center = {0.0, 0.0, 0.42};
    sphere.radius = 0.4;
    sphere.contact = contact;
    def.spheres = {sphere};
    def.ground.contact = contact;
    EXPECT_TRUE(validate(def).ok);
    return def;
  }

  World world;
  SpringNetworkBody* body = nullptr;
  static constexpr int kCentre = 5 * 11 + 5;
  static constexpr double kTop = 0.82;
};
}  // namespace

TEST(ClothCollision, ClothDroppedOnASphereDrapesWithoutEverEnteringItOrTheGround)
{
  Drape drape{ContactDef{}};
  const SpringNetworkBody& body = *drape.body;
  const int corners[] = {0, 10, 110, 120};
  bool touched_ground = false;
  for (int k = 0; k < 600; ++k)
  {
    drape.world.step();
    const ParticlePool& p = body.particles();
    for (int i = 0; i < p.size(); ++i)
    {
      std::string why;
      ASSERT_FALSE(insideSomething(p.position.col(i), drape.world.environment(), why))
          << "particle " << i << " after step " << k + 1 << ": " << why;
      touched_ground = touched_ground || p.position(2, i) < 1e-3;
    }
  }
  ASSERT_FALSE(body.frozen()) << body.frozenReason();
  EXPECT_TRUE(touched_ground) << "the corners should reach the ground, so that the ground check is exercised";
  const ParticlePool& p = body.particles();
  // The centre rests on top of the sphere.
  EXPECT_GE(p.position(2, Drape::kCentre), Drape::kTop - 1e-9);
  EXPECT_NEAR(p.position(2, Drape::kCentre), Drape::kTop, 0.01);
  EXPECT_LE(p.position.col(Drape::kCentre).head<2>().norm(), 1e-6) << "the centre stays above the sphere's top";
  // The corners hang well below it.
  for (int c : corners)
    EXPECT_LT(p.position(2, c), p.position(2, Drape::kCentre) - 0.5) << "corner " << c;
}

// Once the sheet lies still on the sphere, the particle on top does not move; the velocity it
// reports must say so. With restitution 0 it does. With the default restitution 0.5 the stiff
// springs pull the top particle into the sphere within every step and the contact reflects that
// pull as an outward "bounce" velocity, step after step.
TEST(ClothCollision, ParticleLyingStillOnTheSphereReportsNoSpeed)
{
  for (double restitution : {0.0, 0.5})
  {
    ContactDef contact;
    contact.restitution = restitution;
    Drape drape(contact);
    for (int k = 0; k < 500; ++k)
      drape.world.step();
    const Eigen::Vector3d before = drape.body->particles().position.col(Drape::kCentre);
    double speed = 0.0;
    for (int k = 0; k < 100; ++k)
    {
      drape.world.step();
      speed = std::max(speed, drape.body->particles().velocity.col(Drape::kCentre).norm());
    }
    const Eigen::Vector3d after = drape.body->particles().position.col(Drape::kCentre);
    ASSERT_FALSE(drape.body->frozen());
    // It lies still: it moved less than 1 mm in 0.5 s ...
    ASSERT_LE((after - before).norm(), 1e-3) << "restitution " << restitution;
    // ... so its speed is small at every step (0.05 m/s would carry it 2.5 cm in 0.5 s).
    EXPECT_LT(speed, 0.05) << "restitution " << restitution << ": the top particle of a sheet lying still on the "
                           << "sphere reports a speed of " << speed << " m/s";
  }
}

TEST(ClothCollision, MovingTheSpherePushesTheClothOutOfIt)
{
  WorldDef world_def;
  world_def.dt = 1.0 / 200.0;
  world_def.gravity.setZero();
  world_def.ground.enabled = false;
  SphereColliderDef sphere;
  sphere.name = "tool";
  sphere.center = {0.0, 3.0, 1.0};  // far from the cloth
  sphere.radius = 0.3;
  world_def.spheres = {sphere};
  World world(world_def);

  // A vertical sheet in the plane y = 0 hanging from its top edge.
  ClothGridDef def;
  def.name = "curtain";
  def.origin = {-0.5, 0.0, 1.5};
  def.edge_u = {1.0, 0.0, 0.0};
  def.edge_v = {0.0, 0.0, -1.0};
  def.nu = 11;
  def.nv = 11;
  def.named_pins = {"edge_v0"};
  ASSERT_TRUE(world.addClothGrid(def).ok);
  const SpringNetworkBody& body = *world.findSpringBody("curtain");
  const Eigen::Matrix3Xd start = body.particles().position;

  EXPECT_FALSE(world.setSphereCenter("nope", Eigen::Vector3d::Zero()).ok);
  EXPECT_FALSE(world.setSphereCenter("tool", Eigen::Vector3d(kNaN, 0, 0)).ok);
  // Move the sphere so that its centre is 0.1 m behind the sheet's middle.
  const Eigen::Vector3d moved(0.0, -0.1, 1.0);
  ASSERT_TRUE(world.setSphereCenter("tool", moved).ok);
  EXPECT_EQ(world.environment().spheres[0].center, moved);
  int inside_before = 0;
  for (int i = 0; i < body.particles().size(); ++i)
    inside_before += (start.col(i) - moved).norm() < sphere.radius;
  ASSERT_GT(inside_before, 5) << "the moved sphere must overlap the sheet for the test to mean anything";

  for (int k = 0; k < 20; ++k)
  {
    world.step();
    const ParticlePool& p = body.particles();
    for (int i = 0; i < p.size(); ++i)
    {
      std::string why;
      ASSERT_FALSE(insideSomething(p.position.col(i), world.environment(), why))
          << "particle " << i << " after step " << k + 1 << ": " << why;
    }
  }
  // The overlapped particles were pushed towards +y, away from the centre behind the sheet.
  const ParticlePool& p = body.particles();
  const int middle = 5 * 11 + 5;
  EXPECT_GT(p.position(1, middle) - start(1, middle), 0.1);
  for (int pin : body.definition().pins)
    EXPECT_EQ(p.position.col(pin), start.col(pin));
}

// ---------------------------------------------------------------------------------------------
// Air

namespace
{
// A free flat cloth in a world without gravity or ground, stepped by symplectic Euler.
struct AirWorld
{
  explicit AirWorld(const AirDef& air, const Eigen::Vector3d& edge_u, const Eigen::Vector3d& edge_v)
      : world(makeDef(air))
  {
    ClothGridDef def;
    def.name = "sail";
    def.origin = {0.0, 0.0, 2.0};
    def.edge_u = edge_u;
    def.edge_v = edge_v;
    def.nu = 6;
    def.nv = 6;
    def.mass = 0.5;
    def.integrator.type = kSymplecticEulerIntegrator;
    EXPECT_TRUE(world.addClothGrid(def).ok);
    body = world.findSpringBody("sail");
    area = edge_u.cross(edge_v).norm();
    normal = edge_u.cross(edge_v).normalized();
  }
  static WorldDef makeDef(const AirDef& air)
  {
    WorldDef def;
    def.dt = 1e-3;
    def.gravity.setZero();
    def.ground.enabled = false;
    def.air = air;
    return def;
  }
  void run(double duration)
  {
    const int steps = static_cast<int>(std::lround(duration / world.dt()));
    for (int k = 0; k < steps; ++k)
      world.step();
  }

  World world;
  SpringNetworkBody* body = nullptr;
  double area = 0.0;
  Eigen::Vector3d normal;
};
}  // namespace

TEST(ClothAir, WindAlongTheNormalPushesWithDragTimesAreaTimesWind)
{
  // Tilted sheet; the wind has a normal part 2 m/s and an in-plane part 3 m/s.
  const Eigen::Vector3d edge_u(1.0, 0.0, 0.3), edge_v(0.0, 0.8, 0.0);
  const Eigen::Vector3d normal = edge_u.cross(edge_v).normalized();
  const Eigen::Vector3d in_plane = edge_u.normalized();
  AirDef air;
  air.drag = 0.05;
  air.wind = 2.0 * normal + 3.0 * in_plane;
  AirWorld w(air, edge_u, edge_v);
  const double t = 0.1;
  w.run(t);
  ASSERT_FALSE(w.body->frozen());
  // A flat sheet moving as one at speed s along n: M ds/dt = drag A (2 − s), so
  // p(t) = 2 M (1 − exp(−drag A t / M)) ≈ drag A 2 t (0.4 % less here).
  const double mass = 0.5;
  const double linear = air.drag * w.area * 2.0 * t;
  const double exact = 2.0 * mass * (1.0 - std::exp(-air.drag * w.area * t / mass));
  const Eigen::Vector3d p = w.body->momentum();
  EXPECT_NEAR(p.dot(normal), linear, 0.02 * linear);
  EXPECT_NEAR(p.dot(normal), exact, 0.01 * exact);
  // Only along the normal: the in-plane wind pushes nothing.
  EXPECT_LE((p - p.dot(normal) * normal).norm(), 1e-3 * p.norm());

  // Wind against the normal pushes the other way just as hard.
  air.wind = -2.0 * normal;
  AirWorld back(air, edge_u, edge_v);
  back.run(t);
  EXPECT_NEAR(back.body->momentum().dot(normal), -p.dot(normal), 1e-3 * p.norm());
}

TEST(ClothAir, WindInThePlaneOrZeroDragGivesNoForce)
{
  const Eigen::Vector3d edge_u(1.0, 0.0, 0.0), edge_v(0.0, 0.8, 0.0);  // the plane z = 2
  AirDef in_plane;
  in_plane.drag = 0.5;
  in_plane.wind = {3.0, -1.0, 0.0};
  AirWorld a(in_plane, edge_u, edge_v);
  a.run(0.1);
  EXPECT_LE(a.body->momentum().norm(), 1e-12);
  EXPECT_LE(maxSpeed(*a.body), 1e-12);

  AirDef still;
  still.drag = 0.0;
  still.wind = {0.0, 0.0, 5.0};
  AirWorld b(still, edge_u, edge_v);
  b.run(0.1);
  EXPECT_EQ(b.body->momentum().norm(), 0.0);
  EXPECT_EQ(maxSpeed(*b.body), 0.0);
}

TEST(ClothAir, SetWindChangesTheForceFromTheNextStep)
{
  const Eigen::Vector3d edge_u(1.0, 0.0, 0.0), edge_v(0.0, 0.8, 0.0);
  AirDef air;
  air.drag = 0.05;  // and no wind yet
  AirWorld w(air, edge_u, edge_v);
  w.run(0.05);
  EXPECT_LE(w.body->momentum().norm(), 1e-12);

  ASSERT_TRUE(w.world.setWind(Eigen::Vector3d(0.0, 0.0, -2.0)).ok);
  EXPECT_EQ(w.world.environment().air.wind, Eigen::Vector3d(0.0, 0.0, -2.0));
  EXPECT_FALSE(w.world.setWind(Eigen::Vector3d(0.0, kNaN, 0.0)).ok);
  EXPECT_EQ(w.world.environment().air.wind, Eigen::Vector3d(0.0, 0.0, -2.0));
  w.run(0.1);
  const double expected = -air.drag * w.area * 2.0 * 0.1;
  EXPECT_NEAR(w.body->momentum().z(), expected, 0.02 * std::abs(expected));
  EXPECT_LE(w.body->momentum().head<2>().norm(), 1e-9);
}

// ---------------------------------------------------------------------------------------------
// Hanging cloth

namespace
{
// A vertical sheet in the plane y = 0 pinned at its two top corners; gravity stays in its plane,
// so it stays in it too.
ClothGridDef hangingCloth(IntegratorType type)
{
  ClothGridDef def;
  def.name = "hanging";
  def.origin = {-0.4, 0.0, 2.0};
  def.edge_u = {0.8, 0.0, 0.0};
  def.edge_v = {0.0, 0.0, -0.8};
  def.nu = 7;
  def.nv = 7;
  def.mass = 0.3;
  def.stretch = {300.0, 1.0};
  def.shear = {100.0, 0.5};
  def.bend = {10.0, 0.1};
  def.named_pins = {"corner_00", "corner_10"};
  def.integrator.type = type;
  return def;
}

const int kBottomCentre = 6 * 7 + 3;

// Runs a hanging cloth for `duration` at step `dt`; returns the whole final state.
Eigen::Matrix3Xd hang(IntegratorType type, double dt, double duration, double* final_speed = nullptr,
                      double* residual = nullptr)
{
  SpringNetworkBody body(buildClothGrid(hangingCloth(type)));
  Environment env;
  env.ground.enabled = false;
  const int steps = static_cast<int>(std::lround(duration / dt));
  for (int k = 0; k < steps; ++k)
    body.step(dt, env);
  EXPECT_FALSE(body.frozen()) << body.frozenReason();
  if (final_speed) *final_speed = maxSpeed(body);
  if (residual)
  {
    // Net force on the free particles, relative to one particle's weight.
    const ParticlePool& p = body.particles();
    Eigen::Matrix3Xd force(3, p.size());
    body.computeForces(p.position.leftCols(p.size()), p.velocity.leftCols(p.size()), env.gravity, force);
    double worst = 0.0;
    for (int i = 0; i < p.size(); ++i)
      if (!body.isPinned(i)) worst = std::max(worst, force.col(i).norm());
    *residual = worst / (0.3 / 49 * 9.81);
  }
  return body.particles().position;
}
}  // namespace

TEST(ClothHanging, ImplicitEulerApproachesTheFineStepMotionAtFirstOrder)
{
  // The sheet mid-fall at t = 0.25 s, against RK4 at a step 16 times finer than the finest here.
  const double t = 0.25;
  const Eigen::Matrix3Xd reference = hang(kRk4Integrator, 1.0 / 25600.0, t);
  std::vector<double> errors;
  for (double dt : {1.0 / 400.0, 1.0 / 800.0, 1.0 / 1600.0})
  {
    const Eigen::Matrix3Xd x = hang(kImplicitEulerIntegrator, dt, t);
    errors.push_back((x.col(kBottomCentre) - reference.col(kBottomCentre)).norm());
  }
  for (std::size_t k = 0; k + 1 < errors.size(); ++k)
  {
    // First order: halving dt halves the error (1.7, 1.84, ... towards 2 as dt shrinks).
    const double ratio = errors[k] / errors[k + 1];
    EXPECT_GT(ratio, 1.6) << "dt halving " << k << ": " << errors[k] << " -> " << errors[k + 1];
    EXPECT_LT(ratio, 2.5) << "dt halving " << k << ": " << errors[k] << " -> " << errors[k + 1];
  }
  EXPECT_GT(errors.front(), 1e-4) << "the comparison time must be mid-motion, not at rest";
}

TEST(ClothHanging, StaticEquilibriumDoesNotDependOnTheStep)
{
  // Settled under implicit Euler at three steps, and under symplectic Euler: the same static
  // equilibrium (net force zero on every free particle) every time.
  std::vector<Eigen::Vector3d> bottoms;
  for (double dt : {1.0 / 100.0, 1.0 / 200.0, 1.0 / 400.0})
  {
    double speed = 0.0, residual = 0.0;
    const Eigen::Matrix3Xd x = hang(kImplicitEulerIntegrator, dt, 8.0, &speed, &residual);
    EXPECT_LT(speed, 1e-4) << "dt " << dt;
    EXPECT_LT(residual, 1e-3) << "dt " << dt;
    bottoms.push_back(x.col(kBottomCentre));
  }
  double speed = 0.0, residual = 0.0;
  const Eigen::Matrix3Xd explicit_x = hang(kSymplecticEulerIntegrator, 1.0 / 2000.0, 8.0, &speed, &residual);
  EXPECT_LT(speed, 1e-4);
  EXPECT_LT(residual, 1e-3);
  bottoms.push_back(explicit_x.col(kBottomCentre));

  // The sheet sags: its bottom centre is below where it started, in the plane, on the axis.
  const Eigen::Vector3d start = buildClothGrid(hangingCloth(kImplicitEulerIntegrator)).positions[kBottomCentre];
  EXPECT_LT(bottoms[0].z(), start.z() - 1e-3);
  EXPECT_NEAR(bottoms[0].x(), 0.0, 1e-6);
  EXPECT_EQ(bottoms[0].y(), 0.0);
  for (std::size_t k = 1; k < bottoms.size(); ++k)
    EXPECT_LE((bottoms[k] - bottoms[0]).norm(), 1e-5) << "run " << k << " settled elsewhere";
}
