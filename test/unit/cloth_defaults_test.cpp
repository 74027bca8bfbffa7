// A cloth's defaults are the core's, whichever front-end fills the definition: a scene file that
// names only the model, and a spawn_cloth request that leaves its "0 = the default" fields at 0,
// build the same network, spring by spring and condition by condition, as the C++ definition
// `ClothGridDef d; d.model = model;` (defaults defined once, in the core).

#include <gtest/gtest.h>

#include <string>
#include <variant>

#include "network_expectations.h"
#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/builders/mesh_cloth.h"
#include "particle_sim/ros/request_conversions.h"
#include "particle_sim/scene/scene.h"

using namespace particle_sim;
using core::ClothGridDef;
using core::ClothModel;
using core::MeshClothDef;
using particle_sim_test::expectSameNetwork;

namespace
{
// The one body of a scene file, read.
template <typename Def>
Def readOneBody(const std::string& yaml)
{
  scene::SceneDef scene;
  const core::Status status = scene::parseScene(yaml, "test.yaml", scene);
  EXPECT_TRUE(status.ok) << status.message;
  EXPECT_EQ(scene.bodies.size(), 1u);
  const Def* def = scene.bodies.empty() ? nullptr : std::get_if<Def>(&scene.bodies.front());
  EXPECT_NE(def, nullptr);
  return def ? *def : Def();
}

template <typename Def>
Def withModel(ClothModel model)
{
  Def def;
  def.name = "c";
  def.model = model;
  return def;
}
}  // namespace

TEST(ClothDefaults, SceneFileGridClothGetsTheDefinitionsDefaults)
{
  for (ClothModel model : {ClothModel::BaraffWitkin, ClothModel::Springs})
  {
    SCOPED_TRACE(core::toString(model));
    const ClothGridDef from_scene = readOneBody<ClothGridDef>(
        std::string("bodies:\n  - {name: c, kind: cloth, model: ") + core::toString(model) + "}\n");
    expectSameNetwork(core::buildClothGrid(from_scene), core::buildClothGrid(withModel<ClothGridDef>(model)));
  }
}

TEST(ClothDefaults, SceneFileMeshClothGetsTheDefinitionsDefaults)
{
  for (ClothModel model : {ClothModel::BaraffWitkin, ClothModel::Springs})
  {
    SCOPED_TRACE(core::toString(model));
    const MeshClothDef from_scene = readOneBody<MeshClothDef>(
        std::string("bodies:\n  - name: c\n    kind: cloth\n    model: ") + core::toString(model) +
        "\n    vertices: [[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]\n"
        "    triangles: [[0, 1, 2], [0, 2, 3]]\n    uvs: [[0, 0], [1, 0], [1, 1], [0, 1]]\n");
    MeshClothDef def = withModel<MeshClothDef>(model);
    def.vertices = from_scene.vertices;
    def.triangles = from_scene.triangles;
    def.uvs = from_scene.uvs;
    ASSERT_TRUE(core::validate(def, 100).ok);
    expectSameNetwork(core::buildMeshCloth(from_scene), core::buildMeshCloth(def));
  }
}

TEST(ClothDefaults, SceneFileValueGivenIsKeptAndTheOtherTakesTheModelsDefault)
{
  // bend.stiffness given, bend.damping Baraff–Witkin's 5e-5 N·m·s: as in C++.
  const ClothGridDef from_scene =
      readOneBody<ClothGridDef>("bodies:\n  - {name: c, kind: cloth, model: baraff_witkin, bend: {stiffness: 0.01}}\n");
  ClothGridDef def = withModel<ClothGridDef>(ClothModel::BaraffWitkin);
  def.bend.stiffness = 0.01;
  const core::SpringNetworkDef net = core::buildClothGrid(from_scene);
  EXPECT_EQ(net.baraff_witkin.bend.stiffness, 0.01);
  EXPECT_EQ(net.baraff_witkin.bend.damping, 5e-5);
  expectSameNetwork(net, core::buildClothGrid(def));
}

TEST(ClothDefaults, SpawnClothRequestGetsTheDefinitionsDefaults)
{
  for (ClothModel model : {ClothModel::BaraffWitkin, ClothModel::Springs})
  {
    SCOPED_TRACE(core::toString(model));
    const ClothGridDef expected = withModel<ClothGridDef>(model);
    // nu, nv, mass, b_u and b_v left at 0 ("0 = the default"); the geometry and the constants,
    // which have no such default in the request, are the definition's.
    SpawnCloth::Request req;
    req.name = "c";
    req.model = core::toString(model);
    req.origin.x = expected.origin.x(), req.origin.y = expected.origin.y(), req.origin.z = expected.origin.z();
    req.edge_u.x = expected.edge_u.x(), req.edge_u.y = expected.edge_u.y(), req.edge_u.z = expected.edge_u.z();
    req.edge_v.x = expected.edge_v.x(), req.edge_v.y = expected.edge_v.y(), req.edge_v.z = expected.edge_v.z();
    const core::SpringConstants stretch = expected.constants(core::SpringClass::Stretch);
    const core::SpringConstants shear = expected.constants(core::SpringClass::Shear);
    const core::SpringConstants bend = expected.constants(core::SpringClass::Bend);
    req.stretch_stiffness = stretch.stiffness, req.stretch_damping = stretch.damping;
    req.shear_stiffness = shear.stiffness, req.shear_damping = shear.damping;
    req.bend_stiffness = bend.stiffness, req.bend_damping = bend.damping;

    ClothGridDef from_request;
    ASSERT_TRUE(ros_interface::toClothGridDef(req, core::IntegratorDef(), from_request).ok);
    EXPECT_EQ(from_request.model, model);
    EXPECT_EQ(from_request.nu, 15);
    EXPECT_EQ(from_request.nv, 15);
    EXPECT_EQ(from_request.mass, 0.5);
    EXPECT_EQ(from_request.b_u, 1.0);
    EXPECT_EQ(from_request.b_v, 1.0);
    ASSERT_TRUE(core::validate(from_request, 100000).ok);
    expectSameNetwork(core::buildClothGrid(from_request), core::buildClothGrid(expected));
  }
}
