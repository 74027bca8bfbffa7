#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "particle_sim/core/body.h"
#include "particle_sim/core/cloth_model.h"
#include "particle_sim/core/constraints/self_collision.h"
#include "particle_sim/core/constraints/strain_limit.h"
#include "particle_sim/core/forces/baraff_witkin_model.h"
#include "particle_sim/core/forces/force_set.h"
#include "particle_sim/core/forces/plate_bending.h"
#include "particle_sim/core/forces/rod_bending.h"
#include "particle_sim/core/integrator.h"
#include "particle_sim/core/integrators/implicit_euler.h"
#include "particle_sim/core/integrators/integration_method.h"
#include "particle_sim/core/integrators/stability_guard.h"
#include "particle_sim/core/spring.h"
#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// How a spring network is laid out, so that it can be drawn: ropes are chains in index order.
enum class NetworkShape
{
  Network,  ///< free-form particles and springs (the lecture's "interaction between particles")
  Rope,     ///< a chain 0-1-2-...; see buildRope()
  Cloth,    ///< a sheet with surface triangles; see buildClothGrid(), buildMeshCloth()
  Jelly,    ///< a 3-D lattice whose boundary faces are its surface triangles; see buildJelly()
};

const char* toString(NetworkShape shape);

/// A body of particles joined by springs. Ropes, cloth and jelly are builders of this one
/// structure, not separate physics.
struct SpringNetworkDef
{
  std::string name;
  NetworkShape shape = NetworkShape::Network;
  std::vector<Eigen::Vector3d> positions;   ///< [m] initial positions
  std::vector<Eigen::Vector3d> velocities;  ///< [m/s] initial velocities; empty = all zero
  std::vector<double> masses;               ///< [kg] > 0, one per particle
  std::vector<Spring> springs;
  std::vector<int> pins;                   ///< indices pinned where they start
  std::vector<Eigen::Vector3i> triangles;  ///< surface triangles (cloth, jelly): drawn, published, feel the air
  BaraffWitkinDef baraff_witkin;           ///< Baraff–Witkin energies (cloth model baraff_witkin); empty = none
  RodBendingDef rod_bending;               ///< discrete rod bending (ropes built from a material); empty = none
  PlateBendingDef plate_bending;  ///< isotropic plate bending (mesh cloths built from a material); empty = none
  StrainLimitDef strain_limit;
  BodyIntegratorDef integrator;    ///< what the body sets; the rest is the world's default
  double contact_thickness = 0.0;  ///< [m] in limits::kContactThickness: kept from ground and spheres (0 = touch)
  /// [-] in limits::kTearStrain, 0 = never. At the end of a step, a spring of positive rest length
  /// stretched past (1 + tear_strain) times its rest length breaks, and a Baraff–Witkin triangle
  /// whose strain max(|w_u|/b_u, |w_v|/b_v) − 1 exceeds it is removed with the bends across its
  /// edges. Refused together with rod or plate bending (ropes and cloths given by a material).
  double tear_strain = 0.0;
  /// Collisions of the body with itself and with the other bodies that enable theirs (the World's
  /// SelfCollisionSolver, after each step); off by default.
  SelfCollisionDef self_collision;
};

/// Checks sizes, indices, masses, spring constants, pins and the integrator; the message names the
/// field (e.g. "springs[3].stiffness"), its value and the allowed range.
Status validate(const SpringNetworkDef& def, int max_particles);

