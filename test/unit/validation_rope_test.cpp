// Ropes against published physics (issue 17): a heavy elastic catenary (Irvine), the speed of a
// transverse wave on a taut rope (√(T/μ)) and the lowest mode of a hanging chain (Bernoulli/Euler,
// Bessel J₀). Each case is computed at three resolutions from the same material in physical units
// (RopeDef::material), asserted against the reference within a tolerance derived from the
// discretisation error, asserted to converge, and reported through validation_report.h for
// docs/validation.md (scripts/bench --validation).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/verlet.h"
#include "particle_sim/core/spring_network.h"
#include "validation_report.h"

using namespace particle_sim::core;
using particle_sim_test::checkAndReport;
using particle_sim_test::richardsonErrors;
using particle_sim_test::ValidationCase;
using particle_sim_test::ValidationRun;

namespace
{
constexpr double kPi = 3.14159265358979323846;
constexpr double kGravity = 9.81;  // [m/s²], Environment's default

RopeMaterial material(double linear_density, double axial_stiffness, double damping_ratio)
{
  RopeMaterial m;
  m.linear_density = linear_density;
  m.axial_stiffness = axial_stiffness;
  m.bending_stiffness = 0.0;
  m.damping_ratio = damping_ratio;
  return m;
}

Environment withoutGround(double gravity)
{
  Environment env;
  env.ground.enabled = false;
  env.gravity = Eigen::Vector3d(0.0, 0.0, -gravity);
  return env;
}

double maxSpeed(const SpringNetworkBody& body)
{
  const ParticlePool& p = body.particles();
  return p.velocity.leftCols(p.size()).colwise().norm().maxCoeff();
}

std::string formatted(double value)
{
  std::ostringstream out;
  out.precision(10);
  out << value;
  return out.str();
}

// --- Heavy elastic catenary -------------------------------------------------------------------------
// Irvine, Cable Structures (1981), ch. 2 (the elastic catenary): a cable of unstretched length L₀, weight w = μ g per
// unstretched length and axial stiffness EA hanging between supports at equal height `span` apart.
// With s the unstretched arc length from the left support, V = w L₀ / 2 the vertical reaction and
// H the horizontal tension:
//   x(s) = H s / EA + (H / w) [asinh(V / H) − asinh((V − w s) / H)]
//   z(s) = −(V s − w s² / 2) / EA − (H / w) [√(1 + (V / H)²) − √(1 + ((V − w s) / H)²)]
// and H is the root of x(L₀) = span.
struct ElasticCatenary
{
  double w, axial_stiffness, length, span;

