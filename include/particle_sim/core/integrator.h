#pragma once

#include <string>

#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// The time integrators a spring body can use (chosen per body). Each is a unit of its own in
/// core/integrators/ and declares its name, order, stability limit and whether it is implicit in
/// the registry (integrators/registry.h), which toString(), parseIntegratorType(),
/// integratorTypeNames() and stabilityLimit() read.
enum class IntegratorType
{
  SymplecticEuler,  ///< the lecture's loop: v += h f/m, then x += h v (first order)
  Verlet,           ///< the lecture's x' = x + k_d (x − x_prev) + h² f/m, second-order start (second order
                    ///< for position-only forces; first order once forces depend on velocity)
  ImplicitEuler,    ///< linearised backward Euler solved by modified preconditioned CG (first order, stable)
  Rk4,              ///< classical Runge–Kutta, the accuracy reference (fourth order)
  Bdf2,             ///< linearised BDF2 (Choi & Ko 2002), solved as implicit Euler is (second order, stable)
  Auto,             ///< per body and step: Verlet where its stability bound holds with margin, else implicit Euler
};

const char* toString(IntegratorType type);
/// Parses a registered name ("symplectic_euler", "verlet", "implicit_euler", "rk4", "bdf2") or "auto";
/// false when unknown.
bool parseIntegratorType(const std::string& text, IntegratorType& type);
/// "symplectic_euler, verlet, implicit_euler, rk4, bdf2, auto", for error messages.
const char* integratorTypeNames();

/// An integrator and its settings, with defaults.
struct IntegratorDef
{
  IntegratorType type = IntegratorType::ImplicitEuler;
  double verlet_damping = 1.0;  ///< the lecture's Verlet k_d in [0, 1]: 1 = no damping, below 1 damps
  double cg_tolerance = 1e-8;   ///< implicit Euler: stop when |r| <= tolerance |b| (filtered residuals), > 0
  int cg_max_iterations = 500;  ///< implicit Euler: iteration cap, >= 1
  int max_substeps = 64;        ///< explicit methods: most substeps a step may be split into to stay stable, >= 1
};

/// The stability limit h·ω of a method on an undamped oscillator of frequency ω, as the method
/// declares it (integrators/registry.h): 2 for symplectic Euler and Verlet, 2√2 for RK4, infinite
/// for implicit Euler (and for `auto`, which picks a stable method).
double stabilityLimit(IntegratorType type);
/// True for a method that solves a linear system each step (implicit Euler); false for explicit
/// methods and for `auto`, which is not a method (ask the body which method ran).
bool isImplicit(IntegratorType type);

Status validate(const IntegratorDef& def);

/// What the last implicit solve did (zero iterations for the explicit methods).
struct SolverReport
{
  int iterations = 0;
  double relative_residual = 0.0;  ///< |r| / |b| at the end
  bool converged = true;           ///< the residual reached the tolerance within the iteration cap
  bool breakdown = false;          ///< CG met a direction of non-positive (or NaN) curvature: the solve failed
};

}  // namespace core
}  // namespace particle_sim
