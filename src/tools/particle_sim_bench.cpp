// particle_sim_bench: the speed-versus-error report (issue #6). Runs the canonical scenes of
// config/scenes/bench/ with every integrator at a sweep of steps, and writes
//   work_precision.csv  one row per (scene, integrator, dt): status, RMS position error, wall time
//   references.csv      one row per scene: what the error is measured against, and how good that is
//   stability.csv       largest stable dt of each integrator on a spring of growing stiffness
// plus, with --tables, the markdown tables of docs/accuracy.md. scripts/bench runs it and plots.
//
//   particle_sim_bench [--scenes DIR] [--out DIR] [--tables FILE] [--only NAME,...] [--no-stability] [--quick]
//
// It needs no ROS and no source tree: the default scenes are found through the package (see
// findBenchScenes), and the output folder is created; so `rosrun particle_sim particle_sim_bench`
// works from any folder.
//
// Error: the RMS over the free (not pinned) particles of |x − x_ref| at the final time. The
// reference is the analytic answer where there is one (oscillator, hanging rope's equilibrium,
// ballistic emitters), else the same scene under RK4 at a much smaller step, checked against RK4
// at half that step. Work: wall time of the stepping loop (std::chrono::steady_clock) per
// simulated second, the median of repeated runs when one run is short.

#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "particle_sim/core/integrators/registry.h"
#include "particle_sim/core/integrators/verlet.h"
#include "particle_sim/process/huge_pages.h"
#include "particle_sim/scene/scene.h"

