// A cloth's constants default by its model, defined once (defaultClothConstants()): choosing the
// model in the constructor, ClothGridDef(model), or assigning it afterwards, `d.model = model`,
// builds the same network, spring by spring and condition by condition, with the documented
// defaults (README "Cloth and jelly"); a value the caller sets is kept whatever the model, the
// other value of its class still takes the model's default.

#include <gtest/gtest.h>

#include <string>

#include "network_expectations.h"
#include "particle_sim/core/builders/cloth_common.h"
#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/builders/mesh_cloth.h"
#include "particle_sim/core/forces/baraff_witkin_model.h"

using namespace particle_sim::core;
using particle_sim_test::expectConstants;
using particle_sim_test::expectSameNetwork;

namespace
{
constexpr int kMaxParticles = 100000;

// The documented defaults (README "Cloth and jelly"): spring cloth [N/m], [N·s/m]; Baraff–Witkin
// per unit area, bend [N·m], [N·m·s].
const SpringConstants kSpringsStretch{1000.0, 0.5}, kSpringsShear{200.0, 0.2}, kSpringsBend{20.0, 0.05};
const SpringConstants kBwStretch{1000.0, 1.0}, kBwShear{100.0, 0.1}, kBwBend{0.005, 5e-5};

// Every spring of `net` has the constants of its class.
void expectSpringConstants(const SpringNetworkDef& net, const SpringConstants& stretch, const SpringConstants& shear,
                           const SpringConstants& bend)
{
  for (const Spring& s : net.springs)
  {
    const SpringConstants& expected = s.spring_class == SpringClass::Stretch ? stretch
                                      : s.spring_class == SpringClass::Shear ? shear
                                                                             : bend;
    expectConstants({s.stiffness, s.damping}, expected, "spring " + std::to_string(s.i) + "-" + std::to_string(s.j));
  }
}

ClothGridDef smallGrid(ClothGridDef def)
{
  def.name = "grid";
  def.nu = 4;
  def.nv = 3;
  return def;
}

MeshClothDef square(MeshClothDef def)
{
  def.name = "mesh";
  def.vertices = {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  def.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  def.triangles = {{0, 1, 2}, {0, 2, 3}};
  return def;
}

template <typename ClothDef>
ClothDef assigned(ClothModel model)
{
  ClothDef def;
  def.model = model;
  return def;
}
}  // namespace

TEST(ClothConstants, GridBaraffWitkinIsTheSameWhetherTheModelIsConstructedOrAssigned)
{
  const ClothGridDef constructed = smallGrid(ClothGridDef(ClothModel::BaraffWitkin));
  const ClothGridDef assigned_model = smallGrid(assigned<ClothGridDef>(ClothModel::BaraffWitkin));
  ASSERT_TRUE(validate(constructed, kMaxParticles).ok);
  ASSERT_TRUE(validate(assigned_model, kMaxParticles).ok);
  const SpringNetworkDef a = buildClothGrid(constructed), b = buildClothGrid(assigned_model);
  expectSameNetwork(a, b);

  // No springs; the conditions carry Baraff–Witkin's defaults, never the spring cloth's bend 20.
  EXPECT_TRUE(b.springs.empty());
  EXPECT_EQ(b.baraff_witkin.triangles.size(), 2u * 3u * 2u);
  expectConstants(b.baraff_witkin.stretch, kBwStretch, "stretch");
  expectConstants(b.baraff_witkin.shear, kBwShear, "shear");
  expectConstants(b.baraff_witkin.bend, kBwBend, "bend");
  expectConstants(assigned_model.constants(SpringClass::Bend), kBwBend, "constants(Bend)");
}

TEST(ClothConstants, GridSpringsIsTheSameWhetherTheModelIsConstructedOrAssigned)
{
  // Back from Baraff–Witkin to springs: the unset constants follow the model.
  ClothGridDef switched = smallGrid(ClothGridDef(ClothModel::BaraffWitkin));
  switched.model = ClothModel::Springs;
  const SpringNetworkDef a = buildClothGrid(smallGrid(ClothGridDef(ClothModel::Springs)));
  const SpringNetworkDef b = buildClothGrid(smallGrid(ClothGridDef()));
  const SpringNetworkDef c = buildClothGrid(switched);
  expectSameNetwork(a, b);
  expectSameNetwork(a, c);

  // 4 x 3 grid: 3·3 + 4·2 stretch, 2·3·2 shear, 2·3 + 4·1 bend springs, at the spring defaults.
  EXPECT_EQ(c.springs.size(), 17u + 12u + 10u);
  EXPECT_TRUE(c.baraff_witkin.empty());
  expectSpringConstants(c, kSpringsStretch, kSpringsShear, kSpringsBend);
}

TEST(ClothConstants, MeshIsTheSameWhetherTheModelIsConstructedOrAssigned)
{
  for (ClothModel model : {ClothModel::BaraffWitkin, ClothModel::Springs})
  {
    SCOPED_TRACE(toString(model));
    const MeshClothDef constructed = square(MeshClothDef(model));
    const MeshClothDef assigned_model = square(assigned<MeshClothDef>(model));
    ASSERT_TRUE(validate(constructed, kMaxParticles).ok);
    ASSERT_TRUE(validate(assigned_model, kMaxParticles).ok);
    const SpringNetworkDef a = buildMeshCloth(constructed), b = buildMeshCloth(assigned_model);
    expectSameNetwork(a, b);
    if (model == ClothModel::BaraffWitkin)
    {
      EXPECT_TRUE(b.springs.empty());
      EXPECT_EQ(b.baraff_witkin.bends.size(), 1u);
      expectConstants(b.baraff_witkin.stretch, kBwStretch, "stretch");
      expectConstants(b.baraff_witkin.shear, kBwShear, "shear");
      expectConstants(b.baraff_witkin.bend, kBwBend, "bend");
    }
    else
    {
      EXPECT_EQ(b.springs.size(), 5u + 1u);  // every edge, and a bend spring across the diagonal
      expectSpringConstants(b, kSpringsStretch, kSpringsShear, kSpringsBend);
    }
  }

  // Back from Baraff–Witkin to springs.
  MeshClothDef switched = square(MeshClothDef(ClothModel::BaraffWitkin));
  switched.model = ClothModel::Springs;
  expectSameNetwork(buildMeshCloth(switched), buildMeshCloth(square(MeshClothDef())));
}

TEST(ClothConstants, AValueSetIsKeptAndTheOtherValueOfItsClassTakesTheModelsDefault)
{
  // Set before the model is chosen: stiffness kept, damping Baraff–Witkin's.
  ClothGridDef grid = smallGrid(ClothGridDef());
  grid.bend.stiffness = 0.01;
  grid.stretch = {2000.0, 3.0};
  grid.model = ClothModel::BaraffWitkin;
  ASSERT_TRUE(validate(grid, kMaxParticles).ok);
  const SpringNetworkDef net = buildClothGrid(grid);
  expectConstants(net.baraff_witkin.bend, {0.01, kBwBend.damping}, "bend");
  expectConstants(net.baraff_witkin.stretch, {2000.0, 3.0}, "stretch");
  expectConstants(net.baraff_witkin.shear, kBwShear, "shear");
  expectConstants(grid.constants(SpringClass::Bend), {0.01, kBwBend.damping}, "constants(Bend)");

  // The same through the constructor.
  ClothGridDef constructed = smallGrid(ClothGridDef(ClothModel::BaraffWitkin));
  constructed.bend.stiffness = 0.01;
  constructed.stretch = {2000.0, 3.0};
  expectSameNetwork(buildClothGrid(constructed), net);

  // A mesh: damping set, stiffness the spring cloth's.
  MeshClothDef mesh = square(MeshClothDef(ClothModel::BaraffWitkin));
  mesh.stretch.damping = 0.7;
  mesh.model = ClothModel::Springs;
  expectSpringConstants(buildMeshCloth(mesh), {kSpringsStretch.stiffness, 0.7}, kSpringsShear, kSpringsBend);
}

TEST(ClothConstants, ValidationChecksTheConstantsTheClothGets)
{
  // A value set out of range is refused with its name, whatever the model.
  ClothGridDef grid = smallGrid(ClothGridDef());
  grid.shear.damping = -0.5;
  grid.model = ClothModel::BaraffWitkin;
  const Status status = validate(grid, kMaxParticles);
  EXPECT_FALSE(status.ok);
  EXPECT_NE(status.message.find("shear.damping"), std::string::npos) << status.message;
  EXPECT_NE(status.message.find("-0.5"), std::string::npos) << status.message;

  // The table: each model's defaults, one place.
  expectConstants(defaultClothConstants(ClothModel::Springs, SpringClass::Stretch), kSpringsStretch, "springs stretch");
  expectConstants(defaultClothConstants(ClothModel::Springs, SpringClass::Shear), kSpringsShear, "springs shear");
  expectConstants(defaultClothConstants(ClothModel::Springs, SpringClass::Bend), kSpringsBend, "springs bend");
  expectConstants(defaultClothConstants(ClothModel::BaraffWitkin, SpringClass::Stretch), kBwStretch, "bw stretch");
  expectConstants(defaultClothConstants(ClothModel::BaraffWitkin, SpringClass::Shear), kBwShear, "bw shear");
  expectConstants(defaultClothConstants(ClothModel::BaraffWitkin, SpringClass::Bend), kBwBend, "bw bend");
}
