#pragma once

#include <optional>
#include <string>

#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// Which time integrator a spring body uses (chosen per body): one of the methods registered in
/// integrators/registry.cpp, or `auto`. A method is named by the address of its `kName`, an inline
/// static constexpr member and so one object in the whole program: the registry is the one
/// source of integrator identity, and a new method needs no constant here. The built-in methods'
/// constants live with each method (e.g. kVerletIntegrator in integrators/verlet.h); `auto` is
/// kAutoIntegrator below. toString(), parseIntegratorType(), integratorTypeNames(),
/// stabilityLimit() and isImplicit() read the registry.
class IntegratorType
{
public:
  /// The built-in default method of a body that sets none in a world that sets none: implicit Euler.
  IntegratorType();

  /// The method `Method` (a class declaring `static constexpr const char* kName`).
  template <class Method>
  static constexpr IntegratorType of()
  {
    return IntegratorType(&Method::kName);
  }

  /// The method's registered name ("verlet", ...), or "auto".
  const char* name() const { return *name_; }

  friend constexpr bool operator==(IntegratorType a, IntegratorType b) { return a.name_ == b.name_; }
  friend constexpr bool operator!=(IntegratorType a, IntegratorType b) { return a.name_ != b.name_; }

private:
  constexpr explicit IntegratorType(const char* const* name) : name_(name) {}
  const char* const* name_;  // &Method::kName
};

/// `auto`: not a method but a policy that picks one per body and step: Verlet where its stability
/// bound holds with margin, else implicit Euler (integrators/stability_guard.h).
struct AutoIntegratorPolicy
{
  static constexpr const char* kName = "auto";
};
inline constexpr IntegratorType kAutoIntegrator = IntegratorType::of<AutoIntegratorPolicy>();

const char* toString(IntegratorType type);
/// Parses a registered name ("symplectic_euler", "verlet", "implicit_euler", "rk4", "bdf2", ...)
/// or "auto"; false when unknown.
bool parseIntegratorType(const std::string& text, IntegratorType& type);
/// "symplectic_euler, verlet, implicit_euler, rk4, bdf2, auto" (every registered name, then auto),
/// for error messages.
std::string integratorTypeNames();

/// How the implicit methods solve their linear system each step.
enum class LinearSolverType
{
  Auto,               ///< the cheapest of the three, from flop counts and the iterations measured (see below)
  ConjugateGradient,  ///< Baraff & Witkin's modified preconditioned conjugate gradient, to cg_velocity_tolerance
                      ///< or cg_tolerance
  Direct,             ///< sparse block L D Lᵀ in a fill-reducing order (exact; O(n) on a rope)
  /// the conjugate gradient of ConjugateGradient (the same stopping rule and cap) preconditioned by
  /// one cycle of smoothed-aggregation multigrid (SmoothedAggregation) instead of block Jacobi:
  /// iterations that hardly grow with the size of a sheet, each dearer; its hierarchy is built anew
  /// each solve
  Multigrid,
};
/// `auto` picks the direct solver when one factorization and solve cost at most this many
/// conjugate-gradient iterations, counted in floating-point operations from the pattern: true of
/// ropes and chains (no fill) and of small sheets. Larger sheets and lattices start with CG, and
/// switch to the direct solver for good once a CG solve takes more iterations than the direct solve
/// costs (stiff sheets at large steps); under `auto` the cap cg_max_iterations stops CG only once it
/// has spent that many too, and a solve stopped there short of both tolerances is solved again
/// directly.
inline constexpr double kDirectSolverCgIterations = 40.0;
/// `auto` tries the multigrid (LinearSolverType::Multigrid) for one solve once a converged CG solve
/// took more than this many iterations while the direct solver was dearer: a sheet whose slow
/// bending and swinging modes block Jacobi needs hundreds of iterations for. It keeps the multigrid
/// for good when that solve cost fewer flops than the CG solve did (its setup, cycles, products and
/// vector passes, counted from the hierarchy's sizes), and otherwise goes back to CG for good; the
/// multigrid kept gives way to the direct solver as CG does, and to CG when a solve stops short.
inline constexpr int kMultigridTrialCgIterations = 100;
/// What a flop of the multigrid's hierarchy (its setup and cycles) costs in flops of CG, in that
/// comparison: its 6x6 blocks, its Galerkin products' scattered sums and its serial setup run at
/// about half the rate of CG's streamed pair product (one thread, spring cloths of 32² to 96² at
/// dt = 1/60: at 32² and 48² CG is the faster, 1.3x; at 64² the two tie; from 96² on the multigrid
/// is the faster, README "Or by multigrid"). The cycle's smoothings and residuals on the finest
/// level (SmoothedAggregation::finestCycleFlops()), block-diagonal products and CG's own product,
/// count as CG's flops.
inline constexpr double kMultigridFlopWeight = 2.0;

