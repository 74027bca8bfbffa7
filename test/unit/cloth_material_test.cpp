// Cloth materials in physical units (issue 17): validation messages and presets.
#include "particle_sim/core/materials/cloth_material.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>

#include "particle_sim/core/limits.h"

namespace core = particle_sim::core;

namespace
{
core::ClothMaterial someCloth()
{
  return {"", 0.2, 5000.0, 50.0, 1e-5, 0.1};
}
}  // namespace

TEST(ClothMaterial, AValidMaterialPasses)
{
  EXPECT_TRUE(core::validate(someCloth()).ok) << core::validate(someCloth()).message;
  core::ClothMaterial flexible = someCloth();
  flexible.bending_rigidity = 0.0;  // a cloth without bending resistance is allowed
  flexible.damping_ratio = 0.0;
  EXPECT_TRUE(core::validate(flexible).ok);
}

TEST(ClothMaterial, EachFieldOutOfRangeIsRefusedNamingFieldValueRangeAndUnit)
{
  struct Case
  {
    double core::ClothMaterial::*field;
    double value;
    const char* message;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const Case cases[] = {
      {&core::ClothMaterial::areal_density, -0.5,
       "material.areal_density = -0.5 is out of range: must be in [0.001, 10] kg/m^2"},
      {&core::ClothMaterial::areal_density, 0.0,
       "material.areal_density = 0 is out of range: must be in [0.001, 10] kg/m^2"},
      {&core::ClothMaterial::areal_density, -nan,
       "material.areal_density = nan is not a finite number: must be in [0.001, 10] kg/m^2"},
      {&core::ClothMaterial::tensile_stiffness, 0.0,
       "material.tensile_stiffness = 0 is out of range: must be in [1, 1e+07] N/m"},
      {&core::ClothMaterial::tensile_stiffness, inf,
       "material.tensile_stiffness = inf is not a finite number: must be in [1, 1e+07] N/m"},
      {&core::ClothMaterial::shear_stiffness, 2e6,
       "material.shear_stiffness = 2e+06 is out of range: must be in [0.01, 1e+06] N/m"},
      {&core::ClothMaterial::bending_rigidity, -1e-6,
       "material.bending_rigidity = -1e-06 is out of range: must be in [0, 1] N·m"},
      {&core::ClothMaterial::bending_rigidity, -inf,
       "material.bending_rigidity = -inf is not a finite number: must be in [0, 1] N·m"},
      {&core::ClothMaterial::damping_ratio, 11.0, "material.damping_ratio = 11 is out of range: must be in [0, 10]"},
      {&core::ClothMaterial::damping_ratio, nan,
       "material.damping_ratio = nan is not a finite number: must be in [0, 10]"},
  };
  for (const Case& c : cases)
  {
    core::ClothMaterial material = someCloth();
    material.*c.field = c.value;
    const core::Status status = core::validate(material);
    EXPECT_FALSE(status.ok) << c.message;
    EXPECT_EQ(status.message, c.message);
  }
}

TEST(ClothMaterial, RangesAreTheSharedOnes)
{
  // The damping ratio range is shared with the rope material (limits.h).
  EXPECT_EQ(core::limits::kDampingRatio.min, 0.0);
  EXPECT_EQ(core::limits::kDampingRatio.max, 10.0);
  EXPECT_STREQ(core::limits::kDampingRatio.unit, "-");
}

TEST(ClothMaterial, PresetsAreValidNamedAndFound)
{
  const std::set<std::string> wanted = {"cotton", "denim", "silk", "polyester", "wool", "aramid"};
  std::set<std::string> names;
  for (const core::ClothMaterial& preset : core::clothPresets())
  {
    EXPECT_TRUE(core::validate(preset).ok) << preset.name << ": " << core::validate(preset).message;
    EXPECT_TRUE(names.insert(preset.name).second) << "preset named twice: " << preset.name;
    const auto found = core::findClothPreset(preset.name);
    ASSERT_TRUE(found.has_value());
    EXPECT_EQ(found->areal_density, preset.areal_density);
    EXPECT_NE(core::clothPresetNames().find(preset.name), std::string::npos);
  }
  EXPECT_EQ(names, wanted);
  EXPECT_FALSE(core::findClothPreset("tweed").has_value());
  EXPECT_FALSE(core::findClothPreset("").has_value());
  EXPECT_EQ(core::clothPresetNames(), "cotton, denim, silk, polyester, wool, aramid");
}

TEST(ClothMaterial, PresetsFollowTheKnownOrderingOfFabrics)
{
  // Independent of the exact figures: denim is heavier and stiffer in bending and shear than cotton
  // shirting, which is heavier and stiffer than silk; the aramid is by far the stiffest in tension.
  const auto cotton = *core::findClothPreset("cotton"), denim = *core::findClothPreset("denim"),
             silk = *core::findClothPreset("silk"), aramid = *core::findClothPreset("aramid");
  EXPECT_GT(denim.areal_density, cotton.areal_density);
  EXPECT_GT(cotton.areal_density, silk.areal_density);
  EXPECT_GT(denim.bending_rigidity, cotton.bending_rigidity);
  EXPECT_GT(cotton.bending_rigidity, silk.bending_rigidity);
  EXPECT_GT(denim.shear_stiffness, cotton.shear_stiffness);
  EXPECT_GT(aramid.tensile_stiffness, 10.0 * denim.tensile_stiffness);
  // Fabrics' bending length (B/(w g))^(1/3), the cantilever test's quantity, lies between about 0.5
  // and 5 cm for apparel fabrics (Peirce 1930; ASTM D1388 reports it in that range).
  for (const core::ClothMaterial& preset : core::clothPresets())
  {
    const double bending_length = std::cbrt(preset.bending_rigidity / (preset.areal_density * 9.81));
    EXPECT_GT(bending_length, 0.005) << preset.name;
    EXPECT_LT(bending_length, 0.05) << preset.name;
  }
}

// ---------------------------------------------------------------------------------------------------
// Conversion of a material into masses and constants (cloth_common.h), checked against membrane and
// plate theory at two resolutions.

#include <Eigen/Geometry>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/builders/mesh_cloth.h"
#include "particle_sim/core/forces/plate_bending.h"
#include "particle_sim/core/forces/rod_bending.h"
#include "particle_sim/core/spring.h"

namespace
{
constexpr double kWidthU = 0.5, kWidthV = 0.3;  // [m] the test strip

// A flat grid cloth of `material` in the xy plane, kWidthU × kWidthV, nu × nv particles.
core::ClothGridDef materialGrid(core::ClothModel model, int nu, int nv, const core::ClothMaterial& material)
{
  core::ClothGridDef def(model);
  def.name = "cloth";
  def.origin = Eigen::Vector3d::Zero();
  def.edge_u = Eigen::Vector3d(kWidthU, 0.0, 0.0);
  def.edge_v = Eigen::Vector3d(0.0, kWidthV, 0.0);
  def.nu = nu;
  def.nv = nv;
  def.material = material;
  return def;
}

Eigen::Matrix3Xd columns(const std::vector<Eigen::Vector3d>& x)
{
  Eigen::Matrix3Xd m(3, x.size());
  for (std::size_t i = 0; i < x.size(); ++i)
    m.col(i) = x[i];
  return m;
}

// The Baraff–Witkin element of a built cloth with only `kept` class's stiffness (the others zero).
core::BaraffWitkinModel onlyClass(const core::SpringNetworkDef& net, core::SpringClass kept)
{
  core::BaraffWitkinModel model(net.baraff_witkin);
  for (core::SpringClass c : {core::SpringClass::Stretch, core::SpringClass::Shear, core::SpringClass::Bend})
  {
    if (c != kept) model.setConstants(c, 0.0, 0.0);
  }
  return model;
}

// Sum of the u components of the forces on the particles of column a = nu − 1 (the strip's end).
double endForceAlongU(const Eigen::Matrix3Xd& force, int nu, int nv)
{
  double sum = 0.0;
  for (int b = 0; b < nv; ++b)
    sum += force(0, b * nu + nu - 1);
  return sum;
}
}  // namespace

TEST(ClothMaterialConversion, LumpedMassesCarryTheArealDensity)
{
  const core::ClothMaterial cotton = *core::findClothPreset("cotton");
  for (int n : {9, 17})
  {
    const core::SpringNetworkDef net = core::buildClothGrid(materialGrid(core::ClothModel::BaraffWitkin, n, n, cotton));
    double total = 0.0;
    for (double m : net.masses)
      total += m;
    EXPECT_NEAR(total, cotton.areal_density * kWidthU * kWidthV, 1e-12);
    // An interior particle carries a quarter of each of its four cells: one cell's area.
    const double cell = kWidthU / (n - 1) * kWidthV / (n - 1);
    EXPECT_NEAR(net.masses[(n / 2) * n + n / 2], cotton.areal_density * cell, 1e-15);
  }
}

TEST(ClothMaterialConversion, BaraffWitkinUniaxialStretchPullsWithTensileStiffnessTimesWidthTimesStrain)
{
  // Membrane theory: a strip of width w stretched by ε along u needs E·t·w·ε. Stretch the whole
  // strip uniformly along u (no lateral contraction: the Baraff–Witkin conditions are uncoupled)
  // and sum the forces on its end.
  const core::ClothMaterial denim = *core::findClothPreset("denim");
  const double strain = 0.01;
  for (int n : {5, 13})
  {
    const core::SpringNetworkDef net = core::buildClothGrid(materialGrid(core::ClothModel::BaraffWitkin, n, n, denim));
    Eigen::Matrix3Xd x = columns(net.positions);
    x.row(0) *= 1.0 + strain;
    Eigen::Matrix3Xd force = Eigen::Matrix3Xd::Zero(3, x.cols());
    core::BaraffWitkinModel(net.baraff_witkin).addForces(x, Eigen::Matrix3Xd::Zero(3, x.cols()), force);
    EXPECT_NEAR(-endForceAlongU(force, n, n), denim.tensile_stiffness * kWidthV * strain,
                1e-9 * denim.tensile_stiffness * kWidthV * strain)
        << n << " x " << n;
    EXPECT_NEAR(core::BaraffWitkinModel(net.baraff_witkin).energy(x),
                0.5 * denim.tensile_stiffness * strain * strain * kWidthU * kWidthV, 1e-9);
  }
}

TEST(ClothMaterialConversion, BaraffWitkinSimpleShearStoresShearStiffnessTimesShearSquaredOverTwo)
{
  // Simple shear x = u + γ v: w_u = (1, 0, 0), w_v = (γ, 1, 0), so w_u·w_v = γ exactly and |w_v| − 1 =
  // √(1 + γ²) − 1 (a stretch of second order). Membrane theory: G·t γ²/2 per area, plus that stretch.
  const core::ClothMaterial wool = *core::findClothPreset("wool");
  const double gamma = 0.02, area = kWidthU * kWidthV;
  const double stretch_v = std::sqrt(1.0 + gamma * gamma) - 1.0;
  for (int n : {5, 13})
  {
    const core::SpringNetworkDef net = core::buildClothGrid(materialGrid(core::ClothModel::BaraffWitkin, n, n, wool));
    Eigen::Matrix3Xd x = columns(net.positions);
    x.row(0) += gamma * x.row(1);
    const double expected =
        area * (0.5 * wool.shear_stiffness * gamma * gamma + 0.5 * wool.tensile_stiffness * stretch_v * stretch_v);
    EXPECT_NEAR(core::BaraffWitkinModel(net.baraff_witkin).energy(x), expected, 1e-12 * expected + 1e-15);
    EXPECT_NEAR(onlyClass(net, core::SpringClass::Shear).energy(x), area * 0.5 * wool.shear_stiffness * gamma * gamma,
                1e-12);
  }
}

namespace
{
// The grid of `net` (flat in xy, kWidthU × kWidthV from the origin) rolled onto a cylinder of
// curvature κ whose axis is along v (around_v) or along u: the arc length along the bent direction is
// kept, so each cell stays a flat rectangle and the chords of neighbouring cells meet at κ h.
Eigen::Matrix3Xd rolled(const core::SpringNetworkDef& net, double curvature, bool around_v)
{
  Eigen::Matrix3Xd x = columns(net.positions);
  const double radius = 1.0 / curvature;
  for (int i = 0; i < x.cols(); ++i)
  {
    const int bent = around_v ? 0 : 1;
    const double s = x(bent, i);
    x(bent, i) = radius * std::sin(s / radius);
    x(2, i) = radius * (1.0 - std::cos(s / radius));
  }
  return x;
}
}  // namespace

TEST(ClothMaterialConversion, GridBendingRigidityMapsOneToOneForCylindersAlongTheGridAxes)
{
  // Plate theory: a cylinder of curvature κ stores B κ²/2 per area. Rolled about v, the grid's
  // rows are circles and its columns stay straight; the cells stay flat (their diagonal hinges keep
  // θ = 0) and each rod along a row, at its nu − 2 interior vertices, turns by θ = κ h_u: the rods
  // store Σ_rows (2 k / 1) tan²(θ/2), k = B w_row / h_u, the rows' widths w_row summing to L_v
  // (cloth_grid.cpp). For small θ that is B κ²/2 per area of the interior columns, (L_u − h_u) L_v:
  // the rod's tan form is (tan(θ/2) / (θ/2))² = 1 + θ²/6 + 17 θ⁴/720 + ... times θ²/2 (second order in
  // h). Alike about u.
  const core::ClothMaterial denim = *core::findClothPreset("denim");
  const double curvature = 4.0;  // [1/m]
  for (int n : {9, 33})
  {
    const core::SpringNetworkDef net = core::buildClothGrid(materialGrid(core::ClothModel::BaraffWitkin, n, n, denim));
    ASSERT_DOUBLE_EQ(net.baraff_witkin.bend.stiffness, denim.bending_rigidity);
    const double hu = kWidthU / (n - 1), hv = kWidthV / (n - 1);
    const core::BaraffWitkinModel hinges = onlyClass(net, core::SpringClass::Bend);
    const core::RodBendingForce rods(net.rod_bending);
    const Eigen::VectorXd masses = Eigen::VectorXd::Ones(net.positions.size());
    const std::vector<char> pinned(net.positions.size(), 0);
    const core::ForceContext context{masses, pinned, Eigen::Vector3d::Zero(), core::AirDef(), 0.0};
    for (bool around_v : {true, false})
    {
      const Eigen::Matrix3Xd x = rolled(net, curvature, around_v);
      EXPECT_NEAR(hinges.energy(x), 0.0, 1e-15) << "the diagonal hinges of a cylinder along a grid axis stay flat";
      double energy = 0.0;
      rods.addEnergy(context, x, energy);
      const double h = around_v ? hu : hv, along = around_v ? kWidthU : kWidthV, across = around_v ? kWidthV : kWidthU;
      const double exact =
          2.0 * denim.bending_rigidity * across / h * std::pow(std::tan(curvature * h / 2.0), 2) * (n - 2);
      EXPECT_NEAR(energy, exact, 1e-9 * exact) << n << " x " << n;
      const double density = 0.5 * denim.bending_rigidity * curvature * curvature;
      const double theta = curvature * h;
      EXPECT_NEAR(energy / ((along - h) * across) / density - 1.0, theta * theta / 6.0, std::pow(theta, 4) / 40.0)
          << n << " x " << n;
    }
  }
}

namespace
{
// The grid of `net` (flat in xy) lifted onto z = ½ (κ_uu x² + 2 κ_uv x y + κ_vv y²), x and y from the
// point (x0, y0).
Eigen::Matrix3Xd quadraticSurface(const core::SpringNetworkDef& net, const Eigen::Matrix2d& curvature, double x0,
                                  double y0)
{
  Eigen::Matrix3Xd x = columns(net.positions);
  for (int i = 0; i < x.cols(); ++i)
  {
    const Eigen::Vector2d p(x(0, i) - x0, x(1, i) - y0);
    x(2, i) = 0.5 * p.dot(curvature * p);
  }
  return x;
}
}  // namespace

TEST(ClothMaterialConversion, GridBendingIsAnIsotropicPlateForEveryUniformCurvature)
{
  // An isotropic plate of Poisson ratio 0 stores B/2 (κ₁² + κ₂²) = B/2 (κ_uu² + κ_vv² + 2 κ_uv²) per
  // area under a uniform curvature, whatever its orientation. A material grid cloth bends with rods
  // along its grid lines (κ_uu, κ_vv) and hinges on its cells' diagonals (κ_uv) (cloth_grid.cpp): the
  // rods centred on the vertices of a block of m x m' vertices and the hinges of its m x m' cells hold
  // B/2 (...) times the block's area, for any curvature, up to the small-angle error (relative
  // O((κ L)²) ≈ 1e-5 here). Checked on square and on rectangular cells, for cylinders at several
  // angles to the grid and for a saddle. Hinges on every edge would store, for square cells,
  // B/2 [(κ_uu + κ_uv)² + (κ_vv + κ_uv)² + 4 κ_uv²] instead: bending coupled to twist.
  const core::ClothMaterial denim = *core::findClothPreset("denim");
  const double kappa = 0.02;  // [1/m] small: the angles stay linear
  for (const auto& [nu, nv] : {std::pair<int, int>{25, 25}, std::pair<int, int>{25, 17}})
  {
    const core::SpringNetworkDef net =
        core::buildClothGrid(materialGrid(core::ClothModel::BaraffWitkin, nu, nv, denim));
    const double hu = kWidthU / (nu - 1), hv = kWidthV / (nv - 1);
    // The block: vertices and cells [4, 4 + m) along u and [4, 4 + m') along v, found by the midpoint
    // of a hinge's edge or a rod's centre vertex in half cells (whole for vertices, odd for cells).
    const int mu = nu - 9, mv = nv - 9;
    auto inBlock = [&](const Eigen::Vector3d& point) {
      const long cu = std::lround(2.0 * point.x() / hu), cv = std::lround(2.0 * point.y() / hv);
      return cu >= 8 && cu < 8 + 2 * mu && cv >= 8 && cv < 8 + 2 * mv;
    };
    core::SpringNetworkDef block = net;
    block.rod_bending.bends.clear();
    for (const core::RodBend& rod : net.rod_bending.bends)
    {
      if (inBlock(net.positions[rod.v[1]])) block.rod_bending.bends.push_back(rod);
    }
    for (std::size_t k = 0; k < block.baraff_witkin.bends.size(); ++k)
    {
      const core::BwBend& b = block.baraff_witkin.bends[k];
      if (!inBlock(0.5 * (net.positions[b.v[1]] + net.positions[b.v[2]]))) block.baraff_witkin.bend_weights[k] = 0.0;
    }
    const core::BaraffWitkinModel twist = onlyClass(block, core::SpringClass::Bend);
    const core::RodBendingForce rods(block.rod_bending);
    const Eigen::VectorXd masses = Eigen::VectorXd::Ones(net.positions.size());
    const std::vector<char> pinned(net.positions.size(), 0);
    const core::ForceContext context{masses, pinned, Eigen::Vector3d::Zero(), core::AirDef(), 0.0};
    const double area = mu * hu * mv * hv;
    for (double degrees : {0.0, 17.0, 30.0, 45.0, 60.0, 90.0, 135.0})
    {
      for (const Eigen::Vector2d& principal : {Eigen::Vector2d(kappa, 0.0), Eigen::Vector2d(kappa, -0.6 * kappa)})
      {
        const Eigen::Matrix2d r = Eigen::Rotation2Dd(degrees * M_PI / 180.0).toRotationMatrix();
        const Eigen::Matrix2d curvature = r * principal.asDiagonal() * r.transpose();
        const double expected = 0.5 * denim.bending_rigidity * principal.squaredNorm() * area;
        const Eigen::Matrix3Xd x = quadraticSurface(net, curvature, kWidthU / 2, kWidthV / 2);
        double energy = twist.energy(x);
        rods.addEnergy(context, x, energy);
        EXPECT_NEAR(energy, expected, 1e-4 * expected)
            << nu << " x " << nv << ", principal curvatures " << principal.transpose() << " at " << degrees << "°";
      }
    }
  }

  // A mesh cloth of the same material and grid has no hinges: it bends with the isotropic plate of its
  // flat pattern (forces/plate_bending.h), which stores B/2 (κ_uu + κ_vv)² per area under a uniform
  // curvature (the cotangent Laplacian of these right triangles is the five-point one, exact on the
  // quadratic surface): for a cylinder at any angle to the grid, B/2 κ², as above.
  const int n = 25;
  core::ClothGridDef def = materialGrid(core::ClothModel::BaraffWitkin, n, n, denim);
  def.edge_v = Eigen::Vector3d(0.0, kWidthU, 0.0);
  core::MeshClothDef mesh(core::ClothModel::BaraffWitkin);
  mesh.name = "mesh";
  const core::SpringNetworkDef grid = core::buildClothGrid(def);
  mesh.vertices = grid.positions;
  mesh.triangles = grid.triangles;
  for (const Eigen::Vector3d& p : grid.positions)
    mesh.uvs.emplace_back(p.x(), p.y());
  mesh.material = denim;
  const core::SpringNetworkDef plate_net = core::buildMeshCloth(mesh);
  EXPECT_TRUE(plate_net.baraff_witkin.bends.empty());
  const core::PlateBendingForce plate(plate_net.plate_bending);
  double interior_area = 0.0;
  for (double inverse : plate_net.plate_bending.inverse_area)
    interior_area += 1.0 / inverse;
  const Eigen::VectorXd masses = Eigen::VectorXd::Ones(grid.positions.size());
  const std::vector<char> pinned(grid.positions.size(), 0);
  const core::ForceContext context{masses, pinned, Eigen::Vector3d::Zero(), core::AirDef(), 0.0};
  for (double degrees : {0.0, 17.0, 30.0, 45.0, 60.0, 90.0, 135.0})
  {
    const Eigen::Matrix2d r = Eigen::Rotation2Dd(degrees * M_PI / 180.0).toRotationMatrix();
    const Eigen::Matrix2d curvature = r * Eigen::Vector2d(kappa, 0.0).asDiagonal() * r.transpose();
    double energy = 0.0;
    plate.addEnergy(context, quadraticSurface(plate_net, curvature, kWidthU / 2, kWidthU / 2), energy);
    const double expected = 0.5 * denim.bending_rigidity * kappa * kappa * interior_area;
    EXPECT_NEAR(energy, expected, 1e-9 * expected) << "mesh cloth, cylinder at " << degrees << "°";
  }
}

TEST(ClothMaterialConversion, DampingIsStiffnessProportionalWithTheSameTimeAtEveryResolution)
{
  // k_d = β k, β = 2ζ/ω₁ with ω₁ the cloth's quarter-wave (stretch, shear) or cantilever (bend) mode
  // for L = √area (cloth_common.cpp): independent of the resolution.
  const core::ClothMaterial silk = *core::findClothPreset("silk");
  const double length = std::sqrt(kWidthU * kWidthV);
  const double omega_stretch = M_PI / (2.0 * length) * std::sqrt(silk.tensile_stiffness / silk.areal_density);
  const double omega_bend = std::pow(1.8751 / length, 2) * std::sqrt(silk.bending_rigidity / silk.areal_density);
  for (int n : {5, 17})
  {
    const core::BaraffWitkinDef bw =
        core::buildClothGrid(materialGrid(core::ClothModel::BaraffWitkin, n, n, silk)).baraff_witkin;
    EXPECT_NEAR(bw.stretch.damping / bw.stretch.stiffness, 2.0 * silk.damping_ratio / omega_stretch, 1e-15);
    EXPECT_NEAR(bw.bend.damping / bw.bend.stiffness, 2.0 * silk.damping_ratio / omega_bend, 1e-12);
  }
}

TEST(ClothMaterialConversion, SpringGridUniaxialStretchPullsWithTensileStiffnessTimesWidthTimesStrain)
{
  // A uniform strain ε along u with the free lateral contraction ν = C₁₂/C₂₂ of the spring lattice
  // (cloth_grid.cpp), linearised (ε = 1e-6: the geometric nonlinearity is O(ε) relative): the end
  // carries E·t·w·ε, on square and on rectangular cells.
  core::ClothMaterial cotton = *core::findClothPreset("cotton");
  cotton.bending_rigidity = 0.0;    // the spring model takes no bending rigidity
  cotton.shear_stiffness = 2000.0;  // large enough that the lateral coupling matters
  const double et = cotton.tensile_stiffness, gt = cotton.shear_stiffness;
  const double c = 0.5 * (et + std::sqrt(et * et + 4.0 * gt * gt)), poisson = gt / c, strain = 1e-6;
  for (auto [nu, nv] : {std::pair<int, int>{6, 4}, std::pair<int, int>{11, 11}, std::pair<int, int>{21, 9}})
  {
    const core::ClothGridDef def = materialGrid(core::ClothModel::Springs, nu, nv, cotton);
    ASSERT_TRUE(core::validate(def, 100000).ok) << core::validate(def, 100000).message;
    const core::SpringNetworkDef net = core::buildClothGrid(def);
    Eigen::Matrix3Xd x = columns(net.positions);
    x.row(0) *= 1.0 + strain;
    x.row(1) *= 1.0 - poisson * strain;
    Eigen::Matrix3Xd force = Eigen::Matrix3Xd::Zero(3, x.cols());
    for (const core::Spring& s : net.springs)
    {
      const Eigen::Vector3d f = core::springForce(x.col(s.i), x.col(s.j), Eigen::Vector3d::Zero(),
                                                  Eigen::Vector3d::Zero(), s.rest_length, s.stiffness, 0.0);
      force.col(s.i) += f;
      force.col(s.j) -= f;
    }
    const double expected = et * kWidthV * strain;
    EXPECT_NEAR(-endForceAlongU(force, nu, nv), expected, 1e-4 * expected) << nu << " x " << nv;
    // No net lateral force on the top row: the contraction is the free one.
    double top = 0.0;
    for (int a = 0; a < nu; ++a)
      top += force(1, (nv - 1) * nu + a);
    EXPECT_NEAR(top, 0.0, 1e-4 * expected) << nu << " x " << nv;
  }
}

TEST(ClothMaterialConversion, AClothWithAMaterialAndAConstantIsRefusedNamingBoth)
{
  const core::ClothMaterial denim = *core::findClothPreset("denim");
  core::ClothGridDef grid = materialGrid(core::ClothModel::BaraffWitkin, 5, 5, denim);
  EXPECT_TRUE(core::validate(grid, 1000).ok) << core::validate(grid, 1000).message;
  grid.shear.damping = 0.1;
  EXPECT_EQ(core::validate(grid, 1000).message,
            "material and shear.damping are both set: a material gives the cloth its constants; set one or the other");
  core::MeshClothDef mesh(core::ClothModel::Springs);
  mesh.name = "cloth";
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles = {{0, 1, 2}};
  mesh.material = denim;
  mesh.material->bending_rigidity = 0.0;
  EXPECT_TRUE(core::validate(mesh, 1000).ok) << core::validate(mesh, 1000).message;
  mesh.stretch.stiffness = 500.0;
  EXPECT_EQ(core::validate(mesh, 1000).message,
            "material and stretch.stiffness are both set: a material gives the cloth its constants; set one or the "
            "other");
}

TEST(ClothMaterialConversion, TheSpringModelRefusesABendingRigidity)
{
  const core::ClothMaterial denim = *core::findClothPreset("denim");
  const core::ClothGridDef grid = materialGrid(core::ClothModel::Springs, 5, 5, denim);
  EXPECT_EQ(core::validate(grid, 1000).message,
            "material.bending_rigidity = 7.8e-05 N·m needs model baraff_witkin: the spring model's bend springs cannot "
            "carry a bending rigidity (use model: baraff_witkin, recommended, or bending_rigidity: 0)");
}

TEST(ClothMaterialConversion, AnInvalidMaterialIsRefusedByTheCloth)
{
  core::ClothMaterial bad = *core::findClothPreset("silk");
  bad.areal_density = -1.0;
  EXPECT_EQ(core::validate(materialGrid(core::ClothModel::BaraffWitkin, 5, 5, bad), 1000).message,
            "material.areal_density = -1 is out of range: must be in [0.001, 10] kg/m^2");
}

TEST(ClothMaterialConversion, SpringMeshEdgesFollowThePerTriangleAreaRule)
{
  // Equilateral triangles of side h: an interior edge gets E·t (2 · √3/4 h²)/h² = (√3/2) E·t, a
  // border edge half; the lattice's plane modulus 2k/√3 is then E·t at any h.
  core::ClothMaterial cotton = *core::findClothPreset("cotton");
  cotton.bending_rigidity = 0.0;
  for (double h : {0.1, 0.025})
  {
    core::MeshClothDef mesh(core::ClothModel::Springs);
    mesh.name = "cloth";
    mesh.vertices = {{0, 0, 0}, {h, 0, 0}, {h / 2, h * std::sqrt(3.0) / 2, 0}, {h / 2, -h * std::sqrt(3.0) / 2, 0}};
    mesh.triangles = {{0, 1, 2}, {0, 3, 1}};
    mesh.material = cotton;
    ASSERT_TRUE(core::validate(mesh, 1000).ok);
    const core::SpringNetworkDef net = core::buildMeshCloth(mesh);
    ASSERT_EQ(net.springs.size(), 5u);
    for (const core::Spring& s : net.springs)
    {
      const bool interior = (s.i == 0 && s.j == 1) || (s.i == 1 && s.j == 0);
      EXPECT_NEAR(s.stiffness, (interior ? 1.0 : 0.5) * std::sqrt(3.0) / 2.0 * cotton.tensile_stiffness, 1e-9);
    }
    EXPECT_NEAR(net.masses[0], cotton.areal_density * 2.0 * std::sqrt(3.0) / 4.0 * h * h / 3.0, 1e-15);
  }
}
