#pragma once

#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

#include "particle_sim/core/integrator.h"
#include "particle_sim/core/integrators/implicit_euler_solver.h"
#include "particle_sim/core/worker_pool.h"

namespace particle_sim
{
namespace core
{
/// What an integrator sees of a body during one (sub)step: the state it advances, the masses and
/// pins, and the forces with their Jacobians and energy (the environment of the step is bound
/// in). Nothing else: collisions, pins' targets and constraints are the body's, before and after.
class DynamicSystem
{
public:
  virtual ~DynamicSystem() = default;

  /// Positions x [m] and velocities v [m/s], advanced in place.
  virtual Eigen::Matrix3Xd& positions() = 0;
  virtual Eigen::Matrix3Xd& velocities() = 0;
  virtual const Eigen::VectorXd& masses() const = 0;  ///< [kg], also of pinned particles
  /// [1/kg]: 1/m for free particles, 0 for pinned ones (a = f/m without a pass of its own).
  virtual const Eigen::VectorXd& inverseMasses() const = 0;
  virtual const std::vector<char>& pinned() const = 0;
  /// The particles resting on colliders at the start of the step, which implicit methods hold in
  /// their solve (and on which they report what they did); empty for explicit methods.
  virtual std::vector<RestingContact>& restingContacts() = 0;

  /// force = f(x, v) [N] on every particle.
  virtual void computeForces(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v, Eigen::Matrix3Xd& force) const = 0;
  /// computeForces() of the current state (positions(), velocities()) and its mechanicalEnergy() [J],
  /// the same numbers; a system may take both from one pass over its force elements.
  virtual double computeForcesAndEnergy(Eigen::Matrix3Xd& force)
  {
    computeForces(positions(), velocities(), force);
    return mechanicalEnergy();
  }
  /// a = f(x, v) / m for free particles, 0 for pinned ones [m/s²].
  virtual void accelerations(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v, Eigen::Matrix3Xd& a) const = 0;
  /// Adds the blocks ∂f/∂x, ∂f/∂v at x to `solver` (whose pattern is the system's couplings).
  virtual void addJacobians(const Eigen::Matrix3Xd& x, ImplicitEulerSolver& solver) const = 0;
  /// The particle pairs the Jacobian couples (for a solver's pattern).
  virtual void coupledPairs(std::vector<std::pair<int, int>>& pairs) const = 0;
  /// True when an outside force (wind) may rightly add energy in a step.
  virtual bool suppliesEnergy() const = 0;
  /// True when nothing does work on the body in this step (no wind, no pinned particle moving, no
  /// particle resting on a moving collider), so that an implicit step must not gain energy.
  bool nothingDoesWork()
  {
    if (suppliesEnergy()) return false;
    const std::vector<char>& is_pinned = pinned();
    const Eigen::Matrix3Xd& v = velocities();
    for (int i = 0; i < static_cast<int>(v.cols()); ++i)
      if (is_pinned[i] && !v.col(i).isZero()) return false;
    for (const RestingContact& contact : restingContacts())
      if (!contact.surface_velocity.isZero()) return false;  // a moving collider carries it
    return true;
  }
  /// Threads to share per-particle loops with (null: none): a method may use them only where each
  /// particle's result is computed alone (WorkerPool), so that its results do not change.
  virtual WorkerPool* workers() const { return nullptr; }
  virtual double kineticEnergy() const = 0;     ///< [J] of the current state, free particles
  virtual double mechanicalEnergy() const = 0;  ///< [J] kinetic + potential of the current state
  /// Counts and describes a stability event (e.g. energy taken out by the implicit step).
  virtual void recordEvent(std::string_view event) = 0;

  /// Where the new positions and velocities go.
  struct StateArrays
  {
    Eigen::Matrix3Xd* positions;
    Eigen::Matrix3Xd* velocities;
  };
  /// Where a method that writes its state (IntegrationMethod::writesNextState()) puts the new x and
  /// v: positions() and velocities() themselves by default; a system may give arrays of their size
  /// whose contents it does not need, and take them as its state at stateWritten() (by a swap of the
  /// storage, no copy), keeping the old one (for a roll-back) without a pass of its own.
  virtual StateArrays nextState() { return {&positions(), &velocities()}; }
  /// The method has written every particle's new x and v where nextState() said.
  virtual void stateWritten() {}
};

/// One time integrator. Its identity, order, stability limit and whether it is implicit are
/// declared in the registry (integrators/registry.h), next to its factory.
class IntegrationMethod
{
public:
  virtual ~IntegrationMethod() = default;
  /// Advances `system` by h [s] with `settings`; the report of its linear solve (empty for
  /// explicit methods).
  virtual SolverReport step(double h, DynamicSystem& system, const IntegratorDef& settings) = 0;
  /// Forgets what it kept from earlier steps (after build, reset, a switch of method).
  virtual void restart() {}
  /// True when it keeps something from earlier steps that restart() would forget.
  virtual bool hasHistory() const { return false; }
  /// True when step() evaluates the forces first, at the state it starts from (positions() and
  /// velocities() themselves, unchanged): the system may then hand it forces it already has for that
  /// state (SpringNetworkBody carries those it measured the last step's energy with).
  virtual bool evaluatesForcesFirst() const { return false; }
  /// True when step() computes each particle's new x and v from its old ones alone and writes them
  /// only where DynamicSystem::nextState() says, then calls DynamicSystem::stateWritten(); it reads
  /// positions() and velocities() (the old state) until then and changes them nowhere else.
  virtual bool writesNextState() const { return false; }
};

}  // namespace core
}  // namespace particle_sim