/// A spring network: particles (struct-of-arrays pool), pins and force elements, advanced by its
/// chosen integrator. The forces are a ForceSet (makeSpringBodyForces(): gravity, springs,
/// Baraff–Witkin conditions, air, global damping); the body asks it for forces, Jacobian blocks,
/// stability rows, energy and run-time constants, and knows none of the elements by name.
///
/// Pins make a particle kinematic (inverse mass 0): during each step it moves in a straight line
/// to its pin target, and it ends the step exactly there. Targets can be moved between steps (a
/// gripper carrying the rope end). Implicit Euler filters pinned degrees of freedom.
///
/// Stability (the policy is StabilityGuard, integrators/stability_guard.h; the methods are units in
/// core/integrators/). Before each step an explicit method sees instability coming from the body's
/// stability bound (Gershgorin: ω_max² ≤ max_i Σ_elements k |∂C/∂x_i| Σ_n |∂C/∂x_n| / m_i, and
/// alike a damping rate c_max): when h (ω_max + c_max) exceeds the method's limit (2 for symplectic
/// Euler and Verlet, 2√2 for RK4) with a 10 % margin, the step is split into enough substeps. After
/// the step it checks for blow-up (non-finite state, or mechanical energy grown past 100 times its
/// size plus the body's energy scale); then the step is rolled back and retried with twice the
/// substeps, up to integrator.max_substeps. Each such event is counted and described
/// (stabilityEvents(), lastStabilityEvent()). A body whose state still turns non-finite, or
/// whose implicit solve breaks down, is restored to its last good state and frozen: it stops
/// stepping and says why (frozenReason()). A solve that reaches its iteration cap is kept and
/// reported (lastSolve().converged = false).
///
/// The `auto` integrator picks, per step, the cheaper of Verlet with the substeps its stability
/// needs and implicit Euler (whose cost the body estimates in substeps from its implicit system's
/// pattern); it re-decides when the spring constants or the step change and says what it picked
/// and why (autoChoice()).
class SpringNetworkBody : public Body, private DynamicSystem
{
public:
  /// `def` must have passed validate().
  /// `integrator_defaults`: the settings of every integrator field `def` does not set (a World
  /// passes its WorldDef::integrator).
  explicit SpringNetworkBody(const SpringNetworkDef& def, const IntegratorDef& integrator_defaults = IntegratorDef());

  BodyKind kind() const override { return BodyKind::SpringNetwork; }
  NetworkShape shape() const { return def_.shape; }
  const SpringNetworkDef& definition() const { return def_; }

  void step(double dt, const Environment& env) override;
  void setWorkers(WorkerPool* workers) override { workers_ = workers; }
  void reset() override;

  // Pins ---------------------------------------------------------------------------------------
  /// Pins particle `index` and sets its target [m] (its current position to hold it in place).
  Status pin(int index, const Eigen::Vector3d& target);
  /// Moves the target of a pinned particle; it gets there by the end of the next step.
  Status setPinTarget(int index, const Eigen::Vector3d& target);
  /// Releases a pinned particle with the velocity it had.
  Status unpin(int index);
  bool isPinned(int index) const { return pinned_[index] != 0; }
  int pinnedCount() const;
  Eigen::Vector3d pinTarget(int index) const { return pin_target_.col(index); }
  /// Index of the particle nearest to `point`.
  int nearestParticle(const Eigen::Vector3d& point) const;

  /// The force [N] each pin exerts on its particle to keep it on its course: the reaction
  /// r_i = m_i a_i − f_i(x, v), f_i the force of every element (springs, gravity, air, damping) on
  /// particle i at the current state and a_i its acceleration over the last step, (v − v_before) / dt
  /// (0 before the first step). It is what the held particles need in order to follow their targets
  /// against the body, gravity and their own inertia; 0 for free particles. Computed on call (one
  /// force evaluation, nothing in the step); `reactions` is set to 3 × particles.
  void pinReactions(Eigen::Matrix3Xd& reactions) const;
  /// The sum of the pins' reactions over `indices` (every pinned particle when empty) [N] and its
  /// torque about `about` [N·m], Σ (x_i − about) × r_i.
  struct PinLoad
  {
    Eigen::Vector3d force = Eigen::Vector3d::Zero();
    Eigen::Vector3d torque = Eigen::Vector3d::Zero();
  };
  PinLoad pinLoad(const std::vector<int>& indices, const Eigen::Vector3d& about) const;
  /// The resting contacts of the last implicit step (findRestingContacts): which the solve held,
  /// stuck or let slip, which it let go, and the impulses [N·s] the surfaces gave them. Empty after
  /// an explicit step.
  const std::vector<RestingContact>& lastRestingContacts() const { return resting_contacts_; }