/// "auto", "cg", "direct", "multigrid".
const char* toString(LinearSolverType type);
/// Parses "auto", "cg", "direct" or "multigrid"; false when unknown.
bool parseLinearSolverType(const std::string& text, LinearSolverType& type);
/// "auto, cg, direct, multigrid", for error messages.
const char* linearSolverTypeNames();

/// An integrator and its settings, with defaults.
struct IntegratorDef
{
  IntegratorType type;          ///< default: implicit Euler
  double verlet_damping = 1.0;  ///< the lecture's Verlet k_d in [0, 1]: 1 = no damping, below 1 damps
  double cg_tolerance = 1e-8;   ///< implicit Euler: stop when |r| <= tolerance |b| (filtered residuals), > 0
  /// Implicit methods: CG also stops when the bound on the new velocities' mass-weighted RMS error
  /// (SolverReport::velocity_error) is at most this [m/s], in [0, 1]; 0 leaves only cg_tolerance.
  /// An error of τ m/s a step moves the body's mass-weighted RMS position (so its centre of mass) by
  /// at most τ metres a simulated second; one light particle can be off by more. Unlike
  /// |r| <= tolerance |b|, which asks for the same relative accuracy of an ever smaller change as a
  /// body comes to rest (as many iterations at rest as in motion), it does not depend on how large
  /// this step's change happens to be.
  double cg_velocity_tolerance = 1e-5;
  /// Implicit Euler: iteration cap, >= 1 (under `auto`, CG may go past it up to as many iterations as
  /// the direct solve costs).
  int cg_max_iterations = 500;
  int max_substeps = 64;  ///< explicit methods: most substeps a step may be split into to stay stable, >= 1
  LinearSolverType linear_solver = LinearSolverType::Auto;  ///< implicit methods: how each step's system is solved
};

/// The integrator settings of a body definition (RopeDef, ClothGridDef, MeshClothDef, JellyDef,
/// SpringNetworkDef): only what the body sets. Every field left empty comes from the world's
/// default (WorldDef::integrator) when the body is added to a World, or from IntegratorDef's
/// built-in defaults for a body built without one; so `rope.integrator.type = kVerletIntegrator;`
/// keeps the world's cg_tolerance. The fields' meaning and ranges are IntegratorDef's.
struct BodyIntegratorDef
{
  std::optional<IntegratorType> type;
  std::optional<double> verlet_damping;
  std::optional<double> cg_tolerance;
  std::optional<double> cg_velocity_tolerance;
  std::optional<int> cg_max_iterations;
  std::optional<int> max_substeps;
  std::optional<LinearSolverType> linear_solver;
};

/// `defaults` with every field that `body` sets taken from `body`.
IntegratorDef resolve(const BodyIntegratorDef& body, const IntegratorDef& defaults = IntegratorDef());
/// Settings that set every field to `def`'s.
BodyIntegratorDef settingEveryField(const IntegratorDef& def);

/// The stability limit h·ω of a method on an undamped oscillator of frequency ω, as the method
/// declares it (integrators/registry.h): 2 for symplectic Euler and Verlet, 2√2 for RK4, infinite
/// for implicit Euler (and for `auto`, which picks a stable method).
double stabilityLimit(IntegratorType type);
/// True for a method that solves a linear system each step (implicit Euler); false for explicit
/// methods and for `auto`, which is not a method (ask the body which method ran).
bool isImplicit(IntegratorType type);

Status validate(const IntegratorDef& def);
/// Checks the fields `def` sets, with validate(IntegratorDef)'s messages.
Status validate(const BodyIntegratorDef& def);

/// What the last implicit solve did (zero iterations for the explicit methods).
struct SolverReport
{
  bool direct = false;             ///< the direct solver factorized and solved (CG iterations may follow it, to polish)
  bool multigrid = false;          ///< CG was preconditioned by the multigrid (LinearSolverType::Multigrid)
  int iterations = 0;              ///< conjugate-gradient iterations
  double relative_residual = 0.0;  ///< |r| / |b| at the end
  /// [m/s] sqrt(Σ |r_i|² / m_i / Σ m_i) over the free particles at the end: a bound on the mass-weighted
  /// RMS error of the new velocities, rigorous while every force's Jacobian is negative semi-definite
  /// (then the system A = M − h ∂f/∂v − h² ∂f/∂x is at least M, and |A⁻¹ r|_M <= |r|_M⁻¹). It is
  /// the error of the last linear solve (after implicit Euler's Newton corrections, of the last one).
  double velocity_error = 0.0;
  bool converged = true;   ///< the residual reached a tolerance within the iteration cap, and the
                           ///< resting contacts' holds settled within kMaxContactSolves
  int contact_solves = 1;  ///< linear solves of the step (more than one when contact holds were revised)
  bool breakdown = false;  ///< CG met a direction of non-positive (or NaN) curvature: the solve failed
};

}  // namespace core
}  // namespace particle_sim
