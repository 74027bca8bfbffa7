// Every vectorized pass of the core (AVX2 and AVX-512), as plain code calls it, returns with the upper
// halves of the vector registers cleared (VZEROUPPER), on every path, its scalar tails included, in
// every build (core::clearUpperHalves()). Left set, they slow the plain SSE instructions that follow
// on the same thread until the next clearing: on the AMD EPYC host of 2026-12-07 the multigrid's
// Galerkin products took about three times as long after a Jacobian pass that returned through its
// scalar tail without it; and the sanitizer build (-O1, where GCC inserts no clearing of its own)
// left every pass without one (README, "The vector passes leave the vector registers clean"). The
// processor says whether the upper halves are in use: XGETBV with ECX = 1 (XINUSE), bit 2, set by
// any 256-bit write and cleared by VZEROUPPER. A processor that runs the passes must be able to say
// so (the tests fail otherwise); one without AVX2 runs none of them.

#if defined(__x86_64__)  // the vector passes and XGETBV are x86-64's
#include <cpuid.h>
#include <gtest/gtest.h>
#include <immintrin.h>

#include <array>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/environment.h"
#include "particle_sim/core/integrators/cg_avx2.h"
#include "particle_sim/core/integrators/dense_panel.h"
#include "particle_sim/core/integrators/padded_vectors.h"
#include "particle_sim/core/spring.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/vector_registers.h"
#include "particle_sim/core/worker_pool.h"

namespace core = particle_sim::core;

namespace
{
__attribute__((target("xsave"))) bool upperHalvesInUse()
{
  return (_xgetbv(1) & (1u << 2)) != 0;
}

// A 256-bit register written and left so: in a function not compiled for AVX, which the compiler
// therefore never clears after (it does after its own AVX functions, even around such an asm).
void setUpperHalves()
{
  asm volatile("vpcmpeqd %%ymm7, %%ymm7, %%ymm7" ::: "xmm7");
}

// Whether the processor can tell the state: XGETBV with ECX = 1 (CPUID leaf 0xD, sub-leaf 1, EAX
// bit 2), whose bit 2 is seen to follow a 256-bit write and its clearing here.
bool canTell()
{
  static const bool can = [] {
    unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
    if (!__get_cpuid_count(0xD, 1, &eax, &ebx, &ecx, &edx) || (eax & (1u << 2)) == 0) return false;
    core::clearUpperHalves();
    const bool clear_before = !upperHalvesInUse();
    setUpperHalves();
    const bool set = upperHalvesInUse();
    core::clearUpperHalves();
    return clear_before && set && !upperHalvesInUse();
  }();
  return can;
}

// Whether the vector passes run on this processor (AVX2, and FMA for the dense tiles). Where they
// run, the processor must be able to tell the state (a failure otherwise, not a skip). Where they do
// not, no family of passes may claim to run its vector form, and then none can leave the state set.
bool vectorPassesRun()
{
  if (!core::springPartsVectorized())
  {
    EXPECT_FALSE(core::cg_avx2::available()) << "CG's AVX2 passes run without AVX2";
    EXPECT_FALSE(core::dense_panel::available()) << "the dense AVX2 tiles run without AVX2";
    return false;
  }
  EXPECT_TRUE(core::cg_avx2::available());
  EXPECT_TRUE(core::dense_panel::available()) << "AVX2 without FMA: the dense tiles would run scalar";
  EXPECT_TRUE(canTell()) << "the vector passes run, but XGETBV with ECX = 1 cannot report their state";
  return canTell();
}

// `pass` with the upper halves clear before it; whether they are still clear after it.
void expectLeavesUpperHalvesClear(const std::string& name, const std::function<void()>& pass)
{
  core::clearUpperHalves();
  ASSERT_FALSE(upperHalvesInUse()) << "cleared before " << name;
  pass();
  EXPECT_FALSE(upperHalvesInUse()) << name << " returned with the upper halves of the vector registers set";
}

std::vector<double> randomNumbers(std::size_t count, std::mt19937& random)
{
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<double> numbers(count);
  for (double& n : numbers)
    n = uniform(random);
  return numbers;
}
}  // namespace