namespace
{
namespace core = particle_sim::core;
namespace scene = particle_sim::scene;
using Clock = std::chrono::steady_clock;

constexpr const char* kUsage =
    "usage: particle_sim_bench [--scenes DIR] [--out DIR] [--tables FILE] [--only NAME,...] [--no-stability] "
    "[--quick]\n"
    "  --scenes DIR     the bench scenes (default: config/scenes/bench of the particle_sim package,\n"
    "                   found beside this executable's install space, in the source folder it was\n"
    "                   built from, or on ROS_PACKAGE_PATH)\n"
    "  --out DIR        where the CSV files go, created if missing (default bench_results in the\n"
    "                   current folder; scripts/bench writes docs/bench)\n"
    "  --tables FILE    also write the markdown tables of docs/accuracy.md to FILE\n"
    "  --only NAMES     run only these scenes (comma-separated file stems)\n"
    "  --no-stability   skip the stability map\n"
    "  --quick          fewer steps and repeats: a smoke run, not a report\n";

// ---------------------------------------------------------------------------------------------
// The cases: which scene, against what, over how long and at which steps.

enum class ReferenceKind
{
  Oscillator,   // x(t) = L + A cos ωt + (v0/ω) sin ωt along the spring
  Equilibrium,  // a hanging rope's static equilibrium
  Ballistic,    // every emitted particle on x0 + v0 a + g a²/2
  FineRk4,      // the same scene under RK4 at dt_ref/2, checked against RK4 at dt_ref
};

const char* describe(ReferenceKind kind)
{
  switch (kind)
  {
    case ReferenceKind::Oscillator:
      return "analytic: L + A cos(wt)";
    case ReferenceKind::Equilibrium:
      return "analytic static equilibrium";
    case ReferenceKind::Ballistic:
      return "analytic: x0 + v0 a + g a^2/2";
    case ReferenceKind::FineRk4:
      return "rk4 at a small step";
  }
  return "";
}

struct Case
{
  std::string name;   // scene file stem; the key in every CSV
  std::string title;  // for tables and plots
  ReferenceKind reference;
  double duration;          // [s] simulated; error measured at this time
  std::vector<double> dts;  // [s] swept steps, each dividing `duration`
  double dt_ref = 0.0;      // [s] FineRk4: the checked reference step (the reference runs at half of it)
};

// Steps dt0, dt0/2, ... (count of them).
std::vector<double> halvings(double dt0, int count)
{
  std::vector<double> dts;
  for (int i = 0; i < count; ++i)
    dts.push_back(dt0 / std::pow(2.0, i));
  return dts;
}

// Steps from well above the explicit methods' limits (where only implicit Euler runs: the steps a
// display rate would like) down to where RK4 reaches round-off; each divides the duration exactly.
std::vector<Case> benchCases(bool quick)
{
  auto sweep = [&](double dt0, int count) { return halvings(dt0, quick ? count / 2 : count); };
  std::vector<Case> cases = {
      {"oscillator", "spring oscillator (analytic)", ReferenceKind::Oscillator, 2.0, sweep(2.0 / 32, 8)},
      {"chain_pendulum", "chain pendulum", ReferenceKind::FineRk4, 0.5, sweep(0.5 / 32, 10), 2.5e-6},
      {"hanging_rope", "hanging rope: static equilibrium", ReferenceKind::Equilibrium, 8.0, sweep(0.064, 10)},
      {"cloth_springs", "spring cloth hanging from two corners", ReferenceKind::FineRk4, 0.3, sweep(0.3 / 16, 10),
       2e-5},
      {"cloth_baraff_witkin", "Baraff-Witkin cloth hanging from two corners", ReferenceKind::FineRk4, 0.3,
       sweep(0.3 / 16, 10), 2e-5},
      {"cloth_on_sphere", "cloth falling onto a sphere", ReferenceKind::FineRk4, 0.4, sweep(0.4 / 32, 9), 5e-6},
      {"jelly_drop", "jelly drop", ReferenceKind::FineRk4, 0.4, sweep(0.4 / 32, 9), 5e-6},
      {"cloths_stacked_on_sphere", "two stacked cloths falling onto a sphere (self-collision)",
       ReferenceKind::FineRk4, 0.4, sweep(0.4 / 32, 9), 2e-5},
      {"emitters",
       "emitters (analytic ballistic paths)",
       ReferenceKind::Ballistic,
       1.0,
       {1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4}},
  };
  if (quick)
  {
    for (Case& c : cases)
    {
      c.duration = c.reference == ReferenceKind::Equilibrium ? 4.0 : c.duration;
      if (c.dt_ref > 0.0) c.dt_ref *= 4.0;
    }
  }
  return cases;
}

// ---------------------------------------------------------------------------------------------
// Setting a scene's integrator and step.

// The stability guard of issue #6 splits explicit steps into substeps where they would be unstable
// (IntegratorDef::max_substeps). The bench measures each method as it is: one substep per step.
// (Compiles with or without that field.)
template <class D>
auto oneSubstep(D& def, int) -> decltype(def.max_substeps = 1, void())
{
  def.max_substeps = 1;
}
template <class D>
void oneSubstep(D&, long)
{}

// The integrators to compare: every method of the core's registry, then `auto`.
std::vector<std::string> integratorNames()
{
  std::vector<std::string> names;
  for (const core::IntegratorInfo& info : core::integratorRegistry())
    names.push_back(info.name);
  names.push_back(core::toString(core::kAutoIntegrator));
  return names;
}

void setIntegrator(scene::SceneDef& def, const std::string& name)
{
  core::IntegratorType type;
  if (!core::parseIntegratorType(name, type)) return;  // emitters' "ballistic": no integrator
  const bool raw = name != "auto";
  scene::editIntegrators(def, [&](core::IntegratorDef& integrator) {
    integrator.type = type;
    if (raw) oneSubstep(integrator, 0);
  });
}

// ---------------------------------------------------------------------------------------------
// Running a scene.

enum class RunStatus
{
  Stable,
  Unstable,  // a body froze (non-finite state or failed solve)
  Diverged,  // finite but flew away (|x| > 1e6 m or an error above kDivergedError)
};

const char* toString(RunStatus status)
{
  switch (status)
  {
    case RunStatus::Stable:
      return "stable";
    case RunStatus::Unstable:
      return "unstable";
    case RunStatus::Diverged:
      return "diverged";
  }
  return "";
}

// Nothing in a bench scene moves more than a few metres: an error above this is a blow-up.
constexpr double kDivergedError = 10.0;  // [m]

struct Run
{
  std::unique_ptr<core::World> world;  // state at the final time (first run)
  RunStatus status = RunStatus::Stable;
  std::string why;
  double wall_per_sim = 0.0;  // [s per simulated s], median over repeats
  int repeats = 0;
  double cg_per_step = 0.0;  // mean CG iterations per step over the implicit bodies
};

bool anyFrozen(const core::World& world, std::string& why)
{
  for (const auto& body : world.bodies())
  {
    const auto* spring_body = dynamic_cast<const core::SpringNetworkBody*>(body.get());
    if (spring_body && spring_body->frozen())
    {
      why = spring_body->frozenReason();
      return true;
    }
  }
  return false;
}

double largestCoordinate(const core::World& world)
{
  double largest = 0.0;
  for (const auto& body : world.bodies())
  {
    const auto& p = body->particles();
    for (int i = 0; i < p.size(); ++i)
      largest = std::max(largest, p.position.col(i).cwiseAbs().maxCoeff());
  }
  return largest;
}

// One run of `def` for `duration` [s]: builds the world (not timed), then steps it (timed).
// Stops early once a body froze or the state flew away.
bool runOnce(const scene::SceneDef& def, double duration, Run& run, double& seconds, std::string& error)
{
  // One thread per world, as the report says: its costs compare methods, not thread counts.
  scene::SceneDef one_thread = def;
  one_thread.world.threads = 1;
  std::unique_ptr<core::World> world;
  if (auto status = scene::buildWorld(one_thread, world); !status)
  {
    error = status.message;
    return false;
  }
  const double dt = world->dt();
  const auto steps = static_cast<long long>(std::llround(duration / dt));
  long long cg_iterations = 0;
  run.status = RunStatus::Stable;
  const auto start = Clock::now();
  for (long long k = 1; k <= steps; ++k)
  {
    scene::stepScene(def, *world);
    for (const auto& body : world->bodies())
    {
      if (const auto* spring_body = dynamic_cast<const core::SpringNetworkBody*>(body.get()))
        cg_iterations += spring_body->lastSolve().iterations;
    }
    if (k % 64 == 0 || k == steps)
    {
      if (anyFrozen(*world, run.why))
      {
        run.status = RunStatus::Unstable;
        break;
      }
      if (!(largestCoordinate(*world) < 1e6))
      {
        run.status = RunStatus::Diverged;
        run.why = "coordinates beyond 1e6 m";
        break;
      }
    }
  }
  seconds = std::chrono::duration<double>(Clock::now() - start).count();
  run.cg_per_step = steps > 0 ? static_cast<double>(cg_iterations) / static_cast<double>(steps) : 0.0;
  run.world = std::move(world);
  return true;
}

// Runs `def` and times it: short runs are repeated (at least 3 times and until 0.2 s of stepping,
// at most 9 times) and the median is kept. The world of the first run is kept for the error.
bool runTimed(const scene::SceneDef& def, double duration, int max_repeats, Run& run, std::string& error)
{
  std::vector<double> times;
  double total = 0.0;
  for (int r = 0; r < max_repeats; ++r)
  {
    Run again;
    double seconds = 0.0;
    if (!runOnce(def, duration, r == 0 ? run : again, seconds, error)) return false;
    times.push_back(seconds);
    total += seconds;
    if (run.status != RunStatus::Stable) break;  // no point in timing a blow-up
    if (r + 1 >= 3 && total >= 0.2) break;
    if (seconds >= 0.5) break;
  }
  std::sort(times.begin(), times.end());
  run.repeats = static_cast<int>(times.size());
  run.wall_per_sim = times[times.size() / 2] / duration;
  return true;
}

// Positions [m] of the free particles of every body, in body then index order.
std::vector<Eigen::Vector3d> freePositions(const core::World& world)
{
  std::vector<Eigen::Vector3d> positions;
  for (const auto& body : world.bodies())
  {
    const auto& p = body->particles();
    for (int i = 0; i < p.size(); ++i)
    {
      if (p.inverse_mass[i] > 0.0) positions.push_back(p.position.col(i));
    }
  }
  return positions;
}

// RMS of |a_i − b_i| [m]; NaN when the counts differ.
double rmsDistance(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b)
{
  if (a.size() != b.size() || a.empty()) return std::numeric_limits<double>::quiet_NaN();
  double sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i)
    sum += (a[i] - b[i]).squaredNorm();
  return std::sqrt(sum / static_cast<double>(a.size()));
}