  double x(double h, double s) const
  {
    const double v = w * length / 2.0;
    return h * s / axial_stiffness + h / w * (std::asinh(v / h) - std::asinh((v - w * s) / h));
  }
  double z(double h, double s) const
  {
    const double v = w * length / 2.0;
    return -(v * s - w * s * s / 2.0) / axial_stiffness -
           h / w * (std::sqrt(1.0 + (v / h) * (v / h)) - std::sqrt(1.0 + ((v - w * s) / h) * ((v - w * s) / h)));
  }
  // x(L₀) grows with H: bisection to machine precision.
  double horizontalTension() const
  {
    double low = 1e-9 * w * length, high = 1e9 * w * length;
    for (int i = 0; i < 200; ++i)
    {
      const double mid = std::sqrt(low * high);
      (x(mid, length) < span ? low : high) = mid;
    }
    return std::sqrt(low * high);
  }
};

struct CatenaryRun
{
  double sag;                          // [m] depth of the mid particle below the supports
  double tension;                      // [N] horizontal tension H (the same in every segment at rest)
  std::vector<Eigen::Vector3d> shape;  // [m] the particles at rest
};

// The rope settles under implicit Euler (its numerical damping takes the swing out; at a fixed point
// of the linearised step the forces vanish, so the state it stops in is the static equilibrium).
CatenaryRun settleCatenary(const RopeMaterial& mat, double length, double span, int segments)
{
  RopeDef def;
  def.name = "catenary";
  def.particles = segments + 1;
  def.start = {0.0, 0.0, 0.0};
  def.end = {span, 0.0, 0.0};
  def.rest_length = length;
  def.material = mat;
  def.pins = {0, -1};
  def.integrator.type = kImplicitEulerIntegrator;
  def.integrator.cg_tolerance = 1e-12;
  def.integrator.cg_max_iterations = 2000;
  const Status valid = validate(def, 100000);
  EXPECT_TRUE(valid.ok) << valid.message;
  SpringNetworkDef net = buildRope(def);
  // Start from the inextensible parabola of the same length (sag d: L₀ ≈ span + 8 d² / (3 span)), not
  // from the straight line, whose segments would start compressed.
  const double d = std::sqrt(3.0 * span * (length - span) / 8.0);
  for (int i = 0; i <= segments; ++i)
  {
    const double x = span * i / segments;
    net.positions[i] = Eigen::Vector3d(x, 0.0, -4.0 * d * x * (span - x) / (span * span));
  }
  SpringNetworkBody body(net);
  const Environment env = withoutGround(kGravity);
  for (int step = 0; step < 20000 && !(step > 100 && maxSpeed(body) < 1e-11); ++step)
    body.step(0.05, env);
  EXPECT_FALSE(body.frozen()) << body.frozenReason();

  // At rest: no particle moves and the net force on every free particle is negligible against its
  // weight.
  const ParticlePool& p = body.particles();
  EXPECT_LT(maxSpeed(body), 1e-9) << segments << " segments";
  Eigen::Matrix3Xd force(3, p.size());
  body.computeForces(p.position.leftCols(p.size()), p.velocity.leftCols(p.size()), env.gravity, force);
  const double weight = mat.linear_density * length / segments * kGravity;
  for (int i = 1; i < segments; ++i)
    EXPECT_LT(force.col(i).norm(), 1e-7 * weight) << "particle " << i << " of " << segments << " segments";

  CatenaryRun run;
  run.sag = -p.position(2, segments / 2);
  const Eigen::Vector3d first = p.position.col(1) - p.position.col(0);
  const double segment = length / segments;
  const double k = mat.axial_stiffness / segment;
  run.tension = k * (first.norm() - segment) * first.x() / first.norm();
  for (int i = 0; i <= segments; ++i)
    run.shape.push_back(p.position.col(i));
  return run;
}

TEST(ValidationRope, ElasticCatenaryMatchesIrvine)
{
  // A 10 m nylon-like rope (μ = 0.5 kg/m, EA = 500 N: it stretches about 5 % under its own weight, so
  // the elastic terms matter) hanging between supports 8 m apart.
  const double mu = 0.5, ea = 500.0, length = 10.0, span = 8.0;
  const RopeMaterial mat = material(mu, ea, 0.2);
  const ElasticCatenary exact{mu * kGravity, ea, length, span};
  const double h = exact.horizontalTension();
  const double sag = -exact.z(h, length / 2.0);

  const std::vector<int> segments = {16, 32, 64};
  std::vector<CatenaryRun> runs;
  for (int n : segments)
    runs.push_back(settleCatenary(mat, length, span, n));

  // Tolerance. The lumped-mass chain carries the weight of each segment at its ends (the trapezoidal
  // rule along the unstretched arc length) and is second-order accurate: error ≈ C / N². The error of
  // each run is estimated from it and the next finer run (Richardson, order 2); the tolerance is twice
  // that estimate (the N⁻² law is asymptotic), plus 1e-6 for the rest state (force residual 1e-7 of a
  // particle's weight, CG tolerance 1e-12).
  auto makeCase = [&](const std::string& id, const std::string& title, const std::string& quantity, double reference,
                      const std::string& source, const std::vector<double>& values) {
    ValidationCase c;
    c.id = id;
    c.title = title;
    c.quantity = quantity;
    c.unit = quantity == "mid-span sag" ? "m" : "N";
    c.reference = reference;
    c.source = source;
    const std::vector<double> estimate = richardsonErrors(values, reference, 2.0, 2.0);
    for (std::size_t i = 0; i < values.size(); ++i)
      c.runs.push_back({std::to_string(segments[i]) + " segments", values[i], (values[i] - reference) / reference,
                        2.0 * estimate[i] + 1e-6});
    return c;
  };
  const std::string source =
      "elastic catenary, Irvine, Cable Structures (1981), ch. 2: closed form in the "
      "unstretched arc length, H from x(L0) = span";
  ValidationCase sag_case = makeCase("catenary_sag", "Heavy elastic catenary: mid-span sag", "mid-span sag", sag,
                                     source, {runs[0].sag, runs[1].sag, runs[2].sag});
  ValidationCase tension_case =
      makeCase("catenary_tension", "Heavy elastic catenary: horizontal tension", "horizontal tension H", h, source,
               {runs[0].tension, runs[1].tension, runs[2].tension});

  // Plot: the exact curve (block 0), then the particles at rest of each resolution (blocks 1-3).
  std::ostringstream dat;
  dat << "# x [m] z [m]\n";
  for (int i = 0; i <= 400; ++i)
    dat << exact.x(h, length * i / 400) << ' ' << exact.z(h, length * i / 400) << '\n';
  for (const CatenaryRun& run : runs)
  {
    dat << "\n\n";
    for (const Eigen::Vector3d& x : run.shape)
      dat << x.x() << ' ' << x.z() << '\n';
  }
  sag_case.plot_data = dat.str();
  sag_case.plot_script =
      "set terminal pngcairo size 900,560 enhanced font 'DejaVu Sans,11'\n"
      "set output 'catenary_sag.png'\n"
      "set title 'Elastic catenary: L_0 = 10 m, span 8 m, {/Symbol m} = 0.5 kg/m, EA = 500 N'\n"
      "set xlabel 'x [m]'\nset ylabel 'z [m]'\nset size ratio -1\nset grid\n"
      "set key top center box opaque\nset yrange [-3.2:0.6]\n"
      "plot 'catenary_sag.dat' index 0 with lines lw 2 lc rgb '#333333' title 'Irvine (exact)', \\\n"
      "  '' index 1 with points pt 6 ps 1.6 lc rgb '#d95f02' title '16 segments', \\\n"
      "  '' index 2 with points pt 8 ps 1.2 lc rgb '#7570b3' title '32 segments', \\\n"
      "  '' index 3 with points pt 7 ps 0.6 lc rgb '#1b9e77' title '64 segments'\n";
  checkAndReport(sag_case);
  checkAndReport(tension_case);
}

// --- Wave speed -----------------------------------------------------------------------------------
// A rope of rest length L₀ stretched by ε between two pins carries T = EA ε over a linear density
// μ / (1 + ε); a small transverse pulse travels at c = √(T (1 + ε) / μ) (the string's wave equation).

struct WaveRun
{
  double speed;                                  // [m/s] (x₂ − x₁) / (t₂ − t₁) of the pulse's peak
  std::vector<std::pair<double, double>> trace;  // (t [s], displacement [m]) at the second station
};

// Time of the largest sample, refined by the parabola through it and its neighbours [s].
double peakTime(const std::vector<double>& samples, double dt)
{
  const std::size_t i = std::max_element(samples.begin(), samples.end()) - samples.begin();
  if (i == 0 || i + 1 >= samples.size()) return static_cast<double>(i) * dt;
  const double a = samples[i - 1], b = samples[i], c = samples[i + 1];
  return (static_cast<double>(i) + 0.5 * (a - c) / (a - 2.0 * b + c)) * dt;
}

WaveRun runPulse(const RopeMaterial& mat, double rest_length, double strain, int segments, double amplitude,
                 double width_time, const std::vector<double>& stations)
{
  const double span = rest_length * (1.0 + strain);
  RopeDef def;
  def.name = "taut";
  def.particles = segments + 1;
  def.start = {0.0, 0.0, 1.0};
  def.end = {span, 0.0, 1.0};
  def.rest_length = rest_length;
  def.material = mat;
  def.pins = {0, -1};
  def.integrator.type = kVerletIntegrator;
  def.integrator.verlet_damping = 1.0;
  const Status valid = validate(def, 100000);
  EXPECT_TRUE(valid.ok) << valid.message;
  SpringNetworkBody body(buildRope(def));
  const Environment env = withoutGround(0.0);

  // Step: half the stability limit of the axial waves (h ω_max = 1, ω_max = 2 √(EA / μ) / l), so no
  // substeps are added and the transverse Courant number c h / a stays √ε / 2.
  const double segment = rest_length / segments;
  const double dt = 0.5 * segment / std::sqrt(mat.axial_stiffness / mat.linear_density);
  const double c = std::sqrt(mat.axial_stiffness * strain * (1.0 + strain) / mat.linear_density);
  const double launch = 4.0 * width_time;  // the pulse's peak leaves the pin at t = launch
  const double duration = launch + stations.back() / c + 4.0 * width_time;
  const int steps = static_cast<int>(std::ceil(duration / dt));
  const int steps_per_sample = std::max(1, static_cast<int>(std::lround(2e-3 / dt)));  // plot every 2 ms

  // The left pin moves up and back down: z = A exp(−((t − launch) / τ)²).
  std::vector<int> station_index;
  for (double x : stations)
    station_index.push_back(static_cast<int>(std::lround(x / span * segments)));
  std::vector<std::vector<double>> samples(stations.size());
  WaveRun run;
  const Eigen::Vector3d left = def.start;
  for (int n = 1; n <= steps; ++n)
  {
    const double t = n * dt;
    const double lift = amplitude * std::exp(-std::pow((t - launch) / width_time, 2));
    EXPECT_TRUE(body.setPinTarget(0, left + Eigen::Vector3d(0.0, 0.0, lift)).ok);
    body.step(dt, env);
    for (std::size_t s = 0; s < stations.size(); ++s)
      samples[s].push_back(body.particles().position(2, station_index[s]) - left.z());
    if (n % steps_per_sample == 0) run.trace.push_back({t, samples.back().back()});
  }
  EXPECT_FALSE(body.frozen()) << body.frozenReason();
  EXPECT_EQ(body.lastSubsteps(), 1);
  const double x1 = span * station_index[0] / segments, x2 = span * station_index[1] / segments;
  // Samples are taken at t = (k + 1) dt; the offset cancels in the difference.
  run.speed = (x2 - x1) / (peakTime(samples[1], dt) - peakTime(samples[0], dt));
  return run;
}

TEST(ValidationRope, TransversePulseTravelsAtTheStringWaveSpeed)
{
  // A 10 m rope (μ = 0.1 kg/m, EA = 1000 N) stretched by 1 % (T = 10 N, c ≈ 10.05 m/s); a 1 mm pulse
  // of duration τ = 0.05 s (width σ = c τ ≈ 0.5 m) launched at the left pin, timed at 3 m and 7 m.
  const double mu = 0.1, ea = 1000.0, length = 10.0, strain = 0.01, amplitude = 1e-3, tau = 0.05;
  const RopeMaterial mat = material(mu, ea, 0.0);
  const double c = std::sqrt(ea * strain * (1.0 + strain) / mu);
  const double sigma = c * tau;
  const std::vector<double> stations = {3.0, 7.0};
  const std::vector<int> segments = {50, 100, 200};

  ValidationCase wave;
  wave.id = "wave_speed";
  wave.title = "Wave speed on a taut rope";
  wave.quantity = "transverse wave speed";
  wave.unit = "m/s";
  wave.reference = c;
  wave.source = "string wave equation: c = sqrt(T / mu_stretched), T = EA strain, mu_stretched = mu / (1 + strain)";
  std::ostringstream dat;
  dat << "# t [s] displacement [mm] at the particle nearest x = 7 m; blocks: exact (non-dispersive), 50, 100, 200 "
         "segments\n";
  const double launch = 4.0 * tau;
  for (int i = 0; i <= 400; ++i)
  {
    const double t = launch + stations[1] / c + tau * (-4.0 + 8.0 * i / 400);
    dat << t << ' ' << 1e3 * amplitude * std::exp(-std::pow((t - launch - stations[1] / c) / tau, 2)) << '\n';
  }
  for (int n : segments)
  {
    const WaveRun run = runPulse(mat, length, strain, n, amplitude, tau, stations);
    // Tolerance. The chain's dispersion ω = 2 (c / a) sin(q a / 2) (a = stretched segment length)
    // delays a component of frequency ω over a distance x by x / c · (1 + (ω a / c)² / 24). For the
    // Gaussian pulse g(s) = exp(−s² / τ²), s = t − x / c, this adds γ g‴(s) with γ = a² x / (24 c³),
    // which moves the peak by −γ g⁗(0) / g″(0) = 6 γ / τ²: the peak travels a² / (4 σ²) slower
    // (σ = c τ). Verlet's own dispersion is faster by (c h / a)² = ε / 4 of that. The tolerance is twice
    // the estimate (the analysis is first order in the dispersion); the nonlinear tension change of a
    // 1 mm pulse (EA slope² / 2 ≈ 1.5e-3 N of 10 N, c up by < 1e-4) is far below it.
    const double a = length * (1.0 + strain) / n;
    const double tolerance = 2.0 * a * a / (4.0 * sigma * sigma);
    wave.runs.push_back({std::to_string(n) + " segments", run.speed, (run.speed - c) / c, tolerance});
    dat << "\n\n";
    for (const auto& [t, z] : run.trace)
      if (std::abs(t - launch - stations[1] / c) <= 4.0 * tau) dat << t << ' ' << 1e3 * z << '\n';
  }
  // The bound: ±1 % at the fine grid.
  EXPECT_LE(std::abs(wave.runs.back().error), 0.01);
  wave.plot_data = dat.str();
  wave.plot_script =
      "set terminal pngcairo size 900,560 enhanced font 'DejaVu Sans,11'\n"
      "set output 'wave_speed.png'\n"
      "set title 'Pulse passing the particle nearest x = 7 m on a taut rope (T = 10 N, {/Symbol m} = 0.1 kg/m, "
      "launched at x = 0)'\n"
      "set xlabel 't [s]'\nset ylabel 'transverse displacement [mm]'\nset grid\n"
      "set key top right\n"
      "plot 'wave_speed.dat' index 0 with lines lw 2 dt 2 lc rgb '#333333' title "
      "'exact arrival, c = " +
      formatted(std::round(c * 1000) / 1000) +
      " m/s', \\\n"
      "  '' index 1 with lines lw 2 lc rgb '#d95f02' title '50 segments', \\\n"
      "  '' index 2 with lines lw 2 lc rgb '#7570b3' title '100 segments', \\\n"
      "  '' index 3 with lines lw 2 lc rgb '#1b9e77' title '200 segments'\n";
  checkAndReport(wave);
}

// --- Chain pendulum -------------------------------------------------------------------------------
// A uniform chain of length L hanging from a pin swings in modes u(s) = J₀(2 ω √(s / g)), s measured
// from the free end; the pin (u(L) = 0) makes 2 ω √(L / g) a zero of J₀, so the lowest mode has
// ω₁ = (j₀,₁ / 2) √(g / L), j₀,₁ = 2.404826 (D. Bernoulli 1733, Euler; e.g. Goldstein, Classical
// Mechanics, or Rao, Mechanical Vibrations, the hanging chain).
constexpr double kJ01 = 2.404825557695773;

struct ChainRun
{
  double period;                                 // [s] mean of the periods between upward zero crossings
  std::vector<std::pair<double, double>> trace;  // (t [s], free end's x [m])
};

ChainRun swingChain(const RopeMaterial& mat, double length, int segments, double amplitude, double periods)
{
  RopeDef def;
  def.name = "chain";
  def.particles = segments + 1;
  def.start = {0.0, 0.0, 0.0};
  def.end = {0.0, 0.0, -length};
  def.material = mat;
  def.pins = {0};
  def.integrator.type = kVerletIntegrator;
  def.integrator.verlet_damping = 1.0;
  const Status valid = validate(def, 100000);
  EXPECT_TRUE(valid.ok) << valid.message;
  SpringNetworkDef net = buildRope(def);

  // Start at rest in the static stretch (each segment carries the weight below it) displaced sideways
  // by the mode shape A J₀(j₀,₁ √(s / L)), s the unstretched arc length from the free end.
  const double segment = length / segments;
  double z = 0.0;
  for (int i = 0; i <= segments; ++i)
  {
    if (i > 0)
    {
      double below = 0.0;
      for (int j = i; j <= segments; ++j)
        below += net.masses[j];
      z -= segment * (1.0 + below * kGravity / mat.axial_stiffness);
    }
    const double s = length - segment * i;
    net.positions[i] = Eigen::Vector3d(amplitude * std::cyl_bessel_j(0.0, kJ01 * std::sqrt(s / length)), 0.0, z);
  }
  SpringNetworkBody body(net);
  const Environment env = withoutGround(kGravity);

  // Step: 0.8 of the axial stability limit (h ω_max = 1.6 < 2, ω_max = 2 √(EA / μ) / l): Verlet's
  // phase error on the swing, (ω₁ h)² / 24, is then below 1e-10.
  const double dt = 0.8 * segment / std::sqrt(mat.axial_stiffness / mat.linear_density);
  const double omega = 0.5 * kJ01 * std::sqrt(kGravity / length);
  const int steps = static_cast<int>(std::ceil(periods * 2.0 * kPi / omega / dt));
  const int steps_per_sample = std::max(1, static_cast<int>(std::lround(2e-3 / dt)));  // plot every 2 ms
  ChainRun run;
  std::vector<double> crossings;
  double previous = body.particles().position(0, segments);
  for (int n = 1; n <= steps; ++n)
  {
    body.step(dt, env);
    const double x = body.particles().position(0, segments);
    // Upward zero crossing, interpolated linearly within the step (error O(dt²)).
    if (previous < 0.0 && x >= 0.0) crossings.push_back((n - 1 + previous / (previous - x)) * dt);
    previous = x;
    if (n % steps_per_sample == 0) run.trace.push_back({n * dt, x});
  }
  EXPECT_FALSE(body.frozen()) << body.frozenReason();
  EXPECT_GE(crossings.size(), 2u) << segments << " segments";
  run.period = crossings.size() >= 2 ? (crossings.back() - crossings.front()) / (crossings.size() - 1) : 0.0;
  return run;
}

TEST(ValidationRope, HangingChainLowestModeMatchesBessel)
{
  // A 1 m chain (μ = 0.1 kg/m, EI = 0) with EA = 1e4 N: it stretches by μ g L / EA ≈ 1e-4 at the top,
  // a model difference from the inextensible reference of that relative size. Free end displaced 1 cm
  // (the amplitude's own frequency shift, of order (A / L)², is 1e-4 at most).
  const double mu = 0.1, ea = 1e4, length = 1.0, amplitude = 0.01;
  const RopeMaterial mat = material(mu, ea, 0.0);
  const double period = 2.0 * kPi / (0.5 * kJ01 * std::sqrt(kGravity / length));
  const std::vector<int> segments = {8, 16, 32};

  ValidationCase chain;
  chain.id = "chain_pendulum";
  chain.title = "Hanging chain: lowest mode";
  chain.quantity = "period of the lowest mode";
  chain.unit = "s";
  chain.reference = period;
  chain.source =
      "hanging chain (Bernoulli, Euler): omega1 = (j01 / 2) sqrt(g / L), j01 = 2.404826; Goldstein, "
      "Classical Mechanics";
  std::vector<ChainRun> runs;
  std::vector<double> values;
  for (int n : segments)
  {
    runs.push_back(swingChain(mat, length, n, amplitude, 3.2));
    values.push_back(runs.back().period);
  }
  // Tolerance. The lumped chain (masses μ l, μ l / 2 at the free end) is a second-order
  // discretisation of the hanging chain's equation (its modes J₀(2 ω √(s / g)) are smooth in s): the
  // error of each run is estimated from it and the next finer run (Richardson, order 2) and the
  // tolerance is twice that, plus the stretch μ g L / EA (the reference is inextensible) and the
  // amplitude's (A / L)².
  const std::vector<double> estimate = richardsonErrors(values, period, 2.0, 2.0);
  for (std::size_t i = 0; i < values.size(); ++i)
    chain.runs.push_back({std::to_string(segments[i]) + " segments", values[i], (values[i] - period) / period,
                          2.0 * estimate[i] + mu * kGravity * length / ea + amplitude * amplitude / (length * length)});

  std::ostringstream dat;
  dat << "# t [s] free end's x [mm]; blocks: exact lowest mode, 8, 16, 32 segments\n";
  const double omega = 2.0 * kPi / period;
  for (int i = 0; i <= 600; ++i)
  {
    const double t = 3.2 * period * i / 600;
    dat << t << ' ' << 1e3 * amplitude * std::cos(omega * t) << '\n';
  }
  for (const ChainRun& run : runs)
  {
    dat << "\n\n";
    for (const auto& [t, x] : run.trace)
      dat << t << ' ' << 1e3 * x << '\n';
  }
  chain.plot_data = dat.str();
  // Left: the whole run; right: the last upward zero crossing, where the periods' differences add up.
  const double last_crossing = 2.75 * period;
  const std::string plot =
      "plot 'chain_pendulum.dat' index 0 with lines lw 2 dt 2 lc rgb '#333333' title 'Bessel', \\\n"
      "  '' index 1 with lines lw 1.5 lc rgb '#d95f02' title '8 segments', \\\n"
      "  '' index 2 with lines lw 1.5 lc rgb '#7570b3' title '16 segments', \\\n"
      "  '' index 3 with lines lw 1.5 lc rgb '#1b9e77' title '32 segments'\n";
  chain.plot_script =
      "set terminal pngcairo size 1200,520 enhanced font 'DejaVu Sans,11'\n"
      "set output 'chain_pendulum.png'\n"
      "set multiplot layout 1,2 title 'Hanging chain, L = 1 m, lowest mode: free end against "
      "A cos({/Symbol w}_1 t)'\n"
      "set xlabel 't [s]'\nset ylabel 'free end x [mm]'\nset grid\nset key top right box opaque\n"
      "set title 'three periods'\nset yrange [-12:16]\n" +
      plot + "set title 'zoom on the third upward zero crossing'\nset autoscale y\nset xrange [" +
      formatted(last_crossing - 0.03) + ":" + formatted(last_crossing + 0.03) + "]\nset key top left\n" + plot +
      "unset multiplot\n";
  checkAndReport(chain);
}

}  // namespace
