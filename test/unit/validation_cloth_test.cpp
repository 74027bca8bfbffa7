// Cloth against the standard tests of textile mechanics (issue 17): the cantilever bending length of
// ASTM D1388 against the heavy elastica. The cloth is given by its material in physical units
// (ClothGridDef::material) and computed at three resolutions; the case is asserted against the
// reference within a tolerance derived from the discretisation error, asserted to converge, and
// reported through validation_report.h for docs/validation.md (scripts/bench --validation).

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/spring_network.h"
#include "validation_report.h"

using namespace particle_sim::core;
using particle_sim_test::checkAndReport;
using particle_sim_test::richardsonErrors;
using particle_sim_test::ValidationCase;

namespace
{
constexpr double kPi = 3.14159265358979323846;
constexpr double kGravity = 9.81;  // [m/s²], Environment's default

std::string formatted(double value, int precision = 6)
{
  std::ostringstream out;
  out.precision(precision);
  out << value;
  return out.str();
}

// --- The heavy elastica ------------------------------------------------------------------------------
// An inextensible strip of bending rigidity B [N·m] and weight w [N/m²], clamped horizontally at one
// end and free at the other, L long. With s the arc length from the clamp and θ(s) the slope below the
// horizontal, the moment of the weight outboard of s is B θ'(s), so B θ'' = −w (L − s) cos θ, θ(0) = 0,
// θ'(L) = 0. In σ = s/L: θ'' = −λ (1 − σ) cos θ with λ = w L³ / B, the one parameter of the problem.
// The chord from the clamp to the tip makes the angle φ(λ) with the horizontal; ASTM D1388 measures
// the overhang L at which φ = 41.5° and takes B = w (L/2)³, i.e. λ = 8 (Peirce's approximation).
struct ElasticaShape
{
  double tip_x = 0.0, tip_z = 0.0;        // [L] the tip, from the clamp (z down is negative)
  double slope_end = 0.0;                 // θ'(1) [1/L]
  std::vector<std::array<double, 2>> xz;  // [L] the centre line, every step
};

// Integrates from σ = 0 with θ'(0) = p (classical Runge–Kutta, `steps` steps).
ElasticaShape integrateElastica(double lambda, double p, int steps, bool keep_shape)
{
  // State: θ, θ', x, z.
  auto derivative = [lambda](double sigma, const std::array<double, 4>& y) {
    return std::array<double, 4>{y[1], -lambda * (1.0 - sigma) * std::cos(y[0]), std::cos(y[0]), -std::sin(y[0])};
  };
  std::array<double, 4> y = {0.0, p, 0.0, 0.0};
  const double h = 1.0 / steps;
  ElasticaShape shape;
  if (keep_shape) shape.xz.push_back({0.0, 0.0});
  for (int i = 0; i < steps; ++i)
  {
    const double s = i * h;
    std::array<double, 4> k1 = derivative(s, y), k2, k3, k4, t;
    for (int j = 0; j < 4; ++j)
      t[j] = y[j] + 0.5 * h * k1[j];
    k2 = derivative(s + 0.5 * h, t);
    for (int j = 0; j < 4; ++j)
      t[j] = y[j] + 0.5 * h * k2[j];
    k3 = derivative(s + 0.5 * h, t);
    for (int j = 0; j < 4; ++j)
      t[j] = y[j] + h * k3[j];
    k4 = derivative(s + h, t);
    for (int j = 0; j < 4; ++j)
      y[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
    if (keep_shape) shape.xz.push_back({y[2], y[3]});
  }
  shape.tip_x = y[2];
  shape.tip_z = y[3];
  shape.slope_end = y[1];
  return shape;
}

// The clamped elastica of parameter λ: shooting on θ'(0) (θ'(1) = 0 by bisection; θ'(1) falls as θ'(0)
// grows over [0, λ/2], the moment at the clamp of a strip that stays straight).
ElasticaShape elastica(double lambda, bool keep_shape = false)
{
  constexpr int kSteps = 4000;  // RK4's error ~ (1/4000)⁴: far below what is compared
  double low = 0.0, high = lambda / 2.0;
  for (int i = 0; i < 64; ++i)
  {
    const double mid = 0.5 * (low + high);
    (integrateElastica(lambda, mid, kSteps, false).slope_end > 0.0 ? high : low) = mid;
  }
  return integrateElastica(lambda, 0.5 * (low + high), kSteps, keep_shape);
}

double chordAngle(const ElasticaShape& s)
{
  return std::atan2(-s.tip_z, s.tip_x);
}

// λ at which the chord angle is φ (it grows with λ): bisection.
double elasticaLambda(double phi)
{
  double low = 0.1, high = 100.0;
  for (int i = 0; i < 64; ++i)
  {
    const double mid = 0.5 * (low + high);
    (chordAngle(elastica(mid)) < phi ? low : high) = mid;
  }
  return 0.5 * (low + high);
}

// --- The simulated cantilever --------------------------------------------------------------------------
// A strip `overhang` long beyond the platform's edge and `width` wide, of `cells` cells along the
// overhang, at rest under gravity. The grid runs from x = −h to x = N h (h = overhang / (N + ½)):
// the two columns x = −h and x = 0 are pinned (they lie on the platform and carry the clamp), and the
// platform's edge is at x = −h/2, midway between them. That is where the discrete strip is clamped:
// a hinge's angle is the change of slope across a node, so the slopes live at the segments'
// midpoints, and the pinned segment's slope (zero) is the slope at its midpoint; the free length
// from there to the tip node at N h is then N h + h/2 = overhang (second-order consistent, where
// putting the edge at x = 0 would make the clamp's hinge bend a whole segment too long: first order).
struct CantileverRun
{
  double chord_angle = 0.0;                       // [rad] from the edge to the tip, below horizontal
  std::vector<Eigen::Vector3d> centre_line;       // [m] from the edge, the mid-width particles
  double max_speed = 0.0, max_force_ratio = 0.0;  // at the end: rest checks
  bool frozen = false;
};

CantileverRun settleCantilever(const ClothMaterial& material, double overhang, double width, int cells)
{
  const double h = overhang / (cells + 0.5);
  const int width_cells = std::max(2, static_cast<int>(std::lround(width / h)));
  ClothGridDef def(ClothModel::BaraffWitkin);
  def.name = "strip";
  def.origin = {-h, -width / 2, 0.0};
  def.edge_u = {(cells + 1) * h, 0.0, 0.0};
  def.edge_v = {0.0, width, 0.0};
  def.nu = cells + 2;
  def.nv = width_cells + 1;
  def.material = material;
  for (int b = 0; b < def.nv; ++b)
    def.pins.insert(def.pins.end(), {b * def.nu, b * def.nu + 1});
  def.integrator.type = kImplicitEulerIntegrator;
  def.integrator.linear_solver = LinearSolverType::Direct;
  def.integrator.cg_tolerance = 1e-10;
  const Status valid = validate(def, 100000);
  EXPECT_TRUE(valid.ok) << valid.message;
  SpringNetworkBody body(buildClothGrid(def));

  // Settle: implicit Euler at large steps with global damping near the first mode's critical value
  // (ω₁ = 1.875² √(B / (ρ_A L⁴)), the clamped beam's), until no particle moves faster than 1e-10 m/s.
  Environment env;
  env.ground.enabled = false;
  const double omega = 3.516 * std::sqrt(material.bending_rigidity / (material.areal_density * std::pow(overhang, 4)));
  env.damping = 2.0 * omega;
  const ParticlePool& p = body.particles();
  auto maxSpeed = [&p]() { return p.velocity.leftCols(p.size()).colwise().norm().maxCoeff(); };
  for (int step = 0; step < 4000 && !(step > 20 && maxSpeed() < 1e-10); ++step)
    body.step(0.5 / omega, env);

  CantileverRun run;
  run.frozen = body.frozen();
  run.max_speed = maxSpeed();
  Eigen::Matrix3Xd force(3, p.size());
  body.computeForces(p.position.leftCols(p.size()), Eigen::Matrix3Xd::Zero(3, p.size()), env.gravity, force);
  for (int i = 0; i < p.size(); ++i)
  {
    if (body.isPinned(i)) continue;
    run.max_force_ratio = std::max(run.max_force_ratio, force.col(i).norm() / (body.definition().masses[i] * kGravity));
  }
  // The tip: the mean of the last column; the chord from the edge (x = −h/2, z = 0).
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();
  for (int b = 0; b < def.nv; ++b)
    tip += p.position.col(b * def.nu + def.nu - 1);
  tip /= def.nv;
  run.chord_angle = std::atan2(-tip.z(), tip.x() + h / 2);
  const int mid = def.nv / 2;
  for (int a = 1; a < def.nu; ++a)
    run.centre_line.push_back(p.position.col(mid * def.nu + a) + Eigen::Vector3d(h / 2, 0.0, 0.0));
  return run;
}

// The overhang [m] at which the simulated tip reaches the chord angle φ: secant iterations on the
// overhang from the elastica's answer, each a strip settled from flat.
double simulatedOverhang(const ClothMaterial& material, double phi, double start, double width, int cells,
                         CantileverRun& at_rest)
{
  double o0 = start, o1 = start * 1.02;
  double f0 = settleCantilever(material, o0, width, cells).chord_angle - phi;
  at_rest = settleCantilever(material, o1, width, cells);
  double f1 = at_rest.chord_angle - phi;
  for (int i = 0; i < 12 && std::abs(f1) > 1e-9; ++i)
  {
    const double o2 = o1 - f1 * (o1 - o0) / (f1 - f0);
    o0 = o1;
    f0 = f1;
    o1 = o2;
    at_rest = settleCantilever(material, o1, width, cells);
    f1 = at_rest.chord_angle - phi;
  }
  EXPECT_LT(std::abs(f1), 1e-7) << "the secant did not reach the 41.5° chord at " << cells << " cells";
  return o1;
}
}  // namespace

TEST(ValidationCloth, CantileverBendingLengthRecoversTheBendingRigidity)
{
  // ASTM D1388 (option A, cantilever): a 25 mm strip of the cotton preset slides over the platform's
  // edge until its tip touches the plane inclined 41.5° below it. The rigidity is recovered from the
  // overhang L through the exact heavy elastica, B = w L³ / λ(41.5°), and compared with the B entered.
  const ClothMaterial cotton = *findClothPreset("cotton");
  const double phi = 41.5 * kPi / 180.0, width = 0.025;
  const double w = cotton.areal_density * kGravity;
  const double lambda = elasticaLambda(phi);
  const double overhang = std::cbrt(lambda * cotton.bending_rigidity / w);
  // Peirce's formula behind the standard: c = L (cos(φ/2) / (8 tan φ))^(1/3), B = w c³.
  const double peirce = std::cos(phi / 2) / (8.0 * std::tan(phi));
  std::printf("elastica: lambda(41.5 deg) = %.6f (ASTM D1388 takes 8; Peirce's formula %.6f); overhang %.3f mm\n",
              lambda, 1.0 / peirce, overhang * 1e3);

  const std::vector<int> cells = {8, 16, 32};
  std::vector<double> rigidity;
  std::vector<CantileverRun> runs;
  for (int n : cells)
  {
    CantileverRun run;
    const double o = simulatedOverhang(cotton, phi, overhang, width, n, run);
    ASSERT_FALSE(run.frozen);
    // At rest: nothing moves, and the net force on every free particle is a tiny part of its weight.
    EXPECT_LT(run.max_speed, 1e-9) << n << " cells";
    EXPECT_LT(run.max_force_ratio, 1e-6) << n << " cells";
    rigidity.push_back(w * o * o * o / lambda);
    runs.push_back(run);
    std::printf("%d cells: overhang %.6f mm, B = %.6e N m (entered %.6e)\n", n, o * 1e3, rigidity.back(),
                cotton.bending_rigidity);
  }

  // Tolerance. The strip is a chain of hinges at the nodes, clamped at the pinned segment's midpoint
  // (settleCantilever): the midpoint rule of the elastica, second-order in h. The rigidity recovered
  // goes with L³, so its error is second order too; the tolerance is twice the Richardson estimate of
  // each run's error (order 2, from the next finer run; the finest from the two finest), plus 1e-6
  // for the rest state and the secant's stop (1e-9 rad of chord angle) and the membrane's stretch
  // (w L / E·t ≈ 5e-6, a strain the inextensible elastica does not have).
  const std::vector<double> estimate = richardsonErrors(rigidity, cotton.bending_rigidity, 2.0, 2.0);
  ValidationCase c;
  c.id = "cantilever";
  c.title = "Cantilever bending length (ASTM D1388): bending rigidity";
  c.quantity = "bending rigidity B recovered from the 41.5 deg overhang";
  c.unit = "N·m";
  c.reference = cotton.bending_rigidity;
  c.source = "the B entered (cotton preset); recovered as B = w L^3 / lambda, lambda(41.5 deg) = " + formatted(lambda) +
             " from the heavy elastica (clamped, inextensible; shooting with RK4)";
  for (std::size_t i = 0; i < cells.size(); ++i)
  {
    const double overhang_i = std::cbrt(rigidity[i] * lambda / w);
    c.runs.push_back({std::to_string(cells[i]) + " cells along L = " + formatted(overhang_i * 1e3, 5) + " mm",
                      rigidity[i], (rigidity[i] - c.reference) / c.reference, 2.0 * estimate[i] + 1e-6});
  }

  // Plot: the elastica at 41.5° (block 0) and each resolution's centre line at its own overhang, in
  // units of the elastica's overhang (blocks 1-3).
  std::ostringstream dat;
  dat << "# x / L, z / L\n";
  const ElasticaShape exact = elastica(lambda, true);
  for (std::size_t i = 0; i < exact.xz.size(); i += 40)
    dat << exact.xz[i][0] << ' ' << exact.xz[i][1] << '\n';
  for (const CantileverRun& run : runs)
  {
    dat << "\n\n0 0\n";
    for (const Eigen::Vector3d& x : run.centre_line)
      dat << x.x() / overhang << ' ' << x.z() / overhang << '\n';
  }
  c.plot_data = dat.str();
  c.plot_script =
      "set terminal pngcairo size 900,600 enhanced font 'DejaVu Sans,11'\n"
      "set output 'cantilever.png'\n"
      "set title 'Cantilever (ASTM D1388): cotton strip at the 41.5° overhang, against the heavy elastica'\n"
      "set xlabel 'x / L'\nset ylabel 'z / L'\nset size ratio -1\nset grid\nset key bottom left box opaque\n"
      "set xrange [-0.05:1.05]\nset yrange [-0.75:0.1]\n"
      "set arrow from 0,0 to 1.0,-tan(41.5*pi/180) nohead dt 2 lc rgb '#999999'\n"
      "plot 'cantilever.dat' index 0 with lines lw 2 lc rgb '#333333' title 'heavy elastica (exact)', \\\n"
      "  '' index 1 with linespoints pt 6 ps 1.4 lc rgb '#d95f02' title '8 cells', \\\n"
      "  '' index 2 with linespoints pt 8 ps 1.0 lc rgb '#7570b3' title '16 cells', \\\n"
      "  '' index 3 with lines lw 1 lc rgb '#1b9e77' title '32 cells'\n";
  checkAndReport(c);
}