// ---------------------------------------------------------------------------------------------
// Analytic references.

// The oscillator: one free particle on one undamped spring to a pinned particle, no gravity.
bool oscillatorPositions(const scene::SceneDef& def, double t, std::vector<Eigen::Vector3d>& out, std::string& error)
{
  const auto* net = def.bodies.size() == 1 ? std::get_if<core::SpringNetworkDef>(&def.bodies[0]) : nullptr;
  if (!net || net->positions.size() != 2 || net->springs.size() != 1 || net->pins != std::vector<int>{0} ||
      net->springs[0].damping != 0.0 || def.world.gravity.norm() != 0.0)
  {
    error = "the oscillator must be one network of 2 particles, 1 undamped spring, particle 0 pinned, no gravity";
    return false;
  }
  const core::Spring& spring = net->springs[0];
  const Eigen::Vector3d anchor = net->positions[0];
  const Eigen::Vector3d offset = net->positions[1] - anchor;
  const Eigen::Vector3d d = offset.normalized();
  const Eigen::Vector3d v0 = net->velocities.empty() ? Eigen::Vector3d::Zero() : net->velocities[1];
  if ((v0 - v0.dot(d) * d).norm() > 0.0)
  {
    error = "the oscillator's initial velocity must be along the spring";
    return false;
  }
  const double omega = std::sqrt(spring.stiffness / net->masses[1]);
  const double r = spring.rest_length + (offset.norm() - spring.rest_length) * std::cos(omega * t) +
                   v0.dot(d) / omega * std::sin(omega * t);
  out = {anchor + r * d};
  return true;
}

// A rope hanging straight down from its pinned top particle: spring s from the top carries the
// N − 1 − s particles below it and stretches by (N − 1 − s) m g / k.
bool equilibriumPositions(const scene::SceneDef& def, std::vector<Eigen::Vector3d>& out, std::string& error)
{
  const auto* rope = def.bodies.size() == 1 ? std::get_if<core::RopeDef>(&def.bodies[0]) : nullptr;
  const double g = def.world.gravity.norm();
  if (!rope || rope->pins != std::vector<int>{0} || rope->bend_stiffness != 0.0 || g == 0.0)
  {
    error = "the hanging rope must be one rope pinned at particle 0 only, with no bend springs, under gravity";
    return false;
  }
  const Eigen::Vector3d down = def.world.gravity / g;
  const Eigen::Vector3d along = (rope->end - rope->start).normalized();
  if ((along - down).norm() > 1e-12)
  {
    error = "the hanging rope must start hanging straight down (start above end, along gravity)";
    return false;
  }
  const int n = rope->particles;
  const double total_rest = rope->rest_length > 0.0 ? rope->rest_length : (rope->end - rope->start).norm();
  const double segment = total_rest / (n - 1);
  const double particle_mass = rope->mass / n;
  out.clear();
  Eigen::Vector3d x = rope->start;
  for (int s = 0; s + 1 < n; ++s)
  {
    x += (segment + (n - 1 - s) * particle_mass * g / rope->stretch_stiffness) * down;
    out.push_back(x);  // particle s + 1 (particle 0 is pinned and not counted)
  }
  return true;
}

// Every emitted particle on its ballistic path from its sampled start (the emitter's random
// sequence replayed from its seed), at its age a.
bool ballisticPositions(const core::World& world, std::vector<Eigen::Vector3d>& out, std::string& error)
{
  out.clear();
  const Eigen::Vector3d g = world.environment().gravity;
  for (const auto& body : world.bodies())
  {
    const auto* emitter = dynamic_cast<const core::EmitterBody*>(body.get());
    if (!emitter)
    {
      error = "the emitter scene must hold emitters only";
      return false;
    }
    const auto& p = emitter->particles();
    if (emitter->emittedCount() != p.size() || emitter->droppedCount() != 0)
    {
      error = "emitter '" + body->name() + "' recycled or dropped particles: make lifetime and max_particles larger";
      return false;
    }
    std::mt19937_64 rng(emitter->definition().seed);
    for (int i = 0; i < p.size(); ++i)
    {
      Eigen::Vector3d x0, v0;
      core::EmitterBody::sample(emitter->definition(), rng, x0, v0);
      const double a = p.age[i];
      out.push_back(x0 + v0 * a + 0.5 * a * a * g);
    }
  }
  return true;
}

// ---------------------------------------------------------------------------------------------
// Results.

struct Point
{
  std::string scene, integrator;
  double dt = 0.0;
  long long steps = 0;
  RunStatus status = RunStatus::Stable;
  std::string why;
  double error = std::numeric_limits<double>::quiet_NaN();  // [m]
  double wall_per_sim = 0.0;                                // [s/s]
  int repeats = 0;
  double cg_per_step = 0.0;
};

struct ReferenceInfo
{
  std::string scene, title, kind;
  double duration = 0.0;
  double dt_ref = 0.0;          // [s] the reference's step (FineRk4)
  double check = 0.0;           // [m] RMS difference of the references at dt_ref and dt_ref/2
  double reference_wall = 0.0;  // [s] spent on the references
  int free_particles = 0;
};

struct StabilityPoint
{
  double k_over_m = 0.0;  // [1/s²]
  std::string integrator;
  double dt_max = 0.0;  // [s]
  std::string bound;    // measured | top_of_range | below_range
  double theory = 0.0;  // [s] 0 = none (implicit)
};

std::string fmt(const char* format, double value)
{
  char text[64];
  std::snprintf(text, sizeof(text), format, value);
  return text;
}

// Where the plotted error stops meaning anything: round-off, or the reference's own uncertainty.
double errorFloor(const ReferenceInfo& ref)
{
  return std::max(1e-12, 10.0 * ref.check);
}