TEST(VectorState, EverySpringPassReturnsWithTheUpperHalvesClear)
{
  if (!vectorPassesRun()) return;
  // Springs among 12 particles, every count from 1 to 13 (whole fours, and tails of one to three;
  // below four no 256-bit register is written), in three layouts: each spring with an end i of its
  // own; runs of three springs that share end i, as a cloth's list has them; and the first layout
  // with every fourth spring between two particles at one place (a four with a zero length takes the
  // scalar form inside the vector loop).
  std::mt19937 random(7);
  const int particles = 12;
  std::vector<double> x = randomNumbers(3 * particles, random);
  const std::vector<double> v = randomNumbers(3 * particles, random);
  for (int k = 0; k < 3; ++k)
    x[3 + k] = x[k];  // particles 0 and 1 at one place
  enum class Layout
  {
    Scattered,
    Runs,
    Coincident
  };
  for (const Layout layout : {Layout::Scattered, Layout::Runs, Layout::Coincident})
    for (int count = 1; count <= 13; ++count)
    {
      std::vector<core::Spring> springs;
      for (int s = 0; s < count; ++s)
      {
        core::Spring spring;
        spring.i = layout == Layout::Runs ? s / 3 : s % particles;
        spring.j = layout == Layout::Runs ? s / 3 + 1 + s % 3 : (s * 5 + 1) % particles;
        if (layout == Layout::Coincident && s % 4 == 1)
        {
          spring.i = 0;
          spring.j = 1;
        }
        spring.rest_length = 0.1;
        spring.stiffness = 100.0;
        spring.damping = 0.1;
        springs.push_back(spring);
      }
      const std::string what = std::to_string(count) + (layout == Layout::Runs         ? " springs in runs"
                                                        : layout == Layout::Coincident ? " springs, some of zero length"
                                                                                       : " springs");
      std::vector<double> force(3 * particles, 0.0), energy(count, 0.0);
      for (bool add_i : {true, false})
        for (bool add_j : {true, false})
        {
          if (!add_i && !add_j) continue;
          for (bool with_energy : {true, false})
            expectLeavesUpperHalvesClear("addSpringForcesOf(" + what + ", add_i " + std::to_string(add_i) + ", add_j " +
                                             std::to_string(add_j) + ", energy " + std::to_string(with_energy) + ")",
                                         [&] {
                                           double energy_sum = 0.0;
                                           core::addSpringForcesOf(
                                               springs.data(), springs.data() + count, x.data(), v.data(), force.data(),
                                               with_energy ? energy.data() : nullptr,
                                               with_energy ? &energy_sum : nullptr, add_i, add_j, true);
                                         });
        }
      core::SpringJacobianParts parts;
      parts.resize(springs.size());
      expectLeavesUpperHalvesClear("springJacobianPartsOf(" + what + ")", [&] {
        core::springJacobianPartsOf(springs.data(), 0, count, x.data(), true, parts);
      });
    }
}

TEST(VectorState, EveryConjugateGradientPassReturnsWithTheUpperHalvesClear)
{
  if (!vectorPassesRun()) return;
  std::mt19937 random(11);
  const int rows = 11;
  // The passes' vectors are padded and aligned (PaddedVectors), as the solver's are.
  auto vectors = [&] {
    core::PaddedVectors v;
    v.setZero(rows);
    const std::vector<double> numbers = randomNumbers(3 * rows, random);
    for (int i = 0; i < rows; ++i)
      v.col(i) = Eigen::Vector3d(numbers[3 * i], numbers[3 * i + 1], numbers[3 * i + 2]);
    return v;
  };
  core::PaddedVectors p = vectors(), out = vectors(), direction = vectors(), product = vectors(), delta_v = vectors(),
                      residual = vectors(), preconditioned = vectors();
  const std::vector<double> scale = randomNumbers(rows, random), inverse_mass(rows, 2.0);
  std::vector<Eigen::Matrix3d> inverse_diagonal(rows, Eigen::Matrix3d::Identity());
  std::vector<char> pinned(rows, 0);
  pinned[3] = 1;
  // Pairs for every range below (the last ends at 10), in two lists: each pair with an end i of its
  // own, and runs of two pairs that share end i (held in a register between them).
  std::vector<std::array<int, 2>> ends, shared_ends;
  std::vector<std::array<double, 6>> cs;
  for (int k = 0; k < 10; ++k)
  {
    ends.push_back({k, (k + 2) % rows});
    shared_ends.push_back({k / 2, (k / 2 + 1 + k % 2) % rows});
    cs.push_back({1.0, 0.1, 0.2, 1.0, 0.3, 1.0});
  }
  for (int first : {0, 1})
    for (int last : {first + 4, first + 5, first + 9})
    {
      const std::string range = "[" + std::to_string(first) + ", " + std::to_string(last) + ")";
      for (const auto* list : {&ends, &shared_ends})
        for (bool add_i : {true, false})
          for (bool add_j : {true, false})
            expectLeavesUpperHalvesClear("addPairProducts" + range + (list == &ends ? "" : ", ends i shared") +
                                             ", add_i " + std::to_string(add_i) + ", add_j " + std::to_string(add_j),
                                         [&] {
                                           core::cg_avx2::addPairProducts(add_i, add_j, list->data(), cs.data(), first,
                                                                          last, p.data(), out.data());
                                         });
      expectLeavesUpperHalvesClear("scaleRows" + range,
                                   [&] { core::cg_avx2::scaleRows(scale.data(), first, last, p.data(), out.data()); });
      expectLeavesUpperHalvesClear("curvature" + range, [&] {
        core::cg_avx2::curvature(pinned.data(), first, last, direction.data(), product.data());
      });
      expectLeavesUpperHalvesClear("updateIterate" + range, [&] {
        core::cg_avx2::updateIterate(first, last, 0.5, inverse_mass.data(), inverse_diagonal.data(), direction.data(),
                                     product.data(), delta_v.data(), residual.data(), preconditioned.data());
      });
      expectLeavesUpperHalvesClear("updateDirection" + range, [&] {
        core::cg_avx2::updateDirection(pinned.data(), first, last, 0.5, preconditioned.data(), direction.data());
      });
    }
}

