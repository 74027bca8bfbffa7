// particle_sim_perf: the performance bench of issue 13. Times the core's step on bodies built in
// code at a sweep of sizes and writes one CSV row per case and size: ropes and cloths solved
// implicitly (both linear solvers), Bullet's test cloth ("hang64"), `auto` beside every fixed
// choice on it (timed side by side), the implicit solve's stopping rule on each of them, the direct
// solve's flops against the machine's arithmetic roof, explicit springs against its memory
// bandwidth (a STREAM-like triad), emitters, and the self-collision pass beside the rest of the
// step. scripts/bench --performance runs it and scripts/performance_report.py turns the CSV into
// docs/performance.md and its plots.
//
//   particle_sim_perf [--out FILE] [--quick] [--only CASE,...]
//
// Every time is wall time of the step alone (steady_clock), after warm-up steps, over `repeats`
// runs of `steps` steps: the CSV gives the minimum, median and maximum per step over the repeats.

#include <pthread.h>
#include <sched.h>

#include <Eigen/Core>
#if defined(__x86_64__)
#include <immintrin.h>
#endif
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "../../test/unit/folded_cloth.h"  // the self-collision tests' folded cloth and pile, timed here
#include "bench_rows.h"
#include "hang64.h"
#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/constraints/self_collision.h"
#include "particle_sim/core/emitter.h"
#include "particle_sim/core/integrators/cg_avx2.h"
#include "particle_sim/core/integrators/dense_panel.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/sparse_block_ldlt.h"
#include "particle_sim/core/integrators/symplectic_euler.h"
#include "particle_sim/core/integrators/verlet.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/vector_registers.h"
#include "particle_sim/core/world.h"
#include "particle_sim/process/huge_pages.h"

namespace core = particle_sim::core;
using particle_sim_bench::hang64;
using particle_sim_bench::Row;
using particle_sim_bench::summarize;
using particle_sim_bench::timeInRounds;
using particle_sim_bench::timeRepeat;
using particle_sim_bench::timeSteps;
using particle_sim_bench::writeRow;
using Clock = std::chrono::steady_clock;