  // Force elements ---------------------------------------------------------------------------
  const ForceSet& forces() const { return forces_; }
  /// Read-only views of two elements, for drawing and status: the springs with their current
  /// constants (empty for a body without springs), and the Baraff–Witkin energies (null for a
  /// spring-only body).
  const std::vector<Spring>& springs() const;
  const BaraffWitkinModel* baraffWitkin() const { return forces_.find<BaraffWitkinModel>(); }
  /// Baraff–Witkin when the body was built with Baraff–Witkin energies, else springs (ropes,
  /// jelly and networks too).
  ClothModel clothModel() const;
  bool hasSpringClass(SpringClass spring_class) const { return forces_.hasClass(spring_class); }
  /// Sets stiffness [N/m] and damping [N·s/m] of `spring_class` (every class when empty) in every
  /// force element that has it (springs, Baraff–Witkin conditions). Takes effect at the next step;
  /// the implicit system is rebuilt every step.
  Status setSpringConstants(std::optional<SpringClass> spring_class, double stiffness, double damping);

  // Integrator ---------------------------------------------------------------------------------
  /// The settings it integrates with: its definition's over the defaults it was built with.
  const IntegratorDef& integrator() const { return integrator_; }
  Status setIntegrator(const IntegratorDef& integrator);
  /// Sets the fields `settings` sets and keeps the others.
  Status setIntegrator(const BodyIntegratorDef& settings) { return setIntegrator(resolve(settings, integrator_)); }
  const SolverReport& lastSolve() const { return last_solve_; }
  /// The method the last step used (auto resolved).
  IntegratorType lastIntegrator() const { return last_integrator_; }
  /// Substeps the last step was split into (1 = none).
  int lastSubsteps() const { return last_substeps_; }
  /// How the next step(dt, env) will run, asked before it: the method (`auto` resolved) and its
  /// substeps, by the rules the step itself follows (a blow-up retry may add substeps after).
  SubstepPlan planStep(double dt, const Environment& env) const;
  /// For `auto`: what it picked and why, e.g. "verlet: h (ω + c) = 0.31 <= 1 (ω_max = 41.2 1/s)".
  const std::string& autoChoice() const { return guard_.autoChoice(); }
  /// Upper bounds of the highest frequency ω_max [1/s] and damping rate c_max [1/s] of the body
  /// (Gershgorin, at rest geometry; recomputed when spring constants change).
  double frequencyBound() const { return omega_bound_; }
  double dampingBound() const;
  /// Explicit steps since build or reset whose first force evaluation took the forces the step before
  /// computed at its end state along with its energy (a pass over the springs saved each).
  long long carriedForceSteps() const { return carried_force_steps_; }
  /// Stability events (substeps added, blow-ups rolled back) since build or reset.
  long long stabilityEvents() const { return guard_.events(); }
  const std::string& lastStabilityEvent() const { return guard_.lastEvent(); }

  // Tearing ------------------------------------------------------------------------------------
  /// The surface triangles left (drawn, published and under the air). A cloth splits along its
  /// tears: a triangle goes when two of its edges lost their last spring or it is a torn
  /// Baraff–Witkin triangle, and a vertex whose remaining triangles fall apart into several groups
  /// (joined only through edges that still have a spring) becomes one particle per group, so the
  /// hole opens. A jelly or network drops every triangle with such an edge instead.
  const std::vector<Eigen::Vector3i>& surfaceTriangles() const { return surface_; }
  /// [kg] per particle (pinned ones too); a vertex split shares its particle's mass among the copies.
  const Eigen::VectorXd& particleMasses() const { return mass_; }
  /// The particle as built that particle `i` comes from: itself, or the one a tear split it off.
  int particleOrigin(int i) const { return origin_of_[i]; }
  /// Particles added by splitting vertices along tears since build or reset (a cloth only).
  long long splitParticles() const { return split_particles_; }
  /// Springs broken since build or reset, and in the last step.
  long long tornSprings() const { return torn_springs_; }
  int lastTornSprings() const { return static_cast<int>(torn_.springs.size()); }
  /// Baraff–Witkin triangles removed since build or reset, and in the last step.
  long long tornTriangles() const { return torn_triangles_; }
  int lastTornTriangles() const { return static_cast<int>(torn_.triangles.size()); }
  /// What the last step tore (empty when nothing).
  const TearRecord& lastTear() const { return torn_; }

