// particle_sim_run: runs a scene with no ROS master and writes particle states as CSV.
//
//   particle_sim_run SCENE.yaml --duration T [--dt DT] [--integrator NAME] [--threads N] [--output states.csv] [--every
//   N]
//                    [--pin-forces forces.csv]

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "particle_sim/core/limits.h"
#include "particle_sim/process/huge_pages.h"
#include "particle_sim/scene/scene.h"

namespace
{
// The integrators are the core's (integratorTypeNames()): one added there is listed here.
const std::string kUsage =
    std::string(
        "usage: particle_sim_run SCENE.yaml --duration T [--dt DT] [--integrator NAME] [--threads N] "
        "[--output states.csv] [--every N] [--pin-forces forces.csv]\n"
        "  SCENE.yaml       scene file (see README, 'Scene files')\n"
        "  --duration T     sim time to run [s], > 0; duration / dt must give 1 to 2^64 - 1 steps\n"
        "  --dt DT          physics step [s], overrides the scene's world.dt, in (0, 0.1]\n"
        "  --integrator NAME  integrator of every spring body (rope, spring network, cloth, jelly):\n"
        "                   ") +
    particle_sim::core::integratorTypeNames() +
    "\n"
    "  --threads N      threads of the step, overrides the scene's world.threads, in [0, 256]; 0 = one\n"
    "                   per core (the results are the same bits at any count)\n"
    "  --output FILE    write time,body,index,x,y,z,vx,vy,vz rows for every live particle\n"
    "  --every N        write every N-th step (default 1); the initial state is always written\n"
    "  --pin-forces FILE  write time,body,pinned,fx,fy,fz,tx,ty,tz rows: per spring body with pins, the\n"
    "                   sum of the pins' reactions [N] and its torque about the origin [N m], at the\n"
    "                   steps --output writes (every N-th)\n";

int usageError(const std::string& message)
{
  std::cerr << "particle_sim_run: " << message << "\n" << kUsage;
  return 2;
}

bool parseNumber(const std::string& text, double& value)
{
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size() && std::isfinite(value);
}

// Per spring body with pins: the sum of the pins' reactions and its torque about the origin.
void writePinForces(std::ostream& out, const particle_sim::core::World& world)
{
  char line[320];
  for (const auto& body : world.bodies())
  {
    const auto* spring_body = dynamic_cast<const particle_sim::core::SpringNetworkBody*>(body.get());
    if (spring_body == nullptr || spring_body->pinnedCount() == 0) continue;
    const auto load = spring_body->pinLoad({}, Eigen::Vector3d::Zero());
    std::snprintf(line, sizeof(line), "%.9g,%s,%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", world.simTime(),
                  body->name().c_str(), spring_body->pinnedCount(), load.force.x(), load.force.y(), load.force.z(),
                  load.torque.x(), load.torque.y(), load.torque.z());
    out << line;
  }
}

void writeStates(std::ostream& out, const particle_sim::core::World& world)
{
  char line[320];
  for (const auto& body : world.bodies())
  {
    const auto& p = body->particles();
    for (int i = 0; i < p.size(); ++i)
    {
      const auto x = p.position.col(i);
      const auto v = p.velocity.col(i);
      std::snprintf(line, sizeof(line), "%.9g,%s,%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", world.simTime(),
                    body->name().c_str(), i, x.x(), x.y(), x.z(), v.x(), v.y(), v.z());
      out << line;
    }
  }
}
}  // namespace