// Slope of log(error) against log(dt) over the finest (up to 4) stable points above the floor.
double observedOrder(const std::vector<Point>& points, double floor)
{
  std::vector<std::pair<double, double>> xy;  // (log dt, log error), finest first
  std::vector<const Point*> sorted;
  for (const Point& p : points)
    sorted.push_back(&p);
  std::sort(sorted.begin(), sorted.end(), [](const Point* a, const Point* b) { return a->dt < b->dt; });
  for (const Point* p : sorted)
  {
    if (p->status == RunStatus::Stable && p->error > floor && xy.size() < 4)
      xy.emplace_back(std::log(p->dt), std::log(p->error));
  }
  if (xy.size() < 2) return std::numeric_limits<double>::quiet_NaN();
  double mx = 0, my = 0;
  for (auto& [x, y] : xy)
    mx += x, my += y;
  mx /= xy.size();
  my /= xy.size();
  double sxy = 0, sxx = 0;
  for (auto& [x, y] : xy)
    sxy += (x - mx) * (y - my), sxx += (x - mx) * (x - mx);
  return sxy / sxx;
}

// Cheapest wall time per simulated second at which the integrator's error is at most `target`:
// a measured point, or log-log interpolation between neighbouring steps whose errors straddle it.
double costAtError(const std::vector<Point>& points, double target)
{
  std::vector<const Point*> stable;
  for (const Point& p : points)
  {
    if (p.status == RunStatus::Stable && std::isfinite(p.error)) stable.push_back(&p);
  }
  std::sort(stable.begin(), stable.end(), [](const Point* a, const Point* b) { return a->dt > b->dt; });
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < stable.size(); ++i)
  {
    if (stable[i]->error <= target) best = std::min(best, stable[i]->wall_per_sim);
    if (i + 1 < stable.size())
    {
      const Point& a = *stable[i];
      const Point& b = *stable[i + 1];
      if ((a.error - target) * (b.error - target) < 0.0 && a.error > 0.0 && b.error > 0.0)
      {
        const double s = (std::log(target) - std::log(a.error)) / (std::log(b.error) - std::log(a.error));
        best = std::min(best,
                        std::exp(std::log(a.wall_per_sim) + s * (std::log(b.wall_per_sim) - std::log(a.wall_per_sim))));
      }
    }
  }
  return best;
}

// ---------------------------------------------------------------------------------------------
// Stability map: the oscillator with k from 10 to 1e8 N/m (m = 1 kg), bisection in log dt.

// Stable = 50 periods (at most 5000 steps) stay finite and unfrozen, the largest energy over the
// last quarter of the run is at most twice the largest over the first quarter (no growth), and the
// energy never exceeds 1000 times its start (no fast blow-up that saturates early once the mass
// swings through the anchor). The energy of a bounded symplectic orbit itself swings by up to
// 1/(1 − hω/2) times its start: "within 2x of the start" would call symplectic Euler unstable from
// hω = 1, half its real limit; 1000x costs at most 0.1 % of the limit.
// The body is stepped on its own (not in a World, which refuses steps above kMaxDt = 0.1 s), so the
// search can reach 1 s.
bool stableAt(const scene::SceneDef& def, const std::string& integrator, double dt)
{
  scene::SceneDef with = def;
  setIntegrator(with, integrator);
  const auto& net = std::get<core::SpringNetworkDef>(with.bodies[0]);
  if (!core::validate(net, std::numeric_limits<int>::max())) return false;
  core::SpringNetworkBody oscillator(net);
  core::SpringNetworkBody* body = &oscillator;
  core::Environment env;
  env.gravity = with.world.gravity;
  env.ground.enabled = false;
  const double omega = std::sqrt(net.springs[0].stiffness / net.masses[1]);
  const double period = 2.0 * M_PI / omega;
  const long long steps = std::min<long long>(5000, static_cast<long long>(std::ceil(50.0 * period / dt)));
  const long long quarter = std::max<long long>(1, steps / 4);
  const Eigen::Vector3d g = env.gravity;
  const double start = body->kineticEnergy() + body->potentialEnergy(g);
  double first = 0.0, last = 0.0;
  for (long long k = 1; k <= steps; ++k)
  {
    body->step(dt, env);
    if (body->frozen()) return false;
    const double energy = body->kineticEnergy() + body->potentialEnergy(g);
    if (!(energy <= 1000.0 * start)) return false;
    if (k <= quarter) first = std::max(first, energy);
    if (k > steps - quarter) last = std::max(last, energy);
  }
  return last <= 2.0 * first;
}

std::vector<StabilityPoint> stabilityMap(const scene::SceneDef& oscillator, const std::vector<std::string>& integrators,
                                         bool quick)
{
  std::vector<StabilityPoint> points;
  const double lo = 1e-7, hi = 1.0;  // [s] search range
  const int per_decade = quick ? 1 : 2;
  for (int e = 0; e <= 7 * per_decade; ++e)
  {
    const double k = 10.0 * std::pow(10.0, static_cast<double>(e) / per_decade);  // [N/m], m = 1 kg
    scene::SceneDef def = oscillator;
    auto& net = std::get<core::SpringNetworkDef>(def.bodies[0]);
    net.masses = {1.0, 1.0};
    net.springs[0].stiffness = k;
    // A small amplitude (0.1 % of the rest length), so that even a bounded orbit near the limit,
    // whose amplitude grows as 1/sqrt(1 − hω/2), never passes through the anchor.
    net.positions[1] = net.positions[0] + (1.001 * net.springs[0].rest_length) * Eigen::Vector3d::UnitX();
    net.velocities.clear();
    const double omega = std::sqrt(k);
    for (const std::string& name : integrators)
    {
      StabilityPoint point{k, name, 0.0, "measured", 0.0};
      // The limit h·ω the method declares (none for implicit methods and `auto`).
      core::IntegratorType type = core::kAutoIntegrator;
      core::parseIntegratorType(name, type);
      if (std::isfinite(core::stabilityLimit(type))) point.theory = core::stabilityLimit(type) / omega;
      if (stableAt(def, name, hi))
      {
        point.dt_max = hi;
        point.bound = "top_of_range";
      }
      else if (!stableAt(def, name, lo))
      {
        point.dt_max = lo;
        point.bound = "below_range";
      }
      else
      {
        double a = std::log(lo), b = std::log(hi);  // stable at a, unstable at b
        for (int it = 0; it < (quick ? 12 : 24); ++it)
        {
          const double mid = 0.5 * (a + b);
          (stableAt(def, name, std::exp(mid)) ? a : b) = mid;
        }
        point.dt_max = std::exp(a);
      }
      points.push_back(point);
    }
    std::fprintf(stderr, "[bench] stability k/m = %.3g 1/s^2:", k);
    for (std::size_t i = points.size() - integrators.size(); i < points.size(); ++i)
      std::fprintf(stderr, " %s %.4g s%s", points[i].integrator.c_str(), points[i].dt_max,
                   points[i].bound == "top_of_range" ? " (top of range)" : "");
    std::fprintf(stderr, "\n");
  }
  return points;
}