  // Collisions between surfaces ------------------------------------------------------------------
  /// What the World's SelfCollisionSolver reads and moves after the step: the positions at the
  /// step's start [m], and the particles (positions and velocities), which it changes only through
  /// impulses; it then calls particlesMovedAfterStep().
  const Eigen::Matrix3Xd& stepStartPositions() const { return particles_.previous_position; }
  ParticlePool& particlesForContacts() { return particles_; }
  /// Says that something outside the step moved the particles (the energy the step measured after
  /// itself no longer holds).
  void particlesMovedAfterStep() { forgetEndState(); }

  // Measurements -------------------------------------------------------------------------------
  /// Largest (|x_j − x_i| − L) / L over the stretch and shear springs [-].
  double maxStrain() const;
  double kineticEnergy() const override;                                  ///< [J], free particles
  double potentialEnergy(const Eigen::Vector3d& gravity) const override;  ///< [J], springs + gravity (z = 0 at 0)
  Eigen::Vector3d momentum() const;                                       ///< [kg·m/s], free particles
  bool frozen() const { return !frozen_reason_.empty(); }
  const std::string& frozenReason() const { return frozen_reason_; }

  /// Total force on every particle at state (x, v): every force element, with the air and global
  /// damping of the current step.
  void computeForces(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v, const Eigen::Vector3d& gravity,
                     Eigen::Matrix3Xd& force) const;

private:
  // One (sub)step of length h with `type`: pins, integrator, pin targets, collisions, strain limit.
  void substep(double h, IntegratorType type, const Environment& env);
  // c_max [1/s] under the air and global damping [1/s] of a step.
  double dampingBound(const AirDef& air, double damping) const;
  // Breaks what is stretched past def_.tear_strain and updates the surface, the strain limit and
  // the stability bound when something broke.
  void tearOverstretched();
  // Recomputes omega_bound_ and damping_bound_ from the current constants (and forgets the energy
  // the last step measured: whatever changes the bound may change the energy).
  // `re_explain`: have `auto` write its explanation anew at the next step.
  void updateStabilityBound(bool re_explain = true);
  // A free particle's kinetic energy [J] (0 for a pinned one): kineticEnergy()'s term.
  // On the velocity's three numbers, |v|² as Eigen's squaredNorm() sums it, (v_x² + v_y²) + v_z².
  double kineticEnergyOf(int i) const
  {
    const double* const v = particles_.velocity.data() + 3L * i;
    return pinned_[i] ? 0.0 : 0.5 * mass_[i] * ((v[0] * v[0] + v[1] * v[1]) + v[2] * v[2]);
  }
  // Whether every position and velocity is finite; with `kinetic`, also the kinetic energy, the bits
  // of kineticEnergy(), from the same pass over the particles.
  bool stateFinite(double* kinetic) const;
  // Kinetic plus potential energy of the current state [J].
  double mechanicalEnergy(const Eigen::Vector3d& gravity) const { return kineticEnergy() + potentialEnergy(gravity); }
  // The method of `type` (not auto).
  IntegrationMethod& method(IntegratorType type);
  // Forgets every method's history (Verlet's start, warm starts).
  void restartMethods();