int main(int argc, char** argv)
{
  particle_sim::process::restartWithHugePagesIfAdvised(argv);
  std::string scene_path, output_path, integrator_name, pin_forces_path;
  double duration = -1.0, dt = 0.0, every = 1.0, threads = -1.0;  // threads < 0: the scene's
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    auto value = [&](double& out) {
      if (i + 1 >= argc) return false;
      return parseNumber(argv[++i], out);
    };
    if (arg == "--help" || arg == "-h")
    {
      std::cout << kUsage;
      return 0;
    }
    else if (arg == "--duration")
    {
      if (!value(duration) || duration <= 0.0) return usageError("--duration needs a number of seconds > 0");
    }
    else if (arg == "--dt")
    {
      if (!value(dt) || dt <= 0.0 || dt > particle_sim::core::kMaxDt)
        return usageError("--dt needs a step in (0, 0.1] seconds");
    }
    else if (arg == "--every")
    {
      if (!value(every) || every < 1.0 || every != std::floor(every))
        return usageError("--every needs an integer >= 1");
    }
    else if (arg == "--integrator")
    {
      particle_sim::core::IntegratorType type;
      if (i + 1 >= argc || !particle_sim::core::parseIntegratorType(argv[i + 1], type))
        return usageError(std::string("--integrator needs one of: ") + particle_sim::core::integratorTypeNames());
      integrator_name = argv[++i];
    }
    else if (arg == "--threads")
    {
      if (!value(threads) || threads < particle_sim::core::limits::kThreads.min ||
          threads > particle_sim::core::limits::kThreads.max || threads != std::floor(threads))
        return usageError("--threads needs an integer in [0, 256] (0 = one per core)");
    }
    else if (arg == "--pin-forces")
    {
      if (i + 1 >= argc) return usageError("--pin-forces needs a file name");
      pin_forces_path = argv[++i];
    }
    else if (arg == "--output")
    {
      if (i + 1 >= argc) return usageError("--output needs a file name");
      output_path = argv[++i];
    }
    else if (!arg.empty() && arg[0] == '-')
      return usageError("unknown option '" + arg + "'");
    else if (scene_path.empty())
      scene_path = arg;
    else
      return usageError("only one scene file may be given (got '" + scene_path + "' and '" + arg + "')");
  }
  if (scene_path.empty()) return usageError("no scene file given");
  if (duration <= 0.0) return usageError("--duration is required");

  particle_sim::scene::SceneDef scene;
  if (auto status = particle_sim::scene::loadSceneFile(scene_path, scene); !status)
  {
    std::cerr << "particle_sim_run: " << status.message << "\n";
    return 1;
  }
  if (dt > 0.0) scene.world.dt = dt;
  if (threads >= 0.0) scene.world.threads = static_cast<int>(threads);
  if (!integrator_name.empty())
  {
    particle_sim::core::IntegratorType type;
    particle_sim::core::parseIntegratorType(integrator_name, type);
    // The world's default and every spring body: ropes, spring networks, grid and mesh cloth, jelly.
    particle_sim::scene::editIntegrators(scene, [type](particle_sim::core::IntegratorDef& def) { def.type = type; });
  }
  std::unique_ptr<particle_sim::core::World> world;
  if (auto status = particle_sim::scene::buildWorld(scene, world); !status)
  {
    std::cerr << "particle_sim_run: " << status.message << "\n";
    return 1;
  }

  // Step until the duration is covered: at least one step, and a count that fits in 64 bits.
  const double step_count = std::max(0.0, std::ceil(duration / world->dt() - 1e-9));  // never -0
  constexpr double kTwoTo64 = 18446744073709551616.0;
  char figures[160];
  std::snprintf(figures, sizeof(figures), "--duration %g s with dt = %g s gives %g steps", duration, world->dt(),
                step_count);
  if (!(step_count >= 1.0))
    return usageError(std::string(figures) + ": at least 1 is needed (a longer duration or a smaller dt)");
  if (!(step_count < kTwoTo64))
    return usageError(std::string(figures) + ": more than fit in 64 bits (at most 18446744073709551615)");
  const auto steps = static_cast<std::uint64_t>(step_count);
  std::ofstream output;
  if (!output_path.empty())
  {
    output.open(output_path);
    if (!output)
    {
      std::cerr << "particle_sim_run: cannot write '" << output_path << "'\n";
      return 1;
    }
    output << "time,body,index,x,y,z,vx,vy,vz\n";
    writeStates(output, *world);
  }
  std::ofstream pin_forces;
  if (!pin_forces_path.empty())
  {
    pin_forces.open(pin_forces_path);
    if (!pin_forces)
    {
      std::cerr << "particle_sim_run: cannot write '" << pin_forces_path << "'\n";
      return 1;
    }
    pin_forces << "time,body,pinned,fx,fy,fz,tx,ty,tz\n";
  }

  // Report progress on stderr every second of wall time.
  const auto write_every = static_cast<std::uint64_t>(every);
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto last_progress = start;
  double stepping_seconds = 0.0;

  // Per spring body, the methods that ran (its own, or what `auto` picked step by step), each with
  // its step count and the CG iterations and residuals of its implicit solves.
  struct MethodStats
  {
    particle_sim::core::IntegratorType method;
    long long steps = 0;
    long long iterations = 0;
    int max_iterations = 0;
    double worst_residual = 0.0;
    double worst_velocity_error = 0.0;  // [m/s]
    long long unconverged = 0;
    long long direct = 0;     // steps whose last solve was direct
    long long multigrid = 0;  // steps whose last solve was preconditioned by the multigrid
  };
  // A body that enables self_collision also sums the counts of its collision passes (and the world
  // those of the passes and impact zones), over the run.
  struct CollisionTotals
  {
    long long proximity_pairs = 0;
    long long collisions = 0;
    long long impact_zone_particles = 0;
  };
  struct BodyStats
  {
    const particle_sim::core::SpringNetworkBody* body;
    std::size_t index;                 // in world->bodies() and lastCollisions().bodies
    std::vector<MethodStats> methods;  // in the order they first ran
    CollisionTotals collisions;
  };
  std::vector<BodyStats> body_stats;
  bool any_self_collision = false;
  for (std::size_t i = 0; i < world->bodies().size(); ++i)
  {
    if (const auto* spring_body = dynamic_cast<const particle_sim::core::SpringNetworkBody*>(world->bodies()[i].get()))
    {
      body_stats.push_back({spring_body, i, {}, {}});
      any_self_collision = any_self_collision || spring_body->definition().self_collision.enabled;
    }
  }
  long long collision_passes = 0, impact_zones = 0;

  for (std::uint64_t k = 1; k <= steps; ++k)
  {
    const auto before = Clock::now();
    particle_sim::scene::stepScene(scene, *world);
    const auto after = Clock::now();
    stepping_seconds += std::chrono::duration<double>(after - before).count();
    for (BodyStats& stats : body_stats)
    {
      const particle_sim::core::IntegratorType ran = stats.body->lastIntegrator();
      auto method = std::find_if(stats.methods.begin(), stats.methods.end(),
                                 [&](const MethodStats& m) { return m.method == ran; });
      if (method == stats.methods.end()) method = stats.methods.insert(stats.methods.end(), MethodStats{ran});
      const auto& report = stats.body->lastSolve();
      ++method->steps;
      method->iterations += report.iterations;
      method->max_iterations = std::max(method->max_iterations, report.iterations);
      method->worst_residual = std::max(method->worst_residual, report.relative_residual);
      method->worst_velocity_error = std::max(method->worst_velocity_error, report.velocity_error);
      method->unconverged += report.converged ? 0 : 1;
      method->direct += report.direct ? 1 : 0;
      method->multigrid += report.multigrid ? 1 : 0;
    }
    if (any_self_collision)
    {
      const particle_sim::core::CollisionReport& report = world->lastCollisions();
      collision_passes += report.passes;
      impact_zones += report.impact_zones;
      for (BodyStats& stats : body_stats)
      {
        if (stats.index >= report.bodies.size()) continue;
        const particle_sim::core::CollisionCounts& counts = report.bodies[stats.index];
        stats.collisions.proximity_pairs += counts.proximity_pairs;
        stats.collisions.collisions += counts.collisions;
        stats.collisions.impact_zone_particles += counts.impact_zone_particles;
      }
    }
    if (output.is_open() && (k % write_every == 0 || k == steps)) writeStates(output, *world);
    if (pin_forces.is_open() && (k % write_every == 0 || k == steps)) writePinForces(pin_forces, *world);
    if (after - last_progress > std::chrono::seconds(1))
    {
      std::fprintf(stderr, "particle_sim_run: %.1f%% (sim time %.3f s of %.3f s)\n", 100.0 * k / steps,
                   world->simTime(), duration);
      last_progress = after;
    }
  }
  const double wall = std::chrono::duration<double>(Clock::now() - start).count();
  int exit_code = 0;
  for (const auto& body : world->bodies())
  {
    const auto* spring_body = dynamic_cast<const particle_sim::core::SpringNetworkBody*>(body.get());
    if (spring_body && spring_body->frozen())
    {
      std::fprintf(stderr, "particle_sim_run: body '%s' froze: %s\n", body->name().c_str(),
                   spring_body->frozenReason().c_str());
      exit_code = 3;
    }
  }
  std::printf("steps %llu, sim time %.6g s, wall %.3f s, %.3f us/step, live particles %d\n",
              static_cast<unsigned long long>(steps), world->simTime(), wall,
              steps ? 1e6 * stepping_seconds / steps : 0.0, world->particleCount());
  // What the stability guard did, what `auto` picked, what tore and what collided, per spring body.
  for (const BodyStats& stats : body_stats)
  {
    const particle_sim::core::SpringNetworkBody* spring_body = stats.body;
    const particle_sim::core::Body* body = spring_body;
    if (!spring_body->autoChoice().empty())
      std::printf("body '%s' auto: %s\n", body->name().c_str(), spring_body->autoChoice().c_str());
    if (spring_body->stabilityEvents() > 0)
      std::printf("body '%s': %lld stability events, last: %s\n", body->name().c_str(), spring_body->stabilityEvents(),
                  spring_body->lastStabilityEvent().c_str());
    // Only a body that can tear says what tore, and what is left of its surface when it has one.
    const particle_sim::core::SpringNetworkDef& def = spring_body->definition();
    if (def.tear_strain > 0.0)
    {
      std::printf("body '%s': %lld springs torn (tear_strain %g)", body->name().c_str(), spring_body->tornSprings(),
                  def.tear_strain);
      if (spring_body->baraffWitkin()) std::printf(", %lld triangles torn", spring_body->tornTriangles());
      if (def.shape == particle_sim::core::NetworkShape::Cloth)
        std::printf(", %lld particles split off", spring_body->splitParticles());
      if (!def.triangles.empty())
        std::printf(", %zu of %zu surface triangles left", spring_body->surfaceTriangles().size(),
                    def.triangles.size());
      std::printf("\n");
    }
    // Only a body that enables self_collision says what its collision passes found, summed over the run.
    if (def.self_collision.enabled)
      std::printf(
          "body '%s': %lld contacts, %lld collisions, %lld impact-zone particles over %llu steps "
          "(self_collision, thickness %g m)\n",
          body->name().c_str(), stats.collisions.proximity_pairs, stats.collisions.collisions,
          stats.collisions.impact_zone_particles, static_cast<unsigned long long>(steps), def.self_collision.thickness);
  }
  if (any_self_collision)
    std::printf("self_collision: %lld passes, %lld impact zones over %llu steps\n", collision_passes, impact_zones,
                static_cast<unsigned long long>(steps));
  // The solver figures of every implicit method that ran, named as it ran: "body 'cloth' bdf2: ..."
  // for a body's own method; "body 'rope' auto ran implicit_euler for 40 of 120 steps: ..." (and
  // each explicit method auto ran, with its step count) for an `auto` body.
  for (const BodyStats& stats : body_stats)
  {
    const bool is_auto = stats.body->integrator().type == particle_sim::core::kAutoIntegrator;
    for (const MethodStats& method : stats.methods)
    {
      const bool implicit = particle_sim::core::isImplicit(method.method);
      if (!implicit && !is_auto) continue;
      std::printf("body '%s' ", stats.body->name().c_str());
      if (is_auto)
        std::printf("auto ran %s for %lld of %llu steps", particle_sim::core::toString(method.method), method.steps,
                    static_cast<unsigned long long>(steps));
      else
        std::printf("%s", particle_sim::core::toString(method.method));
      if (implicit)
        std::printf(
            ": CG iterations mean %.1f, max %d; worst relative residual %.2e, velocity error %.2e m/s; %lld steps "
            "not converged; %lld of %lld solved directly",
            static_cast<double>(method.iterations) / method.steps, method.max_iterations, method.worst_residual,
            method.worst_velocity_error, method.unconverged, method.direct, method.steps);
      if (implicit && method.multigrid > 0) std::printf(", %lld by the multigrid", method.multigrid);
      std::printf("\n");
    }
  }
  return exit_code;
}