// ---------------------------------------------------------------------------------------------
// Reports.

std::string machineLine()
{
  std::string cpu = "unknown CPU";
  std::ifstream info("/proc/cpuinfo");
  for (std::string line; std::getline(info, line);)
  {
    if (line.rfind("model name", 0) == 0)
    {
      cpu = line.substr(line.find(':') + 2);
      break;
    }
  }
  std::ostringstream out;
  out << cpu << ", " << std::max(1L, sysconf(_SC_NPROCESSORS_ONLN)) << " logical CPUs; g++ " << __VERSION__
#ifdef __OPTIMIZE__
      << ", optimised build"
#else
      << ", UNOPTIMISED build"
#endif
      << "; one thread";
  return out.str();
}

bool writeCsvs(const std::string& dir, const std::vector<Point>& points, const std::vector<ReferenceInfo>& refs,
               const std::vector<StabilityPoint>& stability, bool with_stability)
{
  std::ofstream wp(dir + "/work_precision.csv");
  std::ofstream rf(dir + "/references.csv");
  if (!wp || !rf)
  {
    std::cerr << "particle_sim_bench: cannot write CSV files into '" << dir << "'\n";
    return false;
  }
  wp << "scene,integrator,dt_s,steps,status,rms_error_m,wall_s_per_sim_s,repeats,cg_iterations_per_step\n";
  char line[512];
  for (const Point& p : points)
  {
    std::snprintf(line, sizeof(line), "%s,%s,%.9g,%lld,%s,%.6e,%.6e,%d,%.2f\n", p.scene.c_str(), p.integrator.c_str(),
                  p.dt, p.steps, toString(p.status), p.error, p.wall_per_sim, p.repeats, p.cg_per_step);
    wp << line;
  }
  // reference_dt_s: the step of the reference (0 = analytic); check_dt_s: twice that, the step of
  // the run it is checked against; reference_check_m: their RMS difference.
  rf << "scene,title,reference,duration_s,free_particles,reference_dt_s,check_dt_s,reference_check_m,"
        "reference_wall_s\n";
  for (const ReferenceInfo& r : refs)
  {
    std::snprintf(line, sizeof(line), "%s,%s,%s,%.9g,%d,%.9g,%.9g,%.6e,%.3f\n", r.scene.c_str(), r.title.c_str(),
                  r.kind.c_str(), r.duration, r.free_particles, r.dt_ref / 2, r.dt_ref, r.check, r.reference_wall);
    rf << line;
  }
  if (with_stability)
  {
    std::ofstream st(dir + "/stability.csv");
    if (!st)
    {
      std::cerr << "particle_sim_bench: cannot write '" << dir << "/stability.csv'\n";
      return false;
    }
    st << "k_over_m_per_s2,omega_rad_per_s,integrator,max_stable_dt_s,bound,theory_dt_s\n";
    // Grouped by integrator (then k), so that a plot can draw each integrator as one line.
    std::vector<StabilityPoint> sorted = stability;
    std::stable_sort(sorted.begin(), sorted.end(), [&](const StabilityPoint& a, const StabilityPoint& b) {
      auto rank = [&](const std::string& name) {
        for (std::size_t i = 0; i < stability.size(); ++i)
        {
          if (stability[i].integrator == name) return i;
        }
        return stability.size();
      };
      return rank(a.integrator) < rank(b.integrator);
    });
    for (const StabilityPoint& s : sorted)
    {
      std::snprintf(line, sizeof(line), "%.9g,%.9g,%s,%.9g,%s,%.9g\n", s.k_over_m, std::sqrt(s.k_over_m),
                    s.integrator.c_str(), s.dt_max, s.bound.c_str(), s.theory);
      st << line;
    }
  }
  return true;
}

std::vector<Point> pointsOf(const std::vector<Point>& points, const std::string& scene, const std::string& integrator)
{
  std::vector<Point> out;
  for (const Point& p : points)
  {
    if (p.scene == scene && p.integrator == integrator) out.push_back(p);
  }
  return out;
}