  // What the integrators see (DynamicSystem), with the gravity of the current step.
  Eigen::Matrix3Xd& positions() override { return particles_.position; }
  Eigen::Matrix3Xd& velocities() override { return particles_.velocity; }
  const Eigen::VectorXd& masses() const override { return mass_; }
  const Eigen::VectorXd& inverseMasses() const override { return particles_.inverse_mass; }
  const std::vector<char>& pinned() const override { return pinned_; }
  std::vector<RestingContact>& restingContacts() override { return resting_contacts_; }
  void computeForces(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v, Eigen::Matrix3Xd& force) const override
  {
    if (!takeCarriedForces(x, v, force)) computeForces(x, v, gravity_, force);
  }
  // The springs' energies from the pass that computes their forces (ForceSet::computeForcesAndEnergy(),
  // the same bits as mechanicalEnergy()), but for forces carried from the last step.
  double computeForcesAndEnergy(Eigen::Matrix3Xd& force) override
  {
    if (takeCarriedForces(particles_.position, particles_.velocity, force)) return mechanicalEnergy();
    return kineticEnergy() +
           forces_.computeForcesAndEnergy(forceContext(gravity_), particles_.position, particles_.velocity, force);
  }
  // force = carried_force_ when this is the step's first evaluation, armed, of the state the forces
  // were carried for (the body's own x and v, the pinned particles' velocities the same bits); false
  // (and nothing written) otherwise. Disarms either way.
  bool takeCarriedForces(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v, Eigen::Matrix3Xd& force) const;
  // Forgets the carried forces (something changed the state or the forces after the step); a carry
  // dropped unused pauses carrying, as one refused does (a cloth that self-collision moves every
  // step would otherwise pay a force pass for each energy).
  void dropCarriedForces()
  {
    if (carried_valid_) carry_pause_ = kCarryPause;
    carried_valid_ = false;
  }
  // Forgets what the last step measured of its end state, its energy and its forces (something
  // changed the state, the pins, constants or springs since).
  void forgetEndState()
  {
    energy_after_valid_ = false;
    dropCarriedForces();
  }
  void accelerations(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v, Eigen::Matrix3Xd& a) const override;
  void addJacobians(const Eigen::Matrix3Xd& x, ImplicitEulerSolver& solver) const override;
  void coupledPairs(std::vector<std::pair<int, int>>& pairs) const override { forces_.coupledPairs(pairs); }
  bool suppliesEnergy() const override { return forces_.suppliesEnergy(forceContext(gravity_)); }
  double mechanicalEnergy() const override { return mechanicalEnergy(gravity_); }
  void recordEvent(std::string_view event) override { guard_.record(event); }
  // The step's first substep, when its method writes its state (start_kept_by_swap_): the saved
  // arrays, which then hold the start of the step after the swap in stateWritten().
  StateArrays nextState() override;
  void stateWritten() override;
  // What the force elements read besides the state, with `gravity` [m/s²].
  ForceContext forceContext(const Eigen::Vector3d& gravity) const
  {
    return {mass_, pinned_, gravity, air_, damping_, workers_};
  }
  WorkerPool* workers() const override { return workers_; }

  // The implicit pattern from the force elements' pairs as they are now, bound to every element,
  // and every integration method made anew for it (their histories start again). Allocates.
  void rebuildPattern();
  // Drops the surface triangles the tears cut off and, in a cloth, splits the particles they left
  // with several groups of triangles; `cut` holds the sorted particle pairs that lost their last
  // spring in this step.
  void cutSurfaceAlongTears(const std::vector<std::pair<int, int>>& cut);
  // Appends one particle per entry of `sources`, each a copy of that particle's state, free; the
  // caller sets masses, rest positions and origins, and re-indexes the force elements. Allocates.
  void appendCopies(const std::vector<int>& sources);

  SpringNetworkDef def_;
  ForceSet forces_;
  IntegratorDef built_integrator_;  // def_.integrator over the defaults it was built with (reset() restores it)
  IntegratorDef integrator_;
  AirDef air_;                     // the air of the current step
  double damping_ = 0.0;           // [1/s] global damping of the current step (Environment::damping)
  WorkerPool* workers_ = nullptr;  // the world's threads (setWorkers), or null
  mutable std::vector<double> kinetic_energy_chunks_;  // kineticEnergy(): per chunk of particles, its energy
  Eigen::Vector3d gravity_ = Eigen::Vector3d::Zero();  // [m/s²] gravity of the current step
  Eigen::VectorXd mass_;                               // [kg], kept for pinned particles too
  std::vector<char> pinned_;
  std::vector<int> pinned_indices_;  // the pinned particles in index order (updateStabilityBound())
  Eigen::Matrix3Xd pin_target_;
  IntegratorType last_integrator_ = kImplicitEulerIntegrator;
  int last_substeps_ = 1;
  double omega_bound_ = 0.0;         // [1/s]
  double damping_bound_ = 0.0;       // [1/s], springs and conditions (global damping added at use)
  double energy_scale_ = 0.0;        // [J] total mass · (|g| + 1 m/s²) · size, for the blow-up check
  StabilityGuard guard_;             // substeps, rollback, freeze and `auto`
  double implicit_step_cost_ = 0.0;  // an implicit Euler step, in explicit substeps (`auto`'s estimate)
  SolverReport last_solve_;
  std::string frozen_reason_;