namespace
{
const char* kUsage =
    "usage: particle_sim_perf [--out FILE] [--quick] [--only CASE,...]\n"
    "  --out FILE    CSV output (default performance.csv)\n"
    "  --quick       fewer sizes, steps and repeats: a smoke run, not a report\n"
    "  --only CASES  run only these cases: rope, cloth, sizes, hang64, auto, stopping, springs,\n"
    "                emitters, selfcollision, threads\n";

core::Environment noGround()
{
  core::Environment env;
  env.ground.enabled = false;
  return env;
}

// Steps a body `warmup` + `repeats` × `steps` times at dt; mean CG iterations over the timed steps.
Row timeBody(core::SpringNetworkBody& body, double dt, int warmup, int steps, int repeats,
             const std::function<void()>& before_repeat = {})
{
  const core::Environment env = noGround();
  long long iterations = 0, counted = 0;
  Row row;
  row.timing = timeSteps(
      [&] {
        body.step(dt, env);
        iterations += body.lastSolve().iterations;
        ++counted;
      },
      warmup, steps, repeats, before_repeat);
  row.iterations = counted > 0 ? static_cast<double>(iterations) / counted : 0.0;
  if (body.frozen()) row.detail = "FROZE: " + body.frozenReason();
  return row;
}

// --- Ropes: the hard case of config/scenes/hard/long_rope.yaml at every size: 5 m, 1 kg, stretch
// springs of 20000 N/m, pinned at one end and released from horizontal, implicit Euler at
// dt = 1/60 with each linear solver. longRope() is that rope, before its integrator is chosen.
core::RopeDef longRope(int segments)
{
  core::RopeDef def;
  def.name = "rope";
  def.particles = segments + 1;
  def.start = {0.0, 0.0, 6.0};
  def.end = {5.0, 0.0, 6.0};
  def.mass = 1.0;
  def.stretch_stiffness = 20000.0;
  def.stretch_damping = 0.0;
  def.pins = {0};
  return def;
}

// That rope under implicit Euler with `solver`, to a relative 1e-8 (the relative rule alone: goal 9
// has its own case).
core::SpringNetworkDef implicitRope(int segments, core::LinearSolverType solver)
{
  core::RopeDef def = longRope(segments);
  def.integrator.type = core::kImplicitEulerIntegrator;
  def.integrator.linear_solver = solver;
  def.integrator.cg_tolerance = 1e-8;
  def.integrator.cg_velocity_tolerance = 0.0;
  def.integrator.cg_max_iterations = 100000;
  return core::buildRope(def);
}

void ropes(std::ostream& out, bool quick)
{
  const std::vector<int> sizes = quick ? std::vector<int>{100, 1000} : std::vector<int>{100, 300, 1000, 3000, 10000};
  for (const char* solver : {"direct", "cg"})
  {
    for (int segments : sizes)
    {
      const bool cg = std::strcmp(solver, "cg") == 0;
      if (cg && segments > (quick ? 1000 : 3000)) continue;  // seconds per step
      core::SpringNetworkBody body(
          implicitRope(segments, cg ? core::LinearSolverType::ConjugateGradient : core::LinearSolverType::Direct));
      const int steps = quick ? 5 : (cg ? std::max(5, 20000 / segments) : std::max(30, 300000 / segments));
      Row row = timeBody(body, 1.0 / 60.0, 10, steps, quick ? 2 : 5);
      row.case_name = "rope";
      row.variant = std::string("implicit_euler ") + solver;
      row.size = segments;
      row.elements = segments;
      if (body.stabilityEvents() > 0)
        row.detail += (row.detail.empty() ? "" : "; ") + std::to_string(body.stabilityEvents()) + " stability events";
      writeRow(out, row);
    }
  }
}

// --- Cloth: a 1 m square spring cloth of n x n particles (Provot: structural, shear and bend
// springs, 1000 N/m, 0.01 N·s/m; 1 kg), horizontal, hanging from two adjacent corners; implicit
// Euler at dt = 1/60, relative CG tolerance 1e-6.
core::ClothGridDef squareCloth(int n, core::LinearSolverType solver)
{
  core::ClothGridDef def(core::ClothModel::Springs);
  def.name = "cloth";
  def.origin = {0.0, 0.0, 2.0};
  def.edge_u = {1.0, 0.0, 0.0};
  def.edge_v = {0.0, 1.0, 0.0};
  def.nu = def.nv = n;
  def.mass = 1.0;
  def.stretch.stiffness = 1000.0;
  def.stretch.damping = 0.01;
  def.shear.stiffness = 1000.0;
  def.shear.damping = 0.01;
  def.bend.stiffness = 100.0;
  def.bend.damping = 0.01;
  def.named_pins = {"corner_00", "corner_10"};
  def.integrator.type = core::kImplicitEulerIntegrator;
  def.integrator.linear_solver = solver;
  def.integrator.cg_tolerance = 1e-6;
  def.integrator.cg_velocity_tolerance = 0.0;  // a fixed relative tolerance (goal 2)
  def.integrator.cg_max_iterations = 100000;
  return def;
}

void cloths(std::ostream& out, bool quick)
{
  const std::vector<int> sizes = quick ? std::vector<int>{32} : std::vector<int>{32, 64, 128, 256};
  for (const core::LinearSolverType solver :
       {core::LinearSolverType::ConjugateGradient, core::LinearSolverType::Direct, core::LinearSolverType::Multigrid})
  {
    for (int n : sizes)
    {
      if (solver == core::LinearSolverType::Direct && n > 64) continue;  // the factor's fill: seconds
      core::SpringNetworkBody body(core::buildClothGrid(squareCloth(n, solver)));
      const int steps = quick ? 3 : std::max(3, 40000 / (n * n));
      Row row = timeBody(body, 1.0 / 60.0, quick ? 3 : 10, steps, quick ? 2 : 3);
      row.case_name = "cloth";
      row.variant = std::string("implicit_euler ") + core::toString(solver);
      row.size = n;
      row.elements = static_cast<double>(n) * n;
      writeRow(out, row);
    }
  }
}

// Bodies timed side by side (goals 2 and 8): built from `defs`, each warmed up by `warmup` steps of
// dt from rest, then timed in rounds (timeInRounds(): each round steps every body `steps` times, one
// after the other, the order shifted by one each round), so that a spell of load on the virtual
// machine falls on all of them alike and each round times them over the same span of simulated time.
struct SideBySide
{
  std::vector<std::unique_ptr<core::SpringNetworkBody>> bodies;
  std::vector<std::vector<double>> times;  // [body][round]: ms per step
  std::vector<double> iterations;          // per body: mean CG iterations per timed step
};

SideBySide timeSideBySide(const std::vector<core::SpringNetworkDef>& defs, double dt, int warmup, int steps, int rounds)
{
  const core::Environment env = noGround();
  SideBySide timed;
  std::vector<long long> iterations(defs.size(), 0);
  std::vector<std::function<void()>> step;
  for (std::size_t b = 0; b < defs.size(); ++b)
  {
    timed.bodies.push_back(std::make_unique<core::SpringNetworkBody>(defs[b]));
    step.push_back([&, b] {
      timed.bodies[b]->step(dt, env);
      iterations[b] += timed.bodies[b]->lastSolve().iterations;
    });
  }
  for (const std::function<void()>& warm_up_step : step)
  {
    for (int i = 0; i < warmup; ++i)
      warm_up_step();
  }
  std::fill(iterations.begin(), iterations.end(), 0);
  timed.times = timeInRounds(step, steps, rounds);
  for (const long long sum : iterations)
    timed.iterations.push_back(static_cast<double>(sum) / (static_cast<double>(rounds) * steps));
  return timed;
}

// --- Goal 2's ratios side by side: for each ratio, the body at both sizes (the spring cloth at 64²
// and 128² with each iterative solver, the rope of 100 and of 1000 segments solved directly) timed
// side by side (timeSideBySide()); each round gives the larger size's time over the smaller's. The
// ratio row's three figures are those ratios' min, median and max, and each size's row its rounds'
// times. The rows of cloths() and ropes() are timed a minute or more apart, so their ratios also carry
// how the machine's load moved in between.
void sizesSideBySide(std::ostream& out, bool quick)
{
  struct Ratio
  {
    std::string case_name, variant;
    int small, large;
    std::function<core::SpringNetworkDef(int)> build;
  };
  const int cloth_small = quick ? 16 : 64, cloth_large = quick ? 32 : 128;
  std::vector<Ratio> ratios;
  for (const core::LinearSolverType solver :
       {core::LinearSolverType::ConjugateGradient, core::LinearSolverType::Multigrid})
    ratios.push_back({"cloth", std::string("implicit_euler ") + core::toString(solver), cloth_small, cloth_large,
                      [solver](int n) { return core::buildClothGrid(squareCloth(n, solver)); }});
  ratios.push_back({"rope", "implicit_euler direct", 100, 1000,
                    [](int segments) { return implicitRope(segments, core::LinearSolverType::Direct); }});
  for (const Ratio& ratio : ratios)
  {
    const std::vector<int> sizes = {ratio.small, ratio.large};
    const bool rope_case = ratio.case_name == "rope";
    const int warmup = quick ? 2 : 10;
    const int rounds = quick ? 3 : 9;
    const int steps = quick ? 2 : (rope_case ? 200 : 4);
    const SideBySide timed =
        timeSideBySide({ratio.build(ratio.small), ratio.build(ratio.large)}, 1.0 / 60.0, warmup, steps, rounds);
    const std::vector<std::vector<double>>& times = timed.times;
    std::vector<double> round_ratios;
    for (int round = 0; round < rounds; ++round)
      round_ratios.push_back(times[1][round] / times[0][round]);
    auto elements = [&](int size) { return rope_case ? size : static_cast<double>(size) * size; };
    for (std::size_t b = 0; b < sizes.size(); ++b)
    {
      Row row;
      row.case_name = "size_paired";
      row.variant = ratio.case_name + " " + ratio.variant + " " + std::to_string(sizes[b]);
      row.size = sizes[b];
      row.elements = elements(sizes[b]);
      row.timing = summarize(times[b]);
      row.iterations = timed.iterations[b];
      std::ostringstream detail;
      detail << rounds << " rounds of " << steps << " steps after " << warmup << " warm-up steps, in turn with size "
             << sizes[1 - b];
      if (timed.bodies[b]->frozen()) detail << "; FROZE: " << timed.bodies[b]->frozenReason();
      row.detail = detail.str();
      writeRow(out, row);
    }
    Row row;
    row.case_name = "size_paired";
    row.variant = "ratio " + ratio.case_name + " " + ratio.variant + " " + std::to_string(ratio.large) + "/" +
                  std::to_string(ratio.small);
    row.size = ratio.large;
    row.elements = elements(ratio.large);
    row.timing = summarize(round_ratios);
    row.detail = "size " + std::to_string(ratio.large) + "'s time over size " + std::to_string(ratio.small) +
                 "'s, round by round (" + std::to_string(rounds) + " rounds of " + std::to_string(steps) +
                 " steps): min, median and max in the time columns";
    writeRow(out, row);
  }
}

// How far hang64 stretches and sags under a method: simulated for `seconds` from rest, the peak
// over all steps of the largest spring strain, and the sag at the end (the lowest particle's depth
// below the pinned corners). Bullet's peer (particle_sim_bullet_peer) reports the same two figures,
// so that the engines can be compared at equal stretch.
std::string stretchAndSag(core::SpringNetworkDef def, double dt, double seconds)
{
  core::SpringNetworkBody body(def);
  const core::Environment env = noGround();
  double peak = 0.0;
  const int steps = static_cast<int>(std::lround(seconds / dt));
  for (int i = 0; i < steps && !body.frozen(); ++i)
  {
    body.step(dt, env);
    peak = std::max(peak, body.maxStrain());
  }
  const core::ParticlePool& p = body.particles();
  const double sag = def.positions[def.pins[0]].z() - p.position.leftCols(p.size()).row(2).minCoeff();
  std::ostringstream text;
  text.precision(3);
  text << "over " << seconds << " s: peak strain " << peak << ", sag " << sag << " m";
  if (body.frozen()) text << ", FROZE";
  return text.str();
}

// A machine roof as a row: its value in the three time columns (the report reads ms_min), its unit
// in the detail.
void writeRoofRow(std::ostream& out, const std::string& case_name, const std::string& variant, double value,
                  const std::string& detail)
{
  Row roof;
  roof.case_name = case_name;
  roof.variant = variant;
  roof.size = 0;
  roof.elements = 0;
  roof.timing = {value, value, value};
  roof.detail = detail;
  writeRow(out, roof);
}

// The arithmetic roof of this build: the most double-precision multiplies and adds one core retires
// a second in the instructions the engine's code is compiled to (Eigen's packets of two doubles: the
// x86-64 baseline, SSE2, with no fused multiply-add). Six chains of multiplies and six of adds,
// independent of each other and held in registers. arithmeticPass() is one pass of `iterations`
// (chains seeded by r), its flop/s; arithmeticRoof() the best of repeats.
double arithmeticPass(long iterations, int r)
{
  volatile double factor_source = 1.0, term_source = 1e-300;  // unknown to the compiler: nothing folds
  const Eigen::Array2d factor = Eigen::Array2d::Constant(static_cast<double>(factor_source));
  const Eigen::Array2d term = Eigen::Array2d::Constant(static_cast<double>(term_source));
  Eigen::Array2d m0 = Eigen::Array2d::Constant(1.0 + r), m1 = m0 + 1.0, m2 = m0 + 2.0, m3 = m0 + 3.0, m4 = m0 + 4.0,
                 m5 = m0 + 5.0;
  Eigen::Array2d a0 = m0 + 6.0, a1 = m0 + 7.0, a2 = m0 + 8.0, a3 = m0 + 9.0, a4 = m0 + 10.0, a5 = m0 + 11.0;
  const auto start = Clock::now();
  for (long i = 0; i < iterations; ++i)
  {
    m0 *= factor;
    a0 += term;
    m1 *= factor;
    a1 += term;
    m2 *= factor;
    a2 += term;
    m3 *= factor;
    a3 += term;
    m4 *= factor;
    a4 += term;
    m5 *= factor;
    a5 += term;
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  volatile double sink = (m0 + m1 + m2 + m3 + m4 + m5 + a0 + a1 + a2 + a3 + a4 + a5).sum();  // keep the chains
  (void)sink;
  return 24.0 * static_cast<double>(iterations) / seconds;  // 12 operations on 2 lanes
}

// The best of repeats of one of the passes.
double bestPass(bool quick, double (*pass)(long, int))
{
  double best = 0.0;
  for (int r = 0; r < (quick ? 3 : 10); ++r)
    best = std::max(best, pass(quick ? 2000000 : 20000000, r));
  return best;
}

double arithmeticRoof(bool quick)
{
  return bestPass(quick, arithmeticPass);
}

#if defined(__x86_64__)
// Twelve chains of fused multiply-adds (x = x factor + term, two flops each) on AVX2's four lanes,
// which the direct solver's supernodal products run on where the processor has AVX2 and FMA
// (core/integrators/dense_panel.h).
__attribute__((target("avx2,fma"))) double arithmeticPassFma(long iterations, int r)
{
  volatile double factor_source = 1.0, term_source = 1e-300;
  const __m256d factor = _mm256_set1_pd(factor_source), term = _mm256_set1_pd(term_source);
  __m256d x[12];
  for (int c = 0; c < 12; ++c)
    x[c] = _mm256_set1_pd(1.0 + c + r);
  const auto start = Clock::now();
  for (long i = 0; i < iterations; ++i)
  {
    // Unrolled whole, so that the twelve chains stay in registers.
#pragma GCC unroll 12
    for (int c = 0; c < 12; ++c)
      x[c] = _mm256_fmadd_pd(x[c], factor, term);
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  __m256d all = x[0];
  for (int c = 1; c < 12; ++c)
    all = _mm256_add_pd(all, x[c]);
  alignas(32) double lanes[4];
  _mm256_store_pd(lanes, all);
  volatile double sink = lanes[0] + lanes[1] + lanes[2] + lanes[3];  // keep the chains
  (void)sink;
  return 96.0 * static_cast<double>(iterations) / seconds;  // 12 fused multiply-adds on 4 lanes
}
#endif

// The FMA roof, 0 where the processor has no AVX2 and FMA (then the supernodal products run scalar).
double arithmeticRoofFma(bool quick)
{
#if defined(__x86_64__)
  if (core::dense_panel::available())
  {
    const double roof = bestPass(quick, arithmeticPassFma);
    core::clearUpperHalves();  // for the plain code of the cases after it, as the engine's passes do
    return roof;
  }
#endif
  (void)quick;
  return 0.0;
}

// hang64's variants: implicit Euler at h = 1/60 with each linear solver (goal 1); Verlet split into
// the substeps its stability needs (the cheapest stable explicit method: against Bullet's
// position-based solver at equal stretch, goal 7); and `auto` (goal 8: within 1.2x of the best fixed
// choice). Then the same at h = 1/1000, where Bullet's implicit solver is compared at the same dt
// (goal 7), to 1e-6 and to Bullet's own default relative residual of 3.45e-4, like Bullet's two rows
// at that dt.
struct HangVariant
{
  std::string name;
  core::IntegratorType integrator;
  core::LinearSolverType solver;
  double tolerance, dt;
};

std::vector<HangVariant> hangVariants()
{
  const double h60 = 1.0 / 60.0, h1000 = 1.0 / 1000.0;
  return {
      {"implicit_euler cg tol 1e-6", core::kImplicitEulerIntegrator, core::LinearSolverType::ConjugateGradient, 1e-6,
       h60},
      {"implicit_euler cg tol 1e-4", core::kImplicitEulerIntegrator, core::LinearSolverType::ConjugateGradient, 1e-4,
       h60},
      {"implicit_euler direct", core::kImplicitEulerIntegrator, core::LinearSolverType::Direct, 1e-6, h60},
      {"implicit_euler multigrid tol 1e-6", core::kImplicitEulerIntegrator, core::LinearSolverType::Multigrid, 1e-6,
       h60},
      {"verlet substepped", core::kVerletIntegrator, core::LinearSolverType::Auto, 1e-6, h60},
      {"auto", core::kAutoIntegrator, core::LinearSolverType::Auto, 1e-6, h60},
      {"implicit_euler cg dt 1/1000", core::kImplicitEulerIntegrator, core::LinearSolverType::ConjugateGradient, 1e-6,
       h1000},
      {"implicit_euler cg dt 1/1000 tol 3.45e-4", core::kImplicitEulerIntegrator,
       core::LinearSolverType::ConjugateGradient, 3.45e-4, h1000},
      {"implicit_euler direct dt 1/1000", core::kImplicitEulerIntegrator, core::LinearSolverType::Direct, 1e-6, h1000},
      {"implicit_euler multigrid dt 1/1000", core::kImplicitEulerIntegrator, core::LinearSolverType::Multigrid, 1e-6,
       h1000},
      {"verlet substepped dt 1/1000", core::kVerletIntegrator, core::LinearSolverType::Auto, 1e-6, h1000},
      {"auto dt 1/1000", core::kAutoIntegrator, core::LinearSolverType::Auto, 1e-6, h1000},
  };
}

// hang64 set up as `variant` asks: its method and linear solver, the variant's relative tolerance
// alone (no velocity rule) and no cap in practice on CG's iterations or the substeps.
core::SpringNetworkDef hangDef(const HangVariant& variant)
{
  core::SpringNetworkDef def = hang64(64);
  def.integrator.type = variant.integrator;
  def.integrator.linear_solver = variant.solver;
  def.integrator.cg_tolerance = variant.tolerance;
  def.integrator.cg_velocity_tolerance = 0.0;
  def.integrator.cg_max_iterations = 100000;
  def.integrator.max_substeps = 100000;
  return def;
}

void hang(std::ostream& out, bool quick)
{
  // The roof the direct solve's flops are measured against (goal 1).
  writeRoofRow(out, "roof", "arithmetic", arithmeticRoof(quick) / 1e9,
               "GFlop/s (best of repeats), one core: independent double multiplies and adds on pairs of lanes "
               "(Eigen's packets in this build, no fused multiply-add)");
  if (const double fma = arithmeticRoofFma(quick); fma > 0.0)
    writeRoofRow(out, "roof", "arithmetic fma", fma / 1e9,
                 "GFlop/s (best of repeats), one core: independent fused multiply-adds on AVX2's four lanes (two "
                 "flops each), which the direct solver's supernodal products run on");
  const std::vector<HangVariant> variants = hangVariants();
  for (const HangVariant& variant : variants)
  {
    const core::SpringNetworkDef def = hangDef(variant);
    core::SpringNetworkBody body(def);
    const int steps = variant.dt < 0.01 ? 500 : 60;
    Row row = timeBody(body, variant.dt, quick ? 3 : 10, quick ? 5 : steps, quick ? 1 : 3);
    if (variant.solver == core::LinearSolverType::Direct)
    {
      // The factorization's size, from the pattern of the implicit system (one block per spring).
      std::vector<std::vector<int>> columns(def.positions.size());
      for (std::size_t i = 0; i < columns.size(); ++i)
        columns[i].push_back(static_cast<int>(i));
      for (const core::Spring& spring : def.springs)
      {
        columns[spring.i].push_back(spring.j);
        columns[spring.j].push_back(spring.i);
      }
      std::vector<int> row_start = {0}, block_column;
      for (std::vector<int>& c : columns)
      {
        std::sort(c.begin(), c.end());
        block_column.insert(block_column.end(), c.begin(), c.end());
        row_start.push_back(static_cast<int>(block_column.size()));
      }
      const core::SparseBlockLdlt::Cost cost = core::SparseBlockLdlt::estimateCost(row_start, block_column);
      std::ostringstream detail;
      detail.precision(3);
      detail << "factorization " << cost.factor_flops / 1e6 << " Mflop (" << cost.factor_blocks
             << " blocks of L), solve " << cost.solve_flops / 1e6 << " Mflop";
      row.detail = detail.str() + (row.detail.empty() ? "" : "; " + row.detail);
    }
    if (!core::isImplicit(body.lastIntegrator()))
      row.detail = std::string(core::toString(body.lastIntegrator())) + ", " + std::to_string(body.lastSubsteps()) +
                   " substeps" + (row.detail.empty() ? "" : "; " + row.detail);
    else if (variant.integrator == core::kAutoIntegrator)
      row.detail = std::string(core::toString(body.lastIntegrator())) + (row.detail.empty() ? "" : "; " + row.detail);
    const std::string stretch = stretchAndSag(def, variant.dt, quick ? 0.1 : 2.0);
    row.detail = (row.detail.empty() ? "" : row.detail + "; ") + stretch;
    row.case_name = "hang64";
    row.variant = variant.name;
    row.size = 64;
    row.elements = 64 * 64;
    writeRow(out, row);
  }
}

// --- `auto` side by side (goal 8): at each dt of hang64's variants, `auto` and every fixed choice of
// that dt, timed side by side (timeSideBySide()). Each round gives auto's time over
// the fastest fixed choice's in that round; the ratio row's three figures are those ratios' min,
// median and max, and each body's row its rounds' times. The separate rows of hang() are timed
// seconds to minutes apart, so their ratios also carry how the machine's load moved in between.
void autoSideBySide(std::ostream& out, bool quick)
{
  const std::vector<HangVariant> variants = hangVariants();
  for (const HangVariant& auto_variant : variants)
  {
    if (auto_variant.integrator != core::kAutoIntegrator) continue;
    // The auto body first, then the fixed choices of its dt, as hangVariants() lists them.
    const double dt = auto_variant.dt;
    std::vector<const HangVariant*> chosen = {&auto_variant};
    for (const HangVariant& variant : variants)
    {
      if (variant.dt == dt && variant.integrator != core::kAutoIntegrator) chosen.push_back(&variant);
    }
    const int bodies_count = static_cast<int>(chosen.size());
    std::vector<core::SpringNetworkDef> defs;
    for (const HangVariant* variant : chosen)
      defs.push_back(hangDef(*variant));
    const int warmup = quick ? 2 : 10;
    const int rounds = quick ? 3 : 15;
    const int steps = quick ? 2 : (dt < 0.01 ? 40 : 8);
    const SideBySide timed = timeSideBySide(defs, dt, warmup, steps, rounds);
    const std::vector<std::vector<double>>& times = timed.times;
    std::vector<double> ratios;
    std::vector<int> fastest_rounds(bodies_count, 0);  // rounds in which each fixed choice was the fastest
    for (int round = 0; round < rounds; ++round)
    {
      int best = 1;
      for (int b = 2; b < bodies_count; ++b)
        if (times[b][round] < times[best][round]) best = b;
      ++fastest_rounds[best];
      ratios.push_back(times[0][round] / times[best][round]);
    }
    const std::string at = dt < 0.01 ? " dt 1/" + std::to_string(static_cast<int>(std::lround(1.0 / dt))) : "";
    for (int b = 0; b < bodies_count; ++b)
    {
      const core::SpringNetworkBody& body = *timed.bodies[b];
      Row row;
      row.case_name = "auto_paired";
      row.variant = chosen[b]->name;
      row.size = 64;
      row.elements = 64 * 64;
      row.timing = summarize(times[b]);
      row.iterations = timed.iterations[b];
      std::ostringstream detail;
      detail << rounds << " rounds of " << steps << " steps after " << warmup << " warm-up steps, in turn with "
             << bodies_count - 1 << " other bodies";
      if (b > 0) detail << "; the fastest fixed choice in " << fastest_rounds[b] << " of " << rounds << " rounds";
      if (!core::isImplicit(body.lastIntegrator()))
        detail << "; " << core::toString(body.lastIntegrator()) << ", " << body.lastSubsteps() << " substeps";
      else if (chosen[b]->integrator == core::kAutoIntegrator)
        detail << "; " << core::toString(body.lastIntegrator());
      if (body.frozen()) detail << "; FROZE: " << body.frozenReason();
      row.detail = detail.str();
      writeRow(out, row);
    }
    Row ratio;
    ratio.case_name = "auto_paired";
    ratio.variant = "ratio" + at;
    ratio.size = 64;
    ratio.elements = 64 * 64;
    ratio.timing = summarize(ratios);
    ratio.detail = "auto's time over the fastest fixed choice's, round by round (" + std::to_string(rounds) +
                   " rounds of " + std::to_string(steps) + " steps): min, median and max in the time columns";
    writeRow(out, ratio);
  }
}

// --- The stopping rule (goal 9): every CG scene of the bench, from rest, with the default rule
// (IntegratorDef's cg_velocity_tolerance and cg_tolerance) and no cap in practice: the iterations
// the rule needs each step, how many steps it would leave at the default cap, the worst velocity
// error, and any step that did not meet it; then the same steps at every default (linear solver
// `auto`, the cap): how many ended unconverged and how many were solved directly.
void stoppingRule(std::ostream& out, bool quick)
{
  const core::IntegratorDef defaults;
  struct Scene
  {
    std::string name;
    int size;
    core::SpringNetworkDef def;
    double dt;
    int steps;
  };
  std::vector<Scene> scenes;
  for (int segments : quick ? std::vector<int>{100} : std::vector<int>{100, 300, 1000, 3000})
    scenes.push_back({"rope", segments, core::buildRope(longRope(segments)), 1.0 / 60.0, segments > 1000 ? 20 : 60});
  for (int n : quick ? std::vector<int>{32} : std::vector<int>{32, 64, 128, 256})
    scenes.push_back({"cloth", n, core::buildClothGrid(squareCloth(n, core::LinearSolverType::ConjugateGradient)),
                      1.0 / 60.0, n >= 256 ? 3 : (n >= 128 ? 10 : 60)});
  scenes.push_back({"hang64", 64, hang64(64), 1.0 / 60.0, quick ? 5 : 60});
  scenes.push_back({"hang64 dt 1/1000", 64, hang64(64), 1.0 / 1000.0, quick ? 5 : 500});
  for (Scene& scene : scenes)
  {
    scene.def.integrator = core::BodyIntegratorDef{};
    scene.def.integrator.type = core::kImplicitEulerIntegrator;
    scene.def.integrator.linear_solver = core::LinearSolverType::ConjugateGradient;
    scene.def.integrator.cg_max_iterations = 100000;
    core::SpringNetworkBody body(scene.def);
    const core::Environment env = noGround();
    long long iterations = 0;
    int most = 0, over_cap = 0, unconverged = 0;
    double worst_velocity_error = 0.0;
    const auto start = Clock::now();
    for (int i = 0; i < scene.steps && !body.frozen(); ++i)
    {
      body.step(scene.dt, env);
      const core::SolverReport& report = body.lastSolve();
      iterations += report.iterations;
      most = std::max(most, report.iterations);
      over_cap += report.iterations > defaults.cg_max_iterations ? 1 : 0;
      unconverged += report.converged ? 0 : 1;
      worst_velocity_error = std::max(worst_velocity_error, report.velocity_error);
    }
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count() / scene.steps;
    Row row;
    row.case_name = "stopping";
    row.variant = scene.name;
    row.size = scene.size;
    row.elements = static_cast<double>(scene.def.positions.size());
    row.timing = {ms, ms, ms};
    row.iterations = static_cast<double>(iterations) / scene.steps;
    std::ostringstream detail;
    detail.precision(3);
    detail << scene.steps << " steps from rest at dt " << scene.dt << " s; max " << most << " iterations; " << over_cap
           << " steps over the default cap of " << defaults.cg_max_iterations << "; " << unconverged
           << " unconverged; worst velocity error " << worst_velocity_error << " m/s (tolerance "
           << defaults.cg_velocity_tolerance << " m/s)";
    if (body.frozen()) detail << "; FROZE: " << body.frozenReason();
    // The same steps at the defaults (the linear solver `auto`, the cap of 500): a solve that the
    // cap stops short is done again directly, so no step should end unconverged.
    scene.def.integrator = core::BodyIntegratorDef{};
    scene.def.integrator.type = core::kImplicitEulerIntegrator;
    core::SpringNetworkBody at_defaults(scene.def);
    int unconverged_at_defaults = 0, direct_steps = 0;
    for (int i = 0; i < scene.steps && !at_defaults.frozen(); ++i)
    {
      at_defaults.step(scene.dt, env);
      unconverged_at_defaults += at_defaults.lastSolve().converged ? 0 : 1;
      direct_steps += at_defaults.lastSolve().direct ? 1 : 0;
    }
    detail << "; at the defaults (linear_solver auto, cap " << defaults.cg_max_iterations
           << "): " << unconverged_at_defaults << " steps unconverged, " << direct_steps << " of " << scene.steps
           << " direct";
    if (at_defaults.frozen()) detail << "; FROZE at the defaults: " << at_defaults.frozenReason();
    row.detail = detail.str();
    writeRow(out, row);
  }
}

// --- Explicit springs against the memory roof: symplectic Euler on an n x n spring cloth (forces
// of every spring once per substep), in ns per spring per force pass; and the machine's triad
// bandwidth a[i] = b[i] + s c[i] over arrays far larger than the caches, taken between the springs'
// repeats as well as before them: this machine's bandwidth wanders by a sixth within half an hour,
// and the ratio to the floor should compare the two in the same minutes.
class Triad
{
public:
  explicit Triad(bool quick) : n_(quick ? (1u << 22) : (1u << 24)), a_(n_, 0.0), b_(n_, 1.0), c_(n_, 2.0) {}
  // One more pass; returns its rate [bytes/s]; best() is the best rate of all passes so far.
  double pass()
  {
    const auto start = Clock::now();
    for (std::size_t i = 0; i < n_; ++i)
      a_[i] = b_[i] + 3.0 * c_[i];
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    b_[passes_ % n_] += a_[(passes_ * 7919) % n_];  // keep the loop's result alive
    ++passes_;
    const double rate = 3.0 * sizeof(double) * n_ / seconds;
    best_ = std::max(best_, rate);
    return rate;
  }
  double best() const { return best_; }
  int passes() const { return passes_; }
  std::size_t megabytes() const { return n_ * sizeof(double) >> 20; }

private:
  std::size_t n_;
  std::vector<double> a_, b_, c_;
  double best_ = 0.0;
  int passes_ = 0;
};

void explicitSprings(std::ostream& out, bool quick)
{
  Triad triad(quick);
  for (int r = 0; r < (quick ? 3 : 10); ++r)
    triad.pass();
  for (int n : quick ? std::vector<int>{64} : std::vector<int>{64, 128, 256})
  {
    core::ClothGridDef def = squareCloth(n, core::LinearSolverType::Auto);
    def.integrator.type = core::kSymplecticEulerIntegrator;
    def.integrator.max_substeps = 1;
    core::SpringNetworkBody body(core::buildClothGrid(def));
    const double dt = 0.5 * 2.0 / body.frequencyBound();  // half the explicit limit: one force pass a step
    const int steps = quick ? 5 : std::max(10, 2000000 / (n * n));
    // A triad pass before each repeat, and one untimed step after it, which brings back into the
    // caches what the triad took out of them: the repeat times steps as they follow each other.
    Row row = timeBody(body, dt, 5, steps, quick ? 2 : 5, [&] {
      triad.pass();
      body.step(dt, noGround());
    });
    const double springs = static_cast<double>(body.springs().size());
    row.case_name = "springs";
    row.variant = "symplectic_euler";
    row.size = n;
    row.elements = springs;
    // The force evaluation alone (gravity and every spring; the step's own evaluation also sums the
    // springs' energies), on the state the steps left: how much of the step is the force pass.
    const core::ParticlePool& particles = body.particles();
    Eigen::Matrix3Xd force(3, particles.position.cols());
    const particle_sim_bench::Timing forces =
        timeSteps([&] { body.computeForces(particles.position, particles.velocity, noGround().gravity, force); }, 5,
                  steps, quick ? 2 : 5);
    std::ostringstream detail;
    detail.precision(3);
    detail << row.timing.min * 1e6 / springs << " ns per spring per step (min); the force evaluation alone "
           << forces.min * 1e6 / springs << " ns per spring (min)";
    row.detail = detail.str() + (row.detail.empty() ? "" : "; " + row.detail);
    writeRow(out, row);
  }
  writeRoofRow(out, "springs", "triad bandwidth", triad.best() / 1e9,
               "the best of " + std::to_string(triad.passes()) + " passes of a[i] = b[i] + s c[i] over 3 arrays of " +
                   std::to_string(triad.megabytes()) + " MB, before the springs' repeats and between them");
}

// What two threads can get from this machine at the time: the rate of a kernel run on two threads
// at once against one thread running it alone (2: two whole cores). A virtual machine's two vCPUs
// may share a physical core, or wait for the host, at some hours and not at others; then no
// program's two threads do better than this. The two threads start their passes together (the
// other thread signals that it runs, then both go), and two threads' rate is twice the slower one's:
// the work of both over the time both took. Best of `repeats`, one thread and two in turn.
template <class Pass>  // double pass(int thread): one pass of the kernel on that thread's data, its rate
double twoThreadRatio(int repeats, Pass pass)
{
  double one = 0.0, two = 0.0;
  for (int r = 0; r < repeats; ++r)
  {
    one = std::max(one, pass(0));
    double other_rate = 0.0;
    std::atomic<bool> other_running{false}, go{false};
    std::thread other([&] {
      other_running.store(true, std::memory_order_release);
      while (!go.load(std::memory_order_acquire))
      {}
      other_rate = pass(1);
    });
    while (!other_running.load(std::memory_order_acquire))
      std::this_thread::yield();
    go.store(true, std::memory_order_release);
    const double rate = pass(0);
    other.join();
    two = std::max(two, 2.0 * std::min(rate, other_rate));
  }
  return two / one;
}

// The first two CPUs the calling thread may use, and all of them (to give back after holding it on
// one); false with fewer than two.
bool firstTwoCpus(cpu_set_t& allowed, int (&cpus)[2])
{
  if (pthread_getaffinity_np(pthread_self(), sizeof(allowed), &allowed) != 0 || CPU_COUNT(&allowed) < 2) return false;
  cpus[0] = cpus[1] = -1;
  for (int cpu = 0, found = 0; cpu < CPU_SETSIZE && found < 2; ++cpu)
    if (CPU_ISSET(cpu, &allowed)) cpus[found++] = cpu;
  return true;
}

// Holds the calling thread on `cpu`; false when it cannot be.
bool holdOn(int cpu)
{
  cpu_set_t one;
  CPU_ZERO(&one);
  CPU_SET(cpu, &one);
  return pthread_setaffinity_np(pthread_self(), sizeof(one), &one) == 0;
}

// How evenly the host runs the first two vCPUs at the time: the rate of `pass` (one pass, its rate)
// on each alone, this thread held on one and then the other (the best of `repeats` on each, in
// turn), the slower's over the faster's (1: even). When one vCPU shares its physical core with
// another guest's work, a loop cut in equal halves waits for it: two threads are then at most
// twice this against one thread on the faster. NaN with fewer than two CPUs, or when the thread
// cannot be held on one.
template <class Pass>
double vcpuBalance(int repeats, Pass pass)
{
  cpu_set_t allowed;
  int cpus[2];
  if (!firstTwoCpus(allowed, cpus)) return std::numeric_limits<double>::quiet_NaN();
  double best[2] = {0.0, 0.0};
  bool held = true;
  for (int r = 0; r < repeats && held; ++r)
    for (int c = 0; c < 2 && held; ++c)
    {
      held = holdOn(cpus[c]);
      if (held) best[c] = std::max(best[c], pass());
    }
  pthread_setaffinity_np(pthread_self(), sizeof(allowed), &allowed);
  if (!held) return std::numeric_limits<double>::quiet_NaN();
  return std::min(best[0], best[1]) / std::max(best[0], best[1]);
}

// How long a write on one thread takes to be seen by another and answered [ns]: a cache line passed
// back and forth between two threads, the mean round trip. Between two cores that share a cache it
// is some 100 ns; it grows when the host puts the two vCPUs farther apart, and with it the cost of
// every loop the threads share. Each thread is held on a CPU of its own (the first two the process
// may use), so that the scheduler cannot put them on one CPU; the caller's CPUs are given back after.
// The clock starts after the other thread is held and one round trip has gone by. NaN with fewer
// than two CPUs, or when a thread cannot be held on its CPU.
double roundTripNanoseconds(int round_trips)
{
  cpu_set_t allowed;
  int cpus[2];
  if (!firstTwoCpus(allowed, cpus)) return std::numeric_limits<double>::quiet_NaN();
  const double not_measured = std::numeric_limits<double>::quiet_NaN();
  if (!holdOn(cpus[0]))
  {
    pthread_setaffinity_np(pthread_self(), sizeof(allowed), &allowed);
    return not_measured;
  }
  alignas(64) std::atomic<int> turn{0};
  std::atomic<int> held{0};  // the other thread: 1 once held on its CPU, -1 if it cannot be
  std::thread other([&] {
    held.store(holdOn(cpus[1]) ? 1 : -1, std::memory_order_release);
    if (held.load(std::memory_order_relaxed) != 1) return;
    for (int i = 0; i <= round_trips; ++i)
    {
      while (turn.load(std::memory_order_acquire) != 2 * i + 1)
      {}
      turn.store(2 * i + 2, std::memory_order_release);
    }
  });
  while (held.load(std::memory_order_acquire) == 0)
    std::this_thread::yield();  // the other thread starts on this CPU, until it holds on to its own
  double seconds = not_measured;
  if (held.load(std::memory_order_relaxed) == 1)
  {
    auto start = Clock::now();
    for (int i = 0; i <= round_trips; ++i)
    {
      if (i == 1) start = Clock::now();  // round trip 0 is the warm-up
      turn.store(2 * i + 1, std::memory_order_release);
      while (turn.load(std::memory_order_acquire) != 2 * i + 2)
      {}
    }
    seconds = std::chrono::duration<double>(Clock::now() - start).count();
  }
  other.join();
  pthread_setaffinity_np(pthread_self(), sizeof(allowed), &allowed);
  return seconds * 1e9 / round_trips;
}

// The ceiling's kernels: the arithmetic roof's chains (the cores' own arithmetic), the triad over
// arrays of their own per thread (memory), and the round trip between the threads, as rows of case
// "ceiling".
void writeTwoThreadCeiling(std::ostream& out, bool quick, const char* when)
{
  const int repeats = quick ? 2 : 5;
  const double arithmetic =
      twoThreadRatio(repeats, [quick](int thread) { return arithmeticPass(quick ? 1000000 : 5000000, thread); });
  Triad triads[2] = {Triad(true), Triad(true)};
  const double memory = twoThreadRatio(repeats, [&triads](int thread) { return triads[thread].pass(); });
  const std::string detail = std::string("two threads at once against one alone, ") + when +
                             " the threads case (2 = two whole cores), the best of " + std::to_string(repeats);
  writeRoofRow(out, "ceiling", std::string("arithmetic ") + when, arithmetic, detail);
  writeRoofRow(out, "ceiling", std::string("triad ") + when, memory,
               detail + "; " + std::to_string(triads[0].megabytes()) + " MB arrays");
  double round_trip = roundTripNanoseconds(quick ? 20000 : 200000);
  for (int r = 1; r < repeats; ++r)
    round_trip = std::min(round_trip, roundTripNanoseconds(quick ? 20000 : 200000));
  writeRoofRow(out, "ceiling", std::string("round trip ") + when, round_trip,
               std::string("ns for a cache line to go from one thread to the other and back, ") + when +
                   " the threads case, the least of " + std::to_string(repeats));
  // The threads case's 128² cloth by symplectic Euler, on one thread (its steps, 0.5 ms each on this
  // machine, showed one vCPU 1.4 times as slow as the other at some hours).
  core::ClothGridDef cloth = squareCloth(quick ? 32 : 128, core::LinearSolverType::Auto);
  cloth.integrator.type = core::kSymplecticEulerIntegrator;
  cloth.integrator.max_substeps = 1;
  core::SpringNetworkBody body(core::buildClothGrid(cloth));
  const double dt = 0.5 * 2.0 / body.frequencyBound();
  const core::Environment env = noGround();
  const double balance = vcpuBalance(repeats, [&] { return 1.0 / timeRepeat([&] { body.step(dt, env); }, 200); });
  writeRoofRow(out, "ceiling", std::string("vcpu balance ") + when, balance,
               std::string("the rate of a ") + std::to_string(cloth.nu) + "² cloth's symplectic Euler steps on one " +
                   "thread on the slower of two vCPUs over the faster's, each alone, " + when +
                   " the threads case, the best of " + std::to_string(repeats) + " on each");
}

// --- Two threads (goal 6): squareCloth at 128² and 256² stepped by one thread and by two
// (WorkerPool), each method from rest over the same steps; the two runs must end in the same bits.
// Implicit Euler with CG (relative tolerance 1e-6, as in "Cloth") at 128² only: seconds a step at 256²;
// and with the multigrid, whose passes over a level's nodes the threads share, at both sizes.
// Verlet at dt = 1/60 with the substeps its stability needs (191 at 128²: more than the default
// cap, so `auto` runs implicit Euler there), and symplectic Euler at half its limit (one force
// pass a step, like the explicit springs' case).
void threads(std::ostream& out, bool quick)
{
  writeTwoThreadCeiling(out, quick, "before");
  // One body's steps by one thread and by two, from rest over the same steps: `per_step` is the rough
  // cost of a step in units of one force pass over the n × n particles.
  auto compare = [&](const std::string& name, const core::SpringNetworkDef& net, int n, double dt, double per_step) {
    // The two bodies' repeats alternate (one thread, two threads, one, ...), so that a spell of
    // load on the machine's other core slows both alike rather than one of them.
    core::WorkerPool one_thread(1), two_threads(2);
    core::WorkerPool* pools[2] = {&one_thread, &two_threads};
    std::vector<std::unique_ptr<core::SpringNetworkBody>> bodies;
    for (core::WorkerPool* pool : pools)
    {
      bodies.push_back(std::make_unique<core::SpringNetworkBody>(net));
      bodies.back()->setWorkers(pool);
    }
    // About 2e6 particle-force-passes a repeat (30 steps of a 256² symplectic step, about 0.1 s): with
    // fewer, each repeat's first steps, which find the caches full of the other body's data, weigh on
    // the time (with 4e5, 6 steps, both bodies' 256² symplectic steps took 1.3 to 1.4 times as long).
    const int steps = quick ? 2 : std::max(2, static_cast<int>(2e6 / (static_cast<double>(n) * n * per_step)));
    const int repeats = quick ? 2 : 7;
    const core::Environment env = noGround();
    std::vector<double> per_step_times[2];
    long long iterations[2] = {0, 0}, timed_steps[2] = {0, 0};  // CG iterations over the timed steps
    for (int repeat = -1; repeat < repeats; ++repeat)           // repeat −1: the warm-up steps, untimed
    {
      for (int b = 0; b < 2; ++b)
      {
        const double time = timeRepeat(
            [&] {
              bodies[b]->step(dt, env);
              if (repeat < 0) return;
              iterations[b] += bodies[b]->lastSolve().iterations;
              ++timed_steps[b];
            },
            repeat < 0 ? (quick ? 1 : 2) : steps);
        if (repeat >= 0) per_step_times[b].push_back(time);
      }
    }
    Row rows[2];
    Eigen::Matrix3Xd end_state[2];
    for (int b = 0; b < 2; ++b)
    {
      const core::SpringNetworkBody& body = *bodies[b];
      Row& row = rows[b];
      row.timing = summarize(per_step_times[b]);
      row.iterations = timed_steps[b] > 0 ? static_cast<double>(iterations[b]) / timed_steps[b] : 0.0;
      if (body.frozen()) row.detail = "FROZE: " + body.frozenReason();
      row.case_name = "threads";
      row.variant = name + (b == 0 ? " 1 thread" : " 2 threads");
      row.size = n;
      row.elements = static_cast<double>(n) * n;
      const int count = body.particles().size();
      end_state[b].resize(3, 2 * count);
      end_state[b] << body.particles().position.leftCols(count), body.particles().velocity.leftCols(count);
    }
    const int substeps = bodies[1]->lastSubsteps();
    const bool same = end_state[0].size() == end_state[1].size() &&
                      std::memcmp(end_state[0].data(), end_state[1].data(), sizeof(double) * end_state[0].size()) == 0;
    std::ostringstream detail;
    detail.precision(3);
    detail << rows[0].timing.min / rows[1].timing.min << "x faster than 1 thread (min against min); "
           << (same ? "bit-identical end state" : "END STATE DIFFERS FROM 1 THREAD") << "; " << substeps
           << " substeps a step";
    rows[1].detail = detail.str() + (rows[1].detail.empty() ? "" : "; " + rows[1].detail);
    writeRow(out, rows[0]);
    writeRow(out, rows[1]);
  };
  struct Method
  {
    const char* name;
    core::IntegratorType type;
    core::LinearSolverType solver;
  };
  for (const Method& method :
       {Method{"verlet", core::kVerletIntegrator, core::LinearSolverType::Auto},
        Method{"symplectic_euler", core::kSymplecticEulerIntegrator, core::LinearSolverType::Auto},
        Method{"implicit_euler cg", core::kImplicitEulerIntegrator, core::LinearSolverType::ConjugateGradient},
        Method{"implicit_euler multigrid", core::kImplicitEulerIntegrator, core::LinearSolverType::Multigrid}})
  {
    for (int n : quick ? std::vector<int>{128} : std::vector<int>{128, 256})
    {
      const bool verlet = method.type == core::kVerletIntegrator;
      const bool implicit = method.type == core::kImplicitEulerIntegrator;
      // Block Jacobi's CG takes seconds a step at 256² (its iterations grow with n; the multigrid's
      // hardly do).
      if (method.solver == core::LinearSolverType::ConjugateGradient && n > 128) continue;
      core::ClothGridDef def = squareCloth(n, method.solver);
      def.integrator.type = method.type;
      def.integrator.max_substeps = verlet ? 100000 : 1;
      const core::SpringNetworkDef net = core::buildClothGrid(def);
      const double dt = verlet || implicit ? 1.0 / 60.0 : 0.5 * 2.0 / core::SpringNetworkBody(net).frequencyBound();
      compare(method.name, net, n, dt, verlet || implicit ? 1e3 : 1.0);
    }
  }
  // hang64 by the direct solver at dt = 1/60 (goal 1's case): the factorization's two shares of
  // subtrees at once (README, "Or directly").
  core::SpringNetworkDef hang64 = particle_sim_bench::hang64(64);
  hang64.integrator.type = core::kImplicitEulerIntegrator;
  hang64.integrator.linear_solver = core::LinearSolverType::Direct;
  compare("implicit_euler direct hang64", hang64, 64, 1.0 / 60.0, 25.0);
  writeTwoThreadCeiling(out, quick, "after");
}

// --- Self-collision (issue 15): what the collision pass costs beside the rest of the step. The
// bodies are stepped as World::step steps them, then SelfCollisionSolver::resolve runs over them;
// each part is timed on its own (steady_clock), so the pass's share is measured on the same
// trajectory.
struct CollisionScene
{
  std::string variant;
  core::Environment env;
  std::vector<core::SpringNetworkDef> bodies;
  double dt;
  int warmup, steps, repeats;
};

// A free 1 m square spring cloth of n × n particles (squareCloth's springs, no pins, 1 kg; implicit
// Euler with the default stopping rule), horizontal at height z, colliding with itself (thickness
// 5 mm, under half its edge at 64²).
core::SpringNetworkDef collidingCloth(int n, double z)
{
  core::ClothGridDef def = squareCloth(n, core::LinearSolverType::Auto);
  def.named_pins.clear();
  def.integrator = core::BodyIntegratorDef{};  // implicit Euler, the default stopping rule
  def.integrator.type = core::kImplicitEulerIntegrator;
  def.origin = Eigen::Vector3d(-0.5, -0.5, z);
  def.contact_thickness = 0.004;
  core::SpringNetworkDef network = core::buildClothGrid(def);
  network.self_collision = core::SelfCollisionDef{true, 0.005};
  return network;
}

void selfCollision(std::ostream& out, bool quick)
{
  std::vector<CollisionScene> scenes;
  core::Environment falling = noGround();
  // A 64² cloth falling freely: no pair within reach, the pass is its broad phase alone.
  scenes.push_back(
      {"cloth 64 falling", falling, {collidingCloth(64, 3.0)}, 1.0 / 60.0, 3, quick ? 3 : 10, quick ? 1 : 3});
  // The same cloth dropped onto a sphere of radius 0.25 m and draped over it onto the ground, timed
  // from 1.2 s on (its folds do not come within the thickness of each other then).
  core::Environment draped;
  draped.ground.enabled = true;
  draped.spheres.push_back(core::SphereColliderDef{"ball", Eigen::Vector3d(0.0, 0.0, 0.3), 0.25, {}});
  scenes.push_back({"cloth 64 draped on a sphere",
                    draped,
                    {collidingCloth(64, 0.7)},
                    1.0 / 60.0,
                    quick ? 10 : 72,
                    quick ? 3 : 20,
                    quick ? 1 : 3});
  // The same cloth folded in half on the ground as the self-collision tests fold theirs (its upper
  // half 5 cm above its lower half, joined by a half-circle crease; folding keeps the springs' rest
  // lengths), dropped on itself: timed from 0.2 s on, while its upper half lies on its lower half.
  core::Environment ground;
  ground.ground.enabled = true;
  core::SpringNetworkDef folded = collidingCloth(64, 0.0);
  folded.positions = particle_sim_test::foldedCloth("fold", 64, 1.0, 0.05, 0.0, 0.005).positions;
  scenes.push_back(
      {"cloth 64 folded onto itself", ground, {folded}, 1.0 / 60.0, quick ? 6 : 12, quick ? 3 : 20, quick ? 1 : 3});
  // As config/scenes/cloth_pile.yaml: five 17 × 17 cloths, 0.7 m, 5 cm apart and turned 9° each, on
  // the same sphere; timed from 0.5 s on, while they land on each other.
  std::vector<core::SpringNetworkDef> pile;
  for (int k = 0; k < 5; ++k)
    pile.push_back(particle_sim_test::clothPileLayer(k));
  scenes.push_back({"pile of five 17 cloths", draped, pile, 0.005, quick ? 20 : 100, quick ? 10 : 40, quick ? 1 : 3});

  for (const CollisionScene& scene : scenes)
  {
    std::vector<std::unique_ptr<core::SpringNetworkBody>> owned;
    std::vector<core::SpringNetworkBody*> bodies;
    std::vector<int> report_index;
    for (const core::SpringNetworkDef& def : scene.bodies)
    {
      owned.push_back(std::make_unique<core::SpringNetworkBody>(def));
      bodies.push_back(owned.back().get());
      report_index.push_back(static_cast<int>(report_index.size()));
    }
    core::SelfCollisionSolver solver;
    core::CollisionReport report;
    report.bodies.resize(bodies.size());
    double pass_seconds = 0.0, rest_seconds = 0.0;
    long long timed = 0, contacts = 0, collisions = 0, passes = 0, searches = 0;
    bool counting = false;
    const auto step = [&] {
      const auto start = Clock::now();
      for (core::SpringNetworkBody* body : bodies)
        body->step(scene.dt, scene.env);
      const auto stepped = Clock::now();
      solver.resolve(scene.dt, bodies, report_index, report);
      if (!counting) return;
      pass_seconds += std::chrono::duration<double>(Clock::now() - stepped).count();
      rest_seconds += std::chrono::duration<double>(stepped - start).count();
      contacts += report.total.proximity_pairs;
      collisions += report.total.collisions;
      passes += report.passes;
      searches += report.searches;
      ++timed;
    };
    for (int i = 0; i < scene.warmup; ++i)
      step();
    counting = true;
    Row row;
    row.timing = timeSteps(step, 0, scene.steps, scene.repeats);
    row.case_name = "selfcollision";
    row.variant = scene.variant;
    row.size = static_cast<double>(bodies.size());
    for (const core::SpringNetworkBody* body : bodies)
      row.elements += body->particles().size();
    std::ostringstream detail;
    detail.precision(3);
    detail << "pass " << 1e3 * pass_seconds / timed << " ms per step, "
           << 100.0 * pass_seconds / (pass_seconds + rest_seconds) << " % of the step, " << pass_seconds / rest_seconds
           << "x the rest; per step " << double(contacts) / timed << " proximity pairs, " << double(collisions) / timed
           << " collisions, " << double(passes) / timed << " passes, " << double(searches) / timed
           << " candidate searches";
    row.detail = detail.str();
    for (const core::SpringNetworkBody* body : bodies)
      if (body->frozen()) row.detail += "; FROZE: " + body->frozenReason();
    writeRow(out, row);
  }
}

// --- Emitters: a fountain holding N live particles (rate N / lifetime), stepped at dt = 1/60.
void emitters(std::ostream& out, bool quick)
{
  for (int n : quick ? std::vector<int>{1000, 100000} : std::vector<int>{1000, 10000, 100000, 1000000})
  {
    core::WorldDef world_def;
    world_def.dt = 1.0 / 60.0;
    world_def.threads = 1;  // the throughput of one core
    world_def.max_particles_per_body = n;
    world_def.max_particles_per_world = n;
    core::World world(world_def);
    core::EmitterDef fountain;
    fountain.name = "fountain";
    fountain.max_particles = n;
    fountain.lifetime = 2.0;
    fountain.rate = n / fountain.lifetime;
    if (core::Status s = world.addEmitter(fountain); !s)
    {
      std::cerr << "emitter of " << n << ": " << s.message << "\n";
      continue;
    }
    Row row;
    row.timing = timeSteps([&] { world.step(); }, 150, quick ? 10 : std::max(10, 20000000 / n), quick ? 2 : 5);
    row.case_name = "emitters";
    row.variant = "fountain";
    row.size = n;
    row.elements = world.particleCount();
    std::ostringstream detail;
    detail.precision(3);
    detail << world.particleCount() / (row.timing.min * 1e-3) / 1e6 << " M particle-steps/s (min time)";
    row.detail = detail.str();
    writeRow(out, row);
  }
}
}  // namespace

int main(int argc, char** argv)
{
  particle_sim::process::restartWithHugePagesIfAdvised(argv);
  particle_sim_bench::Options options;
  options.out_path = "performance.csv";
  if (const int code = particle_sim_bench::parseOptions(argc, argv, kUsage, options); code >= 0) return code;
  const std::string& out_path = options.out_path;
  const bool quick = options.quick;
  std::ofstream out(out_path);
  if (!out)
  {
    std::cerr << "particle_sim_perf: cannot write " << out_path << "\n";
    return 1;
  }
  out << particle_sim_bench::kCsvHeader;
  particle_sim_bench::writePagesRow(out, "particle_sim_perf", particle_sim::process::hugePagesReport());
  auto wanted = [&options](const char* name) { return options.wanted(name); };
  if (wanted("rope")) ropes(out, quick);
  if (wanted("cloth")) cloths(out, quick);
  if (wanted("sizes")) sizesSideBySide(out, quick);
  if (wanted("hang64")) hang(out, quick);
  if (wanted("auto")) autoSideBySide(out, quick);
  if (wanted("stopping")) stoppingRule(out, quick);
  if (wanted("springs")) explicitSprings(out, quick);
  if (wanted("emitters")) emitters(out, quick);
  if (wanted("selfcollision")) selfCollision(out, quick);
  if (wanted("threads")) threads(out, quick);
  return 0;
}