std::string markdownTables(const std::vector<Case>& cases, const std::vector<std::string>& integrators,
                           const std::vector<Point>& points, const std::vector<ReferenceInfo>& refs,
                           const std::vector<StabilityPoint>& stability, double bench_seconds)
{
  std::ostringstream md;
  char date[64];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof(date), "%Y-%m-%d", std::localtime(&now));
  md << "Measured on " << date << ": " << machineLine() << ". The whole bench took " << fmt("%.0f", bench_seconds)
     << " s.\n\n";

  // Work-precision tables, one per scene.
  md << "### Error and cost per scene\n\n"
        "Each cell: RMS position error over the free particles at the final time [m] / wall time per simulated "
        "second [s/s] (median of up to 9 runs when a run is short); implicit solvers also give their mean CG "
        "iterations per step. `unstable`: a body froze (non-finite state); `diverged`: it flew away.\n\n";
  for (const Case& c : cases)
  {
    const ReferenceInfo* ref = nullptr;
    for (const ReferenceInfo& r : refs)
    {
      if (r.scene == c.name) ref = &r;
    }
    if (!ref) continue;
    const std::vector<std::string> names =
        c.reference == ReferenceKind::Ballistic ? std::vector<std::string>{"ballistic"} : integrators;
    md << "#### " << c.title << " (`bench/" << c.name << ".yaml`)\n\n";
    md << "T = " << fmt("%g", c.duration) << " s, " << ref->free_particles << " free particles; reference: ";
    if (c.reference == ReferenceKind::FineRk4)
      md << "RK4 at dt = " << fmt("%.3g", c.dt_ref / 2) << " s; it differs from RK4 at " << fmt("%.3g", c.dt_ref)
         << " s by **" << fmt("%.2e", ref->check) << " m** (RMS), so errors below " << fmt("%.1e", errorFloor(*ref))
         << " m are not resolved.\n\n";
    else
      md << ref->kind << ".\n\n";
    md << "| dt [s] |";
    for (const std::string& name : names)
      md << " " << name << " |";
    md << "\n|---|";
    for (std::size_t i = 0; i < names.size(); ++i)
      md << "---|";
    md << "\n";
    for (double dt : c.dts)
    {
      md << "| " << fmt("%.4g", dt) << " |";
      for (const std::string& name : names)
      {
        std::string cell = "—";
        for (const Point& p : pointsOf(points, c.name, name))
        {
          if (p.dt != dt) continue;
          if (p.status != RunStatus::Stable)
            cell = toString(p.status);
          else
          {
            cell = fmt("%.2e", p.error) + " / " + fmt("%.2e", p.wall_per_sim);
            if (p.cg_per_step > 0.0) cell += " (" + fmt("%.1f", p.cg_per_step) + " CG)";
          }
        }
        md << " " << cell << " |";
      }
      md << "\n";
    }
    md << "\n";
  }

  // Orders.
  md << "### Observed orders\n\n"
        "Slope of log(error) against log(dt) over the finest (up to four) stable steps whose error is above the "
        "floor (10 times the reference check, and 1e-12 m). Expected, as each method declares:";
  for (const core::IntegratorInfo& info : core::integratorRegistry())
    md << (&info == &core::integratorRegistry().front() ? " " : ", ") << info.name << " " << info.order
       << (info.type == core::kVerletIntegrator ? " (1 with damped springs)" : "");
  md << "; contacts make every method first order at best. `auto` switches method with the step, so it has no "
        "single order.\n\n| scene |";
  for (const std::string& name : integrators)
    md << " " << name << " |";
  md << "\n|---|";
  for (std::size_t i = 0; i < integrators.size(); ++i)
    md << "---|";
  md << "\n";
  for (const Case& c : cases)
  {
    if (c.reference == ReferenceKind::Ballistic || c.reference == ReferenceKind::Equilibrium) continue;
    const ReferenceInfo* ref = nullptr;
    for (const ReferenceInfo& r : refs)
    {
      if (r.scene == c.name) ref = &r;
    }
    if (!ref) continue;
    md << "| " << c.name << " |";
    for (const std::string& name : integrators)
    {
      if (name == "auto")
      {
        md << " (mixed) |";
        continue;
      }
      const double order = observedOrder(pointsOf(points, c.name, name), errorFloor(*ref));
      md << " " << (std::isfinite(order) ? fmt("%.2f", order) : std::string("—")) << " |";
    }
    md << "\n";
  }
  md << "\n";

  // Cost at equal error.
  const bool has_auto = std::find(integrators.begin(), integrators.end(), "auto") != integrators.end();
  md << "### Cost at equal error\n\n"
        "Wall time per simulated second [s/s] each integrator needs to reach an RMS error of at most 1 mm and "
        "10 µm (a measured step, or log-log interpolation between neighbouring steps); `—`: not reached in the "
        "sweep. Bold: the cheapest.";
  if (has_auto) md << " Last column: auto's cost over implicit Euler's (below 1: auto is cheaper).";
  md << "\n\n| scene | error ≤ [m] |";
  for (const std::string& name : integrators)
    md << " " << name << " |";
  if (has_auto) md << " auto / implicit_euler |";
  md << "\n|---|---|";
  for (std::size_t i = 0; i < integrators.size() + (has_auto ? 1 : 0); ++i)
    md << "---|";
  md << "\n";
  for (const Case& c : cases)
  {
    if (c.reference == ReferenceKind::Ballistic) continue;
    for (double target : {1e-3, 1e-5})
    {
      std::vector<double> costs;
      for (const std::string& name : integrators)
        costs.push_back(costAtError(pointsOf(points, c.name, name), target));
      const double best = *std::min_element(costs.begin(), costs.end());
      md << "| " << c.name << " | " << fmt("%.0e", target) << " |";
      for (double cost : costs)
      {
        if (!std::isfinite(cost))
          md << " — |";
        else if (cost == best)
          md << " **" << fmt("%.2e", cost) << "** |";
        else
          md << " " << fmt("%.2e", cost) << " |";
      }
      if (has_auto)
      {
        const double a = costs[std::find(integrators.begin(), integrators.end(), "auto") - integrators.begin()];
        const double ie =
            costs[std::find(integrators.begin(), integrators.end(), "implicit_euler") - integrators.begin()];
        md << " " << (std::isfinite(a) && std::isfinite(ie) ? fmt("%.2f", a / ie) : std::string("—")) << " |";
      }
      md << "\n";
    }
  }
  md << "\n";

  // References.
  md << "### References\n\n| scene | reference | T [s] | reference dt [s] | check: RMS difference from the reference "
        "at twice its step [m] | smallest error plotted [m] |\n|---|---|---|---|---|---|\n";
  for (const ReferenceInfo& r : refs)
  {
    double smallest = std::numeric_limits<double>::infinity();
    for (const Point& p : points)
    {
      if (p.scene == r.scene && p.status == RunStatus::Stable && p.error > 0.0) smallest = std::min(smallest, p.error);
    }
    md << "| " << r.scene << " | " << r.kind << " | " << fmt("%g", r.duration) << " | "
       << (r.dt_ref > 0.0 ? fmt("%.3g", r.dt_ref / 2) : std::string("—")) << " | "
       << (r.dt_ref > 0.0 ? fmt("%.2e", r.check) : std::string("— (exact)")) << " | "
       << (std::isfinite(smallest) ? fmt("%.2e", smallest) : std::string("—")) << " |\n";
  }
  md << "\n";

  // Stability map.
  if (!stability.empty())
  {
    md << "### Stability map\n\n"
          "Largest stable dt [s] of a 1 kg mass on an undamped spring (other end pinned) against k/m, found by "
          "bisection in log(dt) over [1e-7, 1] s; in brackets, measured over theory (2/ω for symplectic Euler and "
          "Verlet, 2√2/ω for RK4). `≥ 1`: stable at the top of the range.\n\n| k/m [1/s²] | ω [rad/s] | 2/ω [s] | "
          "2√2/ω [s] |";
    for (const std::string& name : integrators)
      md << " " << name << " |";
    md << "\n|---|---|---|---|";
    for (std::size_t i = 0; i < integrators.size(); ++i)
      md << "---|";
    md << "\n";
    for (std::size_t i = 0; i < stability.size(); i += integrators.size())
    {
      const double omega = std::sqrt(stability[i].k_over_m);
      md << "| " << fmt("%.3g", stability[i].k_over_m) << " | " << fmt("%.4g", omega) << " | "
         << fmt("%.4g", 2.0 / omega) << " | " << fmt("%.4g", 2.0 * std::sqrt(2.0) / omega) << " |";
      for (std::size_t j = 0; j < integrators.size() && i + j < stability.size(); ++j)
      {
        const StabilityPoint& s = stability[i + j];
        if (s.bound == "top_of_range")
          md << " ≥ 1 |";
        else if (s.bound == "below_range")
          md << " < 1e-7 |";
        else
        {
          md << " " << fmt("%.4g", s.dt_max);
          if (s.theory > 0.0) md << " (" << fmt("%.3f", s.dt_max / s.theory) << ")";
          md << " |";
        }
      }
      md << "\n";
    }
    md << "\n";
  }
  return md.str();
}