  // Work arrays, sized once.
  std::vector<std::pair<IntegratorType, std::unique_ptr<IntegrationMethod>>> methods_;  // one per registered integrator
  StrainLimit strain_limit_;                          // Provot's constraint, applied after the integrator
  Eigen::Matrix3Xd saved_position_, saved_velocity_;  // the state the step started from
  // The first substep's method writes the new state into the saved arrays, which are then swapped
  // with the state (nextState(), stateWritten()); the pinned particles' velocities at the start,
  // which the substep sets before its method runs, are kept in start_pin_velocity_.
  bool start_kept_by_swap_ = false;
  Eigen::Matrix3Xd start_pin_velocity_;
  Eigen::Matrix3Xd substep_start_;                // positions at the start of a substep, when boxes or capsules sweep
  std::vector<RestingContact> resting_contacts_;  // implicit methods: found before each substep
  double last_dt_ = 0.0;                  // [s] of the last step (pinReactions' accelerations); 0 before the first
  Eigen::Matrix3Xd step_target_;          // pin targets at the end of the whole step (substeps approach them)
  std::vector<Eigen::Vector3i> surface_;  // the surface triangles a tear left
  TearRecord torn_;                       // what the last step tore
  std::vector<std::pair<int, int>> joined_pairs_, cut_pairs_;  // tear work arrays, reserved at build
  std::vector<double> stiffness_rows_, damping_rows_;          // updateStabilityBound()'s Gershgorin rows
  // The mechanical energy [J] the last explicit step measured after itself, under that gravity: the
  // next step's energy before, while valid (nothing changed the state, pins, constants or springs).
  double energy_after_ = 0.0;
  Eigen::Vector3d energy_after_gravity_ = Eigen::Vector3d::Zero();
  bool energy_after_valid_ = false;
  // The forces [N] at the state the last explicit step ended in, computed with its energy after (one
  // pass over the springs for both), for the next step's first force evaluation: the same state,
  // unless something changed it, the pins, constants or springs (carried_valid_ falls with
  // energy_after_valid_), the air or the global damping (kept here), or the pinned particles'
  // velocities (kept per pinned particle). When a carry goes unused (pins moving every step, or
  // self-collision moving particles), the energy is measured alone for kCarryPause steps.
  static constexpr int kCarryPause = 16;
  mutable Eigen::Matrix3Xd carried_force_;  // swapped into the evaluation that takes it
  Eigen::Matrix3Xd carried_pin_velocity_;
  AirDef carried_air_;
  double carried_damping_ = 0.0;
  bool carried_valid_ = false;
  mutable bool carried_armed_ = false;  // this step's first force evaluation may take carried_force_
  mutable int carry_pause_ = 0;
  mutable long long carried_force_steps_ = 0;  // since build or reset
  long long torn_springs_ = 0;                 // since build or reset
  long long torn_triangles_ = 0;               // since build or reset
  // Per particle, its rest position [m] and the built particle it comes from; a vertex split appends
  // copies (reset() drops them).
  std::vector<Eigen::Vector3d> rest_positions_;
  std::vector<int> origin_of_;
  std::vector<std::pair<int, int>> built_pairs_;  // the particle pairs springs joined as built, sorted (tearing only)
  std::vector<int> split_candidates_, split_fan_, split_group_,
      split_roots_;                // cutSurfaceAlongTears()' lists, reserved
  long long split_particles_ = 0;  // since build or reset (above 0: the body grew, its pattern was rebuilt)
};

}  // namespace core
}  // namespace particle_sim