TEST(VectorState, EveryDensePanelKernelReturnsWithTheUpperHalvesClear)
{
  if (!vectorPassesRun()) return;
  std::mt19937 random(13);
  for (int n : {3, 4, 7, 17, 21, 40})
  {
    const int k = 5, columns = 6;
    const std::vector<double> t = randomNumbers(static_cast<std::size_t>(n) * k, random),
                              l = randomNumbers(static_cast<std::size_t>(columns) * k, random),
                              panel = randomNumbers(static_cast<std::size_t>(n) * columns, random),
                              factors = randomNumbers(columns, random), x = randomNumbers(n, random);
    std::vector<double> out = randomNumbers(n, random), kept(n, 0.0), dots(columns, 0.0);
    const std::string size = "(n = " + std::to_string(n) + ")";
    // C's rows one after the other (a dense C), and scattered over a taller C (a supernode's update
    // of the panels above it: the tiles' gathers and scatters, or their entry-by-entry form).
    for (const bool scattered : {false, true})
    {
      std::vector<int> row_offset(n);
      for (int i = 0; i < n; ++i)
        row_offset[i] = scattered ? i + i / 5 : i;
      const long height = row_offset[n - 1] + 1;
      std::vector<long> column_offset(columns);
      for (int j = 0; j < columns; ++j)
        column_offset[j] = static_cast<long>(j) * height;
      std::vector<double> c(static_cast<std::size_t>(height) * columns, 0.0);
      for (core::dense_panel::Tiles asked : {core::dense_panel::Tiles::Avx2, core::dense_panel::Tiles::Avx512})
      {
        core::dense_panel::Tiles ran = asked;
        expectLeavesUpperHalvesClear(
            std::string("subtractLowerProducts, ") + (scattered ? "scattered rows " : "") + size, [&] {
              ran =
                  core::dense_panel::subtractLowerProducts(asked, n, std::min(n, columns), k, t.data(), n, l.data(),
                                                           columns, row_offset.data(), column_offset.data(), c.data());
            });
        SCOPED_TRACE(ran == core::dense_panel::Tiles::Avx512 ? "AVX-512 tiles ran" : "AVX2 tiles ran");
        EXPECT_NE(ran, core::dense_panel::Tiles::Scalar);
      }
    }
    expectLeavesUpperHalvesClear("subtractScaled" + size,
                                 [&] { core::dense_panel::subtractScaled(true, n, t.data(), 0.5, out.data()); });
    expectLeavesUpperHalvesClear("subtractScaledColumns" + size, [&] {
      core::dense_panel::subtractScaledColumns(true, n, columns, panel.data(), n, factors.data(), out.data());
    });
    expectLeavesUpperHalvesClear("subtractScaledColumnsKeepAndScale" + size, [&] {
      core::dense_panel::subtractScaledColumnsKeepAndScale(true, n, columns, panel.data(), n, factors.data(), 0.5,
                                                           out.data(), kept.data());
    });
    expectLeavesUpperHalvesClear("dot" + size, [&] { core::dense_panel::dot(true, n, t.data(), x.data()); });
    expectLeavesUpperHalvesClear("dotColumns" + size, [&] {
      core::dense_panel::dotColumns(true, n, columns, panel.data(), n, x.data(), dots.data());
    });
  }
}

TEST(VectorState, AnImplicitStepOfEachLinearSolverEndsWithTheUpperHalvesClear)
{
  // Whole steps, at one thread and at two: the calling thread's state when the step ends, for the
  // plain code after it. This catches a step that ends with the upper halves set; a pass inside the
  // step that leaves them set until a later vector pass clears them (as the Jacobian pass did) only
  // the pass tests above catch.
  if (!vectorPassesRun()) return;
  for (core::LinearSolverType solver :
       {core::LinearSolverType::ConjugateGradient, core::LinearSolverType::Direct, core::LinearSolverType::Multigrid})
    for (int threads : {1, 2})
    {
      core::ClothGridDef def(core::ClothModel::Springs);
      def.nu = def.nv = 24;
      def.named_pins = {"corner_00", "corner_10"};
      def.integrator.type = core::kImplicitEulerIntegrator;
      def.integrator.linear_solver = solver;
      core::SpringNetworkBody body(core::buildClothGrid(def));
      core::WorkerPool workers(threads);
      body.setWorkers(&workers);
      core::Environment environment;
      environment.ground.enabled = false;
      for (int step = 0; step < 3; ++step)
        expectLeavesUpperHalvesClear("step " + std::to_string(step) + " by " + core::toString(solver) + " at " +
                                         std::to_string(threads) + " threads",
                                     [&] { body.step(1.0 / 60.0, environment); });
    }
}
#endif  // defined(__x86_64__)
