#pragma once

#include <Eigen/Core>
#include <optional>
#include <utility>
#include <vector>

#include "particle_sim/core/environment.h"
#include "particle_sim/core/integrators/implicit_euler_solver.h"
#include "particle_sim/core/spring.h"
#include "particle_sim/core/worker_pool.h"

namespace particle_sim
{
namespace core
{
/// What a force element may read besides the state (x, v): the body's particles and the
/// environment of the current step.
struct ForceContext
{
  const Eigen::VectorXd& mass;      ///< [kg] per particle (kept for pinned ones too)
  const std::vector<char>& pinned;  ///< 1 = kinematic particle (no gravity energy)
  Eigen::Vector3d gravity;          ///< [m/s²]
  AirDef air;                       ///< the air of the current step
  double damping = 0.0;             ///< [1/s] global damping of the current step (Environment::damping)
  WorkerPool* workers = nullptr;    ///< threads to share loops with (null: the caller's alone)
};

/// What one tear removed: the particle pairs of the broken springs and the corners of the removed
/// triangles, in the order the elements hold them.
struct TearRecord
{
  std::vector<std::pair<int, int>> springs;
  std::vector<Eigen::Vector3i> triangles;

  void clear()
  {
    springs.clear();
    triangles.clear();
  }
  bool empty() const { return springs.empty() && triangles.empty(); }
};

/// One kind of force acting on a spring body (springs, Baraff–Witkin conditions, air, global
/// damping, gravity). A body is composed of elements and asks each, in a fixed order, for:
/// its forces at (x, v), its Jacobian blocks (pattern bound once), its rows of the stability
/// bound, its potential energy, and the constants that can be set at run time. Every method
/// but addForces() has a "contributes nothing" default.
class ForceElement
{
public:
  virtual ~ForceElement() = default;

  /// force += the element's force on every particle at (x, v) [N].
  virtual void addForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                         Eigen::Matrix3Xd& force) const = 0;
  /// force = 0 + the element's force [N], for the first element of a set: the same bits as zeroing
  /// `force` and calling addForces(), which is what it does unless an element saves that pass.
  virtual void setForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                         Eigen::Matrix3Xd& force) const;

  // Jacobian ------------------------------------------------------------------------------------
  /// Appends the particle pairs the element's Jacobian couples (for the solver's pattern).
  virtual void coupledPairs(std::vector<std::pair<int, int>>& /*pairs*/) const {}
  /// Looks up the element's block indices in `solver`, once, after its pattern is set.
  virtual void bindPattern(const ImplicitEulerSolver& /*solver*/) {}
  /// Adds the blocks ∂f/∂x, ∂f/∂v at positions x, in a form that keeps the implicit system
  /// symmetric positive definite. Nothing for an element the implicit step treats explicitly.
  virtual void addJacobians(const ForceContext& /*context*/, const Eigen::Matrix3Xd& /*x*/,
                            ImplicitEulerSolver& /*solver*/) const
  {}

  // Stability bound -----------------------------------------------------------------------------
  /// Adds the element's Gershgorin rows at the rest positions: k |∂C/∂x_i| Σ_n |∂C/∂x_n| to
  /// stiffness_rows[i] [N/m], alike with damping to damping_rows[i] [N·s/m].
  virtual void addStabilityRows(const std::vector<Eigen::Vector3d>& /*rest*/, std::vector<double>& /*stiffness_rows*/,
                                std::vector<double>& /*damping_rows*/) const
  {}
  /// A damping rate [1/s] equal on every particle, added to the bound after the maximum over rows.
  virtual double uniformDampingRate(const ForceContext& /*context*/) const { return 0.0; }

  // Energy --------------------------------------------------------------------------------------
  /// energy += the element's potential energy at x [J] (nothing for dissipative elements).
  virtual void addEnergy(const ForceContext& /*context*/, const Eigen::Matrix3Xd& /*x*/, double& /*energy*/) const {}
  /// addForces() that may keep, on the way, what addKeptEnergy() then adds: an element whose energy
  /// costs a pass of its own (springs) computes it with its forces. By default, addForces().
  virtual void addForcesKeepingEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                                      Eigen::Matrix3Xd& force) const
  {
    addForces(context, x, v, force);
  }
  /// setForces() that may keep what addKeptEnergy() then adds, as addForcesKeepingEnergy() does. By
  /// default, setForces().
  virtual void setForcesKeepingEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                                      Eigen::Matrix3Xd& force) const
  {
    setForces(context, x, v, force);
  }
  /// addEnergy() at the x of the last addForcesKeepingEnergy() or setForcesKeepingEnergy(), with the
  /// same bits; an element that kept nothing since (the default) computes it now.
  virtual void addKeptEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, double& energy) const
  {
    addEnergy(context, x, energy);
  }
  /// True when the element can do work on the body from outside (wind), so that a step may
  /// rightly gain energy.
  virtual bool suppliesEnergy(const ForceContext& /*context*/) const { return false; }

  // Run-time constants ----------------------------------------------------------------------------
  /// True when the element has stiffness and damping of `spring_class` to set.
  virtual bool hasClass(SpringClass /*spring_class*/) const { return false; }
  /// Sets stiffness and damping of `spring_class` (every class when empty); `stiffness` and
  /// `damping` were validated by the caller.
  virtual void setClassConstants(std::optional<SpringClass> /*spring_class*/, double /*stiffness*/, double /*damping*/)
  {}
  /// Puts back the constants the element was built with.
  virtual void resetConstants() {}

  // Tearing ------------------------------------------------------------------------------------
  /// Removes every part stretched at x past `tear_strain` [-] (> 0) and appends what broke to
  /// `torn`; the rest keep their order. Nothing for an element that cannot tear.
  virtual void tear(const Eigen::Matrix3Xd& /*x*/, double /*tear_strain*/, TearRecord& /*torn*/) {}
  /// The body's surface after a tear (elements that act on the surface triangles keep only these).
  virtual void setSurface(const std::vector<Eigen::Vector3i>& /*triangles*/) {}
  /// Puts back every part tearing removed (its constants are resetConstants()' business).
  virtual void mend() {}
  /// After a vertex split along a tear: particle `copy` takes `original`'s place in `triangles` (the
  /// surface triangles given to it, corners as they were, with `original`) and in every part that
  /// joins `original` to one of `neighbours` (the other corners of those triangles, sorted). The
  /// implicit pattern is rebuilt afterwards (bindPattern()). Nothing for an element that cannot tear.
  virtual void splitParticle(int /*original*/, int /*copy*/, const std::vector<int>& /*neighbours*/,
                             const std::vector<Eigen::Vector3i>& /*triangles*/)
  {}

  // Measurements ----------------------------------------------------------------------------------
  /// The largest strain [-] of what the element stretches at x; 0 when it stretches nothing.
  virtual double maxStrain(const Eigen::Matrix3Xd& /*x*/) const { return 0.0; }
};

}  // namespace core
}  // namespace particle_sim