namespace fs = std::filesystem;

/// The package's config/scenes/bench, looked for in this order: the install space this executable
/// lies in (<prefix>/lib/particle_sim/ -> <prefix>/share/particle_sim/), the source folder it was
/// built from, then every particle_sim package on ROS_PACKAGE_PATH. Empty when none has it; `tried`
/// lists the folders looked at.
std::string findBenchScenes(std::vector<std::string>& tried)
{
  const fs::path relative = fs::path("config") / "scenes" / "bench";
  std::vector<fs::path> candidates;
  std::error_code error;
  const fs::path executable = fs::read_symlink("/proc/self/exe", error);
  if (!error) candidates.push_back(executable.parent_path() / ".." / ".." / "share" / "particle_sim" / relative);
#ifdef PARTICLE_SIM_SOURCE_DIR
  candidates.push_back(fs::path(PARTICLE_SIM_SOURCE_DIR) / relative);
#endif
  if (const char* package_path = std::getenv("ROS_PACKAGE_PATH"))
  {
    std::stringstream entries(package_path);
    for (std::string entry; std::getline(entries, entry, ':');)
    {
      if (entry.empty()) continue;
      // An entry is a package folder itself, or a folder holding packages.
      if (fs::path(entry).filename() == "particle_sim" || fs::exists(fs::path(entry) / "package.xml", error))
        candidates.push_back(fs::path(entry) / relative);
      candidates.push_back(fs::path(entry) / "particle_sim" / relative);
    }
  }
  for (const fs::path& candidate : candidates)
  {
    tried.push_back(candidate.lexically_normal().string());
    if (fs::is_regular_file(candidate / "oscillator.yaml", error)) return candidate.lexically_normal().string();
  }
  return {};
}

bool splitList(const std::string& text, std::vector<std::string>& out)
{
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');)
  {
    if (!item.empty()) out.push_back(item);
  }
  return !out.empty();
}

}  // namespace

int main(int argc, char** argv)
{
  particle_sim::process::restartWithHugePagesIfAdvised(argv);
  std::string scenes_dir, out_dir = "bench_results", tables_path;
  std::vector<std::string> only;
  bool with_stability = true, quick = false;
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    auto next = [&](std::string& out) {
      if (i + 1 >= argc) return false;
      out = argv[++i];
      return !out.empty();
    };
    std::string value;
    if (arg == "--help" || arg == "-h")
    {
      std::cout << kUsage;
      return 0;
    }
    else if (arg == "--scenes" && next(value))
      scenes_dir = value;
    else if (arg == "--out" && next(value))
      out_dir = value;
    else if (arg == "--tables" && next(value))
      tables_path = value;
    else if (arg == "--only" && next(value) && splitList(value, only))
      continue;
    else if (arg == "--no-stability")
      with_stability = false;
    else if (arg == "--quick")
      quick = true;
    else
    {
      std::cerr << "particle_sim_bench: bad argument '" << arg << "'\n" << kUsage;
      return 2;
    }
  }

  if (scenes_dir.empty())
  {
    std::vector<std::string> tried;
    scenes_dir = findBenchScenes(tried);
    if (scenes_dir.empty())
    {
      std::cerr
          << "particle_sim_bench: cannot find the bench scenes (config/scenes/bench of particle_sim); looked in\n";
      for (const std::string& folder : tried)
        std::cerr << "  " << folder << "\n";
      std::cerr << "give them with --scenes DIR\n";
      return 1;
    }
  }
  // The output folder (and the tables file's folder) exist before hours of work, not after.
  std::error_code error;
  fs::create_directories(out_dir, error);
  if (error || !fs::is_directory(out_dir))
  {
    std::cerr << "particle_sim_bench: cannot create the output folder '" << out_dir << "'"
              << (error ? ": " + error.message() : std::string()) << "\n";
    return 1;
  }
  if (const fs::path tables_folder = fs::path(tables_path).parent_path(); !tables_folder.empty())
  {
    fs::create_directories(tables_folder, error);
    if (error)
    {
      std::cerr << "particle_sim_bench: cannot create '" << tables_folder.string() << "': " << error.message() << "\n";
      return 1;
    }
  }
  std::fprintf(stderr, "[bench] scenes from %s, CSV into %s\n", scenes_dir.c_str(), out_dir.c_str());

  const auto bench_start = Clock::now();
  const std::vector<std::string> integrators = integratorNames();
  std::vector<Case> cases = benchCases(quick);
  if (!only.empty())
  {
    for (const std::string& name : only)
    {
      if (std::none_of(cases.begin(), cases.end(), [&](const Case& c) { return c.name == name; }))
      {
        std::cerr << "particle_sim_bench: no bench scene '" << name << "'\n";
        return 2;
      }
    }
    cases.erase(
        std::remove_if(cases.begin(), cases.end(),
                       [&](const Case& c) { return std::find(only.begin(), only.end(), c.name) == only.end(); }),
        cases.end());
  }
  const int max_repeats = quick ? 1 : 9;
  std::fprintf(stderr, "[bench] integrators:");
  for (const std::string& name : integrators)
    std::fprintf(stderr, " %s", name.c_str());
  std::fprintf(stderr, "\n");

  std::vector<Point> points;
  std::vector<ReferenceInfo> refs;
  for (const Case& c : cases)
  {
    scene::SceneDef def;
    if (auto status = scene::loadSceneFile(scenes_dir + "/" + c.name + ".yaml", def); !status)
    {
      std::cerr << "particle_sim_bench: " << status.message << "\n";
      return 1;
    }
    const auto case_start = Clock::now();
    ReferenceInfo ref{c.name, c.title, describe(c.reference), c.duration, c.dt_ref};
    std::string error;

    // The reference: analytic, or RK4 at dt_ref / 2 checked against RK4 at dt_ref.
    std::vector<Eigen::Vector3d> reference;
    if (c.reference == ReferenceKind::Oscillator && !oscillatorPositions(def, c.duration, reference, error))
      std::cerr << "particle_sim_bench: " << c.name << ": " << error << "\n";
    if (c.reference == ReferenceKind::Equilibrium && !equilibriumPositions(def, reference, error))
      std::cerr << "particle_sim_bench: " << c.name << ": " << error << "\n";
    if (!error.empty()) return 1;
    if (c.reference == ReferenceKind::FineRk4)
    {
      std::vector<Eigen::Vector3d> coarse;
      for (double dt : {c.dt_ref / 2, c.dt_ref})
      {
        scene::SceneDef fine = def;
        fine.world.dt = dt;
        setIntegrator(fine, "rk4");
        Run run;
        double seconds = 0.0;
        if (!runOnce(fine, c.duration, run, seconds, error))
        {
          std::cerr << "particle_sim_bench: " << c.name << ": " << error << "\n";
          return 1;
        }
        if (run.status != RunStatus::Stable)
        {
          std::cerr << "particle_sim_bench: " << c.name << ": the RK4 reference at dt = " << dt
                    << " s is not stable: " << run.why << "\n";
          return 1;
        }
        ref.reference_wall += seconds;
        (dt < c.dt_ref ? reference : coarse) = freePositions(*run.world);
      }
      ref.check = rmsDistance(reference, coarse);
      std::fprintf(stderr, "[bench] %s: reference rk4 dt %.3g s, check against dt %.3g s: %.2e m (%.1f s)\n",
                   c.name.c_str(), c.dt_ref / 2, c.dt_ref, ref.check, ref.reference_wall);
    }

    const std::vector<std::string> names =
        c.reference == ReferenceKind::Ballistic ? std::vector<std::string>{"ballistic"} : integrators;
    for (const std::string& name : names)
    {
      for (double dt : c.dts)
      {
        scene::SceneDef run_def = def;
        run_def.world.dt = dt;
        setIntegrator(run_def, name);
        Run run;
        if (!runTimed(run_def, c.duration, max_repeats, run, error))
        {
          std::cerr << "particle_sim_bench: " << c.name << ": " << error << "\n";
          return 1;
        }
        Point point{c.name, name, dt, std::llround(c.duration / dt), run.status, run.why};
        point.wall_per_sim = run.wall_per_sim;
        point.repeats = run.repeats;
        point.cg_per_step = run.cg_per_step;
        if (run.status == RunStatus::Stable)
        {
          if (c.reference == ReferenceKind::Ballistic && !ballisticPositions(*run.world, reference, error))
          {
            std::cerr << "particle_sim_bench: " << c.name << ": " << error << "\n";
            return 1;
          }
          const std::vector<Eigen::Vector3d> positions = freePositions(*run.world);
          ref.free_particles = static_cast<int>(positions.size());
          point.error = rmsDistance(positions, reference);
          if (!(point.error <= kDivergedError))
          {
            point.status = RunStatus::Diverged;
            point.why = "error " + fmt("%.3g", point.error) + " m";
          }
        }
        if (point.status == RunStatus::Stable)
          std::fprintf(stderr, "[bench] %s %-16s dt %-9.4g s: error %.2e m, %.2e s per sim s (%d runs)\n",
                       c.name.c_str(), name.c_str(), dt, point.error, point.wall_per_sim, point.repeats);
        else
          std::fprintf(stderr, "[bench] %s %-16s dt %-9.4g s: %s (%s)\n", c.name.c_str(), name.c_str(), dt,
                       toString(point.status), point.why.c_str());
        points.push_back(point);
      }
    }
    refs.push_back(ref);
    std::fprintf(stderr, "[bench] %s done in %.1f s (%.0f s so far)\n", c.name.c_str(),
                 std::chrono::duration<double>(Clock::now() - case_start).count(),
                 std::chrono::duration<double>(Clock::now() - bench_start).count());
  }

  std::vector<StabilityPoint> stability;
  if (with_stability)
  {
    scene::SceneDef oscillator;
    if (auto status = scene::loadSceneFile(scenes_dir + "/oscillator.yaml", oscillator); !status)
    {
      std::cerr << "particle_sim_bench: " << status.message << "\n";
      return 1;
    }
    std::string error;
    std::vector<Eigen::Vector3d> unused;
    if (!oscillatorPositions(oscillator, 0.0, unused, error))
    {
      std::cerr << "particle_sim_bench: oscillator: " << error << "\n";
      return 1;
    }
    const auto start = Clock::now();
    stability = stabilityMap(oscillator, integrators, quick);
    std::fprintf(stderr, "[bench] stability map done in %.1f s\n",
                 std::chrono::duration<double>(Clock::now() - start).count());
  }

  if (!writeCsvs(out_dir, points, refs, stability, with_stability)) return 1;
  const double bench_seconds = std::chrono::duration<double>(Clock::now() - bench_start).count();
  if (!tables_path.empty())
  {
    std::ofstream tables(tables_path);
    if (!tables)
    {
      std::cerr << "particle_sim_bench: cannot write '" << tables_path << "'\n";
      return 1;
    }
    tables << markdownTables(cases, integrators, points, refs, stability, bench_seconds);
  }
  std::printf("particle_sim_bench: %zu runs over %zu scenes in %.0f s; CSV in %s\n", points.size(), cases.size(),
              bench_seconds, out_dir.c_str());
  return 0;
}
