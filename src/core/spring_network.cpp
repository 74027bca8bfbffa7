#include "particle_sim/core/spring_network.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>

#include "particle_sim/core/forces/spring_body_forces.h"
#include "particle_sim/core/forces/springs.h"
#include "particle_sim/core/integrators/registry.h"
#include "particle_sim/core/names.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
namespace
{
// to_a = from_a and to_b = from_b (four arrays of the same size), in one pass shared by chunks of
// particles (WorkerPool).
void copyBothShared(WorkerPool* workers, const Eigen::Matrix3Xd& from_a, Eigen::Matrix3Xd& to_a,
                    const Eigen::Matrix3Xd& from_b, Eigen::Matrix3Xd& to_b)
{
  if (to_a.cols() != from_a.cols() || to_b.cols() != from_b.cols() || from_a.cols() != from_b.cols())
  {
    to_a = from_a;
    to_b = from_b;
    return;
  }
  shareLoop(workers, static_cast<int>(from_a.cols()), kParticlesPerVectorChunk, [&](int begin, int end) {
    to_a.middleCols(begin, end - begin) = from_a.middleCols(begin, end - begin);
    to_b.middleCols(begin, end - begin) = from_b.middleCols(begin, end - begin);
  });
}

// (a, b) with the smaller first: a spring's or an edge's particle pair, whichever way it is given.
std::pair<int, int> orderedPair(int a, int b)
{
  return a < b ? std::make_pair(a, b) : std::make_pair(b, a);
}

std::string indexed(const char* field, std::size_t i)
{
  return std::string(field) + "[" + std::to_string(i) + "]";
}

Status checkIndex(const std::string& field, long long index, int count)
{
  if (index >= 0 && index < count) return Status::success();
  return Status::failure(field + " = " + std::to_string(index) + " is out of range: must be in [0, " +
                         std::to_string(count - 1) + "] (the body has " + std::to_string(count) + " particles)");
}
}  // namespace

const char* toString(NetworkShape shape)
{
  switch (shape)
  {
    case NetworkShape::Network:
      return "spring_network";
    case NetworkShape::Rope:
      return "rope";
    case NetworkShape::Cloth:
      return "cloth";
    case NetworkShape::Jelly:
      return "jelly";
  }
  return "unknown";
}

Status validate(const SpringNetworkDef& def, int max_particles)
{
  if (Status s = validateBodyName(def.name); !s) return s;
  const int n = static_cast<int>(def.positions.size());
  if (Status s = checkIntRange("particles (count)", n, 1, max_particles); !s) return s;
  if (def.masses.size() != def.positions.size())
    return Status::failure("masses has " + std::to_string(def.masses.size()) + " entries for " + std::to_string(n) +
                           " particles: give one mass per particle");
  if (!def.velocities.empty() && def.velocities.size() != def.positions.size())
    return Status::failure("velocities has " + std::to_string(def.velocities.size()) + " entries for " +
                           std::to_string(n) + " particles: give one per particle or none");
  for (int i = 0; i < n; ++i)
  {
    if (Status s = checkFinite(indexed("positions", i), def.positions[i]); !s) return s;
    if (Status s = checkPositive(indexed("masses", i), def.masses[i]); !s) return s;
    if (!def.velocities.empty())
    {
      if (Status s = checkFinite(indexed("velocities", i), def.velocities[i]); !s) return s;
    }
  }
  for (std::size_t k = 0; k < def.springs.size(); ++k)
  {
    const Spring& spring = def.springs[k];
    const std::string where = indexed("springs", k) + ".";
    if (Status s = checkIndex(where + "i", spring.i, n); !s) return s;
    if (Status s = checkIndex(where + "j", spring.j, n); !s) return s;
    if (spring.i == spring.j)
      return Status::failure(where + "i = " + where + "j = " + std::to_string(spring.i) +
                             ": a spring joins two different particles");
    if (Status s = checkMin(where + "rest_length", spring.rest_length, 0.0); !s) return s;
    if (Status s = checkSpringConstants(where, spring.stiffness, spring.damping); !s) return s;
  }
  for (std::size_t k = 0; k < def.pins.size(); ++k)
  {
    if (Status s = checkIndex(indexed("pins", k), def.pins[k], n); !s) return s;
  }
  for (std::size_t k = 0; k < def.triangles.size(); ++k)
  {
    const Eigen::Vector3i& t = def.triangles[k];
    for (int c = 0; c < 3; ++c)
    {
      if (Status s = checkIndex(indexed("triangles", k) + "[" + std::to_string(c) + "]", t[c], n); !s) return s;
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      return Status::failure(indexed("triangles", k) + " repeats a particle: a triangle needs three different ones");
  }
  if (Status s = validate(def.strain_limit); !s) return s;
  if (Status s = checkRange("contact_thickness", def.contact_thickness, limits::kContactThickness); !s) return s;
  if (Status s = checkRange("tear_strain", def.tear_strain, limits::kTearStrain); !s) return s;
  if (def.self_collision.enabled)
  {
    if (Status s =
            checkRange("self_collision.thickness", def.self_collision.thickness, limits::kSelfCollisionThickness);
        !s)
      return s;
  }
  if (def.tear_strain > 0.0 && (!def.rod_bending.empty() || !def.plate_bending.empty()))
    return Status::failure("tear_strain = " + formatValue(def.tear_strain) +
                           ": tearing breaks springs and Baraff–Witkin triangles; a body with rod or plate bending "
                           "(a rope or cloth given by its material) cannot tear yet (set tear_strain to 0)");
  const BaraffWitkinDef& bw = def.baraff_witkin;
  for (const BwTriangle& t : bw.triangles)
    for (int c : t.v)
      if (Status s = checkIndex("baraff_witkin triangle corner", c, n); !s) return s;
  for (const BwBend& b : bw.bends)
    for (int c : b.v)
      if (Status s = checkIndex("baraff_witkin bend corner", c, n); !s) return s;
  if (bw.bend_weights.size() != bw.bends.size())
    return Status::failure("baraff_witkin: one bend weight per bend is needed");
  if (Status s = checkSpringConstants("stretch.", bw.stretch.stiffness, bw.stretch.damping); !s) return s;
  if (Status s = checkSpringConstants("shear.", bw.shear.stiffness, bw.shear.damping); !s) return s;
  if (Status s = checkSpringConstants("bend.", bw.bend.stiffness, bw.bend.damping); !s) return s;
  if (Status s = checkPositive("b_u", bw.b_u); !s) return s;
  if (Status s = checkPositive("b_v", bw.b_v); !s) return s;
  for (std::size_t k = 0; k < def.rod_bending.bends.size(); ++k)
  {
    const RodBend& bend = def.rod_bending.bends[k];
    const std::string where = indexed("rod_bending", k) + ".";
    for (int c = 0; c < 3; ++c)
      if (Status s = checkIndex(where + "v[" + std::to_string(c) + "]", bend.v[c], n); !s) return s;
    if (bend.v[0] == bend.v[1] || bend.v[1] == bend.v[2] || bend.v[0] == bend.v[2])
      return Status::failure(where + "v repeats a particle: a bend joins three different ones");
    if (Status s = checkMin(where + "stiffness", bend.stiffness, 0.0); !s) return s;
    if (Status s = checkMin(where + "damping", bend.damping, 0.0); !s) return s;
  }
  const PlateBendingDef& plate = def.plate_bending;
  const bool plate_consistent = plate.empty() ? plate.particles.empty() && plate.weights.empty()
                                              : plate.row_start.size() == plate.inverse_area.size() + 1 &&
                                                    plate.row_start.front() == 0 &&
                                                    plate.particles.size() == plate.weights.size() &&
                                                    plate.row_start.back() == static_cast<int>(plate.particles.size());
  if (!plate_consistent)
    return Status::failure("plate_bending: the stencils' row starts, particles, weights and areas do not agree");
  for (int c : plate.particles)
    if (Status s = checkIndex("plate_bending particle", c, n); !s) return s;
  if (Status s = checkMin("plate_bending.rigidity", plate.rigidity, 0.0); !s) return s;
  if (Status s = checkMin("plate_bending.damping", plate.damping, 0.0); !s) return s;
  return validate(def.integrator);
}

SpringNetworkBody::SpringNetworkBody(const SpringNetworkDef& def, const IntegratorDef& integrator_defaults)
    : Body(def.name),
      def_(def),
      forces_(
          makeSpringBodyForces(def_.springs, def_.baraff_witkin, def_.triangles, def_.rod_bending, def_.plate_bending)),
      built_integrator_(resolve(def.integrator, integrator_defaults)),
      strain_limit_(def_.strain_limit, def_.springs, static_cast<int>(def_.positions.size()))
{
  const int n = static_cast<int>(def_.positions.size());
  particles_.resize(n, n);
  mass_.resize(n);
  pinned_.assign(n, 0);
  pinned_indices_.reserve(n);
  pin_target_.setZero(3, n);
  saved_position_.setZero(3, n);
  saved_velocity_.setZero(3, n);
  substep_start_.setZero(3, n);
  carried_force_.setZero(3, n);
  carried_pin_velocity_.setZero(3, n);
  start_pin_velocity_.setZero(3, n);
  resting_contacts_.reserve(n);
  if (def_.tear_strain > 0.0)
  {
    // A tear allocates nothing: its lists can hold every spring.
    torn_.springs.reserve(def_.springs.size());
    torn_.triangles.reserve(def_.baraff_witkin.triangles.size());
    joined_pairs_.reserve(def_.springs.size());
    cut_pairs_.reserve(def_.springs.size());
    for (const Spring& spring : def_.springs)
      built_pairs_.push_back(orderedPair(spring.i, spring.j));
    std::sort(built_pairs_.begin(), built_pairs_.end());
    // A vertex split's lists: every end of a spring and corner of a triangle as candidates, and a
    // fan as large as the most triangles at one particle (a split never adds triangles to a fan).
    split_candidates_.reserve(2 * def_.springs.size() + 3 * def_.triangles.size());
    std::vector<int> fan_size(n, 0);
    for (const Eigen::Vector3i& t : def_.triangles)
      for (int c = 0; c < 3; ++c)
        ++fan_size[t[c]];
    const int largest_fan = n > 0 ? *std::max_element(fan_size.begin(), fan_size.end()) : 0;
    split_fan_.reserve(largest_fan);
    split_group_.reserve(largest_fan);
    split_roots_.reserve(largest_fan);
  }
  rebuildPattern();
  step_target_.setZero(3, n);

  // The size of the body's energy, for the blow-up check: total mass · extent.
  Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), high = -low;
  double total_mass = 0.0;
  for (int i = 0; i < n; ++i)
  {
    low = low.cwiseMin(def_.positions[i]);
    high = high.cwiseMax(def_.positions[i]);
    total_mass += def_.masses[i];
  }
  energy_scale_ = total_mass * std::max((high - low).norm(), 1e-3);
  reset();
}

void SpringNetworkBody::rebuildPattern()
{
  // The implicit system's pattern: the particle pairs every force element couples. The elements
  // look up their block indices once; they depend only on the pattern, which every implicit
  // method's solver is given.
  const int n = particles_.size();
  std::vector<std::pair<int, int>> pairs;
  forces_.coupledPairs(pairs);
  ImplicitEulerSolver pattern;
  pattern.setPattern(n, pairs);
  forces_.bindPattern(pattern);
  // What an implicit step costs this body, in explicit substeps: `auto` weighs it against Verlet's.
  bool supernodal = false;
  const double direct_in_cg_iterations = pattern.directCostInCgIterations(&supernodal);
  implicit_step_cost_ = StabilityGuard::implicitStepCost(direct_in_cg_iterations, supernodal);
  methods_.clear();
  for (const IntegratorInfo& info : integratorRegistry())
    methods_.emplace_back(info.type, info.make(n, pairs));
}

void SpringNetworkBody::reset()
{
  const int n = static_cast<int>(def_.positions.size());
  ParticlePool& p = particles_;
  const bool split = split_particles_ > 0;  // the body grew and its pattern was rebuilt
  if (split)
  {
    // Drop the particles vertex splits added (the loop below sets every built one).
    p.resize(n, n);
    strain_limit_.resize(n);
    mass_.resize(n);
    pinned_.assign(n, 0);
    pin_target_.setZero(3, n);
    saved_position_.setZero(3, n);
    saved_velocity_.setZero(3, n);
    substep_start_.setZero(3, n);
    step_target_.setZero(3, n);
    carried_force_.setZero(3, n);
    carried_pin_velocity_.setZero(3, n);
    start_pin_velocity_.setZero(3, n);
  }
  rest_positions_ = def_.positions;
  origin_of_.resize(n);
  std::iota(origin_of_.begin(), origin_of_.end(), 0);
  split_particles_ = 0;
  for (int i = 0; i < n; ++i)
  {
    p.position.col(i) = def_.positions[i];
    p.previous_position.col(i) = def_.positions[i];
    p.velocity.col(i) = def_.velocities.empty() ? Eigen::Vector3d::Zero() : def_.velocities[i];
    mass_[i] = def_.masses[i];
    p.inverse_mass[i] = 1.0 / mass_[i];
    p.age[i] = 0.0;
    pinned_[i] = 0;
  }
  for (int index : def_.pins)
  {
    pinned_[index] = 1;
    p.inverse_mass[index] = 0.0;
    pin_target_.col(index) = def_.positions[index];
  }
  forces_.mend();
  if (split) rebuildPattern();  // the built pattern again, for the mended elements
  forces_.resetConstants();
  surface_ = def_.triangles;
  strain_limit_.setSprings(def_.springs);
  torn_.clear();
  torn_springs_ = 0;
  torn_triangles_ = 0;
  integrator_ = built_integrator_;
  guard_.clear();
  updateStabilityBound();
  last_substeps_ = 1;
  last_dt_ = 0.0;
  carry_pause_ = 0;
  carried_force_steps_ = 0;
  last_solve_ = SolverReport{};
  frozen_reason_.clear();
  restartMethods();
}

// ---------------------------------------------------------------------------------------------
// Pins and springs

Status SpringNetworkBody::pin(int index, const Eigen::Vector3d& target)
{
  if (Status s = checkIndex("index", index, particles_.size()); !s) return s;
  if (Status s = checkFinite("target", target); !s) return s;
  pinned_[index] = 1;
  particles_.inverse_mass[index] = 0.0;
  pin_target_.col(index) = target;
  updateStabilityBound();
  return Status::success();
}

Status SpringNetworkBody::setPinTarget(int index, const Eigen::Vector3d& target)
{
  if (Status s = checkIndex("index", index, particles_.size()); !s) return s;
  if (!pinned_[index]) return Status::failure("index = " + std::to_string(index) + " is not pinned");
  if (Status s = checkFinite("target", target); !s) return s;
  pin_target_.col(index) = target;
  return Status::success();
}

Status SpringNetworkBody::unpin(int index)
{
  if (Status s = checkIndex("index", index, particles_.size()); !s) return s;
  if (!pinned_[index]) return Status::failure("index = " + std::to_string(index) + " is not pinned");
  pinned_[index] = 0;
  particles_.inverse_mass[index] = 1.0 / mass_[index];
  updateStabilityBound();
  return Status::success();
}

int SpringNetworkBody::pinnedCount() const
{
  return static_cast<int>(pinned_indices_.size());
}

int SpringNetworkBody::nearestParticle(const Eigen::Vector3d& point) const
{
  int best = 0;
  double best_distance = std::numeric_limits<double>::infinity();
  for (int i = 0; i < particles_.size(); ++i)
  {
    const double distance = (particles_.position.col(i) - point).squaredNorm();
    if (distance < best_distance)
    {
      best_distance = distance;
      best = i;
    }
  }
  return best;
}

const std::vector<Spring>& SpringNetworkBody::springs() const
{
  return forces_.find<SpringForces>()->springs();  // makeSpringBodyForces() always adds one
}

ClothModel SpringNetworkBody::clothModel() const
{
  return def_.baraff_witkin.empty() ? ClothModel::Springs : ClothModel::BaraffWitkin;
}

double SpringNetworkBody::dampingBound() const
{
  return dampingBound(air_, damping_);
}

double SpringNetworkBody::dampingBound(const AirDef& air, double damping) const
{
  return damping_bound_ + forces_.uniformDampingRate({mass_, pinned_, Eigen::Vector3d::Zero(), air, damping});
}

Status SpringNetworkBody::setSpringConstants(std::optional<SpringClass> spring_class, double stiffness, double damping)
{
  if (Status s = checkSpringConstants("", stiffness, damping); !s) return s;
  if (spring_class && !hasSpringClass(*spring_class))
    return Status::failure("spring_class = '" + std::string(toString(*spring_class)) + "': body '" + name() +
                           "' has no such springs");
  forces_.setClassConstants(spring_class, stiffness, damping);
  updateStabilityBound();
  return Status::success();
}

Status SpringNetworkBody::setIntegrator(const IntegratorDef& integrator)
{
  if (Status s = validate(integrator); !s) return s;
  const bool has_method =
      std::any_of(methods_.begin(), methods_.end(), [&](const auto& entry) { return entry.first == integrator.type; });
  if (integrator.type != kAutoIntegrator && !has_method)
    return Status::failure("integrator = " + quoteReceived(toString(integrator.type)) + " was registered after body " +
                           quoteReceived(name()) + " was built");
  if (integrator.type != integrator_.type) restartMethods();
  integrator_ = integrator;
  return Status::success();
}

// ---------------------------------------------------------------------------------------------
// Forces and measurements

void SpringNetworkBody::computeForces(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                                      const Eigen::Vector3d& gravity, Eigen::Matrix3Xd& force) const
{
  forces_.computeForces(forceContext(gravity), x, v, force);
}

double SpringNetworkBody::maxStrain() const
{
  return forces_.maxStrain(particles_.position);
}

double SpringNetworkBody::kineticEnergy() const
{
  // Summed in fixed chunks of particles, shared between threads: the same bits at any thread count.
  return sumByChunks(workers_, particles_.size(), kParticlesPerVectorChunk, kinetic_energy_chunks_,
                     [&](int i) { return kineticEnergyOf(i); });
}

bool SpringNetworkBody::stateFinite(double* kinetic) const
{
  // kineticEnergy()'s sum (the same chunks and order, so the same bits) over every column of the
  // pool, its room beyond the live particles adding +0, with the finiteness check in the same pass.
  // A coordinate c is finite exactly when c − c is 0 (NaN otherwise): each particle's six
  // differences are summed, the sum compared with itself and the results and-ed over the chunk, a
  // few independent operations a particle with no branch and no call.
  const ParticlePool& p = particles_;
  const int live = p.size();
  std::atomic<bool> finite{true};
  const double* const xs = p.position.data();
  const double* const vs = p.velocity.data();
  auto chunk_sum = [&](int first, int last) {
    double sum = 0.0;
    bool chunk_finite = true;
    for (int i = first; i < last; ++i)
    {
      const double* const x = xs + 3L * i;
      const double* const v = vs + 3L * i;
      const double zero =
          ((x[0] - x[0]) + (x[1] - x[1])) + ((x[2] - x[2]) + (v[0] - v[0])) + ((v[1] - v[1]) + (v[2] - v[2]));
      chunk_finite &= zero == zero;
      sum += kinetic && i < live ? kineticEnergyOf(i) : 0.0;
    }
    if (!chunk_finite) finite.store(false, std::memory_order_relaxed);
    return sum;
  };
  const double sum = sumChunks(workers_, static_cast<int>(p.position.cols()), kParticlesPerVectorChunk,
                               kinetic_energy_chunks_, chunk_sum);
  if (kinetic) *kinetic = sum;
  return finite.load();
}

double SpringNetworkBody::potentialEnergy(const Eigen::Vector3d& gravity) const
{
  return forces_.energy(forceContext(gravity), particles_.position);
}

Eigen::Vector3d SpringNetworkBody::momentum() const
{
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (int i = 0; i < particles_.size(); ++i)
  {
    if (!pinned_[i]) total += mass_[i] * particles_.velocity.col(i);
  }
  return total;
}

// ---------------------------------------------------------------------------------------------
// The step

SubstepPlan SpringNetworkBody::planStep(double dt, const Environment& env) const
{
  // The step's own decisions below, with the bounds it will see once it has taken env's air and
  // global damping.
  const double c_max = dampingBound(env.air, env.damping);
  const IntegratorType type =
      integrator_.type == kAutoIntegrator
          ? StabilityGuard::chooseAuto(dt, omega_bound_, c_max, implicit_step_cost_, integrator_.max_substeps)
          : integrator_.type;
  return StabilityGuard::planSubsteps(type, dt, omega_bound_, c_max, integrator_.max_substeps);
}

void SpringNetworkBody::step(double dt, const Environment& env)
{
  torn_.clear();
  if (frozen()) return;
  air_ = env.air;
  damping_ = env.damping;
  gravity_ = env.gravity;
  ParticlePool& p = particles_;
  const int n = p.size();
  // The pins' targets for the end of the step (only pinned columns are read or changed below).
  for (const int i : pinned_indices_)
    step_target_.col(i) = pin_target_.col(i);
  bool switched = false;
  const IntegratorType type = guard_.resolve(integrator_.type, dt, omega_bound_, dampingBound(), implicit_step_cost_,
                                             integrator_.max_substeps, last_integrator_, switched);
  if (switched) restartMethods();
  // The state the step starts from, for a roll-back: copied, or, when the method writes its state
  // where it is told, left where it is while the first substep writes the new one into the saved
  // arrays, which are then swapped with it (one pass over the particles fewer). The pinned
  // particles' are kept now: the substeps read their positions first, and set their velocities.
  start_kept_by_swap_ = method(type).writesNextState() && saved_position_.cols() == p.position.cols() &&
                        saved_velocity_.cols() == p.velocity.cols();
  if (start_kept_by_swap_)
  {
    for (const int i : pinned_indices_)
    {
      saved_position_.col(i) = p.position.col(i);
      start_pin_velocity_.col(i) = p.velocity.col(i);
    }
  }
  else
  {
    copyBothShared(workers_, p.position, saved_position_, p.velocity, saved_velocity_);
  }
  const bool explicit_method = !isImplicit(type);
  const bool had_history = method(type).hasHistory();
  int substeps = guard_.substeps(type, dt, omega_bound_, dampingBound(), integrator_.max_substeps, last_substeps_);
  // The blow-up check's energy before the step: what the last explicit step measured after itself,
  // when nothing has changed it since (updateStabilityBound() forgets it on every change of pins,
  // constants or springs, and the gravity is the same), else measured now.
  const bool energy_known = explicit_method && energy_after_valid_ && env.gravity == energy_after_gravity_;
  const double energy_before = explicit_method ? (energy_known ? energy_after_ : mechanicalEnergy(env.gravity)) : 0.0;
  // The forces the last step carried, for this one's first evaluation when the state and the
  // environment they were computed in still hold (takeCarriedForces() checks the pins).
  carried_armed_ = carried_valid_ && energy_known && method(type).evaluatesForcesFirst() &&
                   env.air.drag == carried_air_.drag && env.air.wind == carried_air_.wind &&
                   env.damping == carried_damping_;
  if (!carried_armed_) dropCarriedForces();  // one this step cannot take pauses carrying
  energy_after_valid_ = carried_valid_ = false;
  guard_.beginStep(explicit_method, energy_before, energy_scale_, env.gravity.norm());
  double energy_after = 0.0;
  bool finite = true, carried = false;

  for (;;)
  {
    // Pinned particles approach their step target in equal parts, one per substep.
    for (int k = 0; k < substeps; ++k)
    {
      const double s = static_cast<double>(k + 1) / substeps;
      for (const int i : pinned_indices_)
      {
        pin_target_.col(i) =
            k + 1 == substeps
                ? Eigen::Vector3d(step_target_.col(i))  // exactly on target at the end
                : Eigen::Vector3d(saved_position_.col(i) + s * (step_target_.col(i) - saved_position_.col(i)));
      }
      substep(dt / substeps, type, env);
    }
    for (const int i : pinned_indices_)
      pin_target_.col(i) = step_target_.col(i);

    // Blow-up of an explicit method: roll back and retry with more substeps, or freeze.
    carried_armed_ = false;
    // The energy after an explicit step, with the forces of its end state when the next step may
    // take them (the springs' energy comes out of their force pass): kinetic + potential, as
    // mechanicalEnergy() sums it, the same bits. The kinetic part comes out of the finiteness check.
    double kinetic = 0.0;
    finite = stateFinite(explicit_method ? &kinetic : nullptr);
    carried = explicit_method && finite && carry_pause_ == 0;
    if (carried)
      energy_after =
          kinetic + forces_.computeForcesAndEnergy(forceContext(env.gravity), p.position, p.velocity, carried_force_);
    else
      energy_after = explicit_method ? kinetic + potentialEnergy(env.gravity) : 0.0;
    if (!guard_.blewUp(finite, energy_after)) break;
    p.position = saved_position_;
    p.velocity = saved_velocity_;
    if (!had_history) method(type).restart();
    const int retry = guard_.retrySubsteps(type, dt, substeps, integrator_.max_substeps, frozen_reason_);
    if (retry == 0)
    {
      // What ran, not what the body was built with.
      last_integrator_ = type;
      last_substeps_ = substeps;
      p.previous_position = saved_position_;
      return;
    }
    substeps = retry;
  }
  last_substeps_ = substeps;
  last_integrator_ = type;
  last_dt_ = dt;
  shareLoop(workers_, n, kParticlesPerVectorChunk, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
      p.age[i] += dt;
  });
  // The step's start becomes the previous position by a swap of the arrays, not a copy (the next
  // step saves its start anew).
  p.previous_position.swap(saved_position_);

  // A non-finite state (as checked after the last try above) or a failed solve is never kept: go
  // back to the last good state and stop this body.
  if (!finite || last_solve_.breakdown)
  {
    p.position = p.previous_position;
    p.velocity = saved_velocity_;
    frozen_reason_ = guard_.freezeReason(type, dt, last_solve_.breakdown);
    return;
  }
  if (explicit_method)
  {
    energy_after_ = energy_after;
    energy_after_gravity_ = env.gravity;
    energy_after_valid_ = true;
    if (carried)
    {
      carried_valid_ = true;
      carried_air_ = env.air;
      carried_damping_ = env.damping;
      for (const int i : pinned_indices_)
        carried_pin_velocity_.col(i) = p.velocity.col(i);
    }
    else if (carry_pause_ > 0)
    {
      --carry_pause_;
    }
  }
  if (def_.tear_strain > 0.0) tearOverstretched();  // a tear forgets energy_after_ (updateStabilityBound)
}

void SpringNetworkBody::tearOverstretched()
{
  forces_.tear(particles_.position, def_.tear_strain, torn_);
  if (torn_.empty()) return;
  torn_springs_ += static_cast<long long>(torn_.springs.size());
  torn_triangles_ += static_cast<long long>(torn_.triangles.size());

  // The pairs springs still join, and this step's cut edges (pairs that had springs and lost them
  // all now): the surface is cut along the tears (cutSurfaceAlongTears). Runs only when something
  // broke.
  std::vector<std::pair<int, int>>& joined = joined_pairs_;
  joined.clear();
  for (const Spring& spring : springs())
    joined.push_back(orderedPair(spring.i, spring.j));
  std::sort(joined.begin(), joined.end());
  std::vector<std::pair<int, int>>& cut = cut_pairs_;
  cut.clear();
  for (const std::pair<int, int>& pair : torn_.springs)
  {
    const std::pair<int, int> edge = orderedPair(pair.first, pair.second);
    if (!std::binary_search(joined.begin(), joined.end(), edge)) cut.push_back(edge);
  }
  std::sort(cut.begin(), cut.end());
  cutSurfaceAlongTears(cut);
  strain_limit_.setSprings(springs());
  // `auto` re-decides from the new bound at the next step anyway; its explanation is kept (rebuilt
  // when its choice changes), as writing it anew would allocate in the step.
  updateStabilityBound(false);
}

void SpringNetworkBody::cutSurfaceAlongTears(const std::vector<std::pair<int, int>>& cut)
{
  // An edge is cut when its particles had a spring as built (between the particles they come from)
  // and have none now: this step's tear or an earlier one.
  std::vector<std::pair<int, int>>& joined = joined_pairs_;  // sorted by tearOverstretched()
  auto is_cut = [&](int a, int b) {
    return !std::binary_search(joined.begin(), joined.end(), orderedPair(a, b)) &&
           std::binary_search(built_pairs_.begin(), built_pairs_.end(), orderedPair(origin_of_[a], origin_of_[b]));
  };
  auto is_torn = [&](const Eigen::Vector3i& t) {
    return std::find(torn_.triangles.begin(), torn_.triangles.end(), t) != torn_.triangles.end();
  };

  // 1. A triangle goes when it tore (Baraff–Witkin) or, in a cloth, two of its edges were cut (it
  //    would hang by one edge or none; a jelly or network drops it at the first). The corners of
  //    what went, and the ends of the cut edges, may split. The work lists are members reserved at
  //    build: a tear that splits nothing allocates nothing.
  const bool cloth = def_.shape == NetworkShape::Cloth;
  const int cuts_that_drop = cloth ? 2 : 1;
  std::vector<int>& candidates = split_candidates_;
  candidates.clear();
  for (const std::pair<int, int>& edge : cut)
  {
    candidates.push_back(edge.first);
    candidates.push_back(edge.second);
  }
  const std::size_t before = surface_.size();
  surface_.erase(std::remove_if(surface_.begin(), surface_.end(),
                                [&](const Eigen::Vector3i& t) {
                                  const int cuts = is_cut(t[0], t[1]) + is_cut(t[1], t[2]) + is_cut(t[2], t[0]);
                                  if (cuts < cuts_that_drop && !is_torn(t)) return false;
                                  candidates.insert(candidates.end(), {t[0], t[1], t[2]});
                                  return true;
                                }),
                 surface_.end());
  if (!cloth)
  {
    if (surface_.size() != before) forces_.setSurface(surface_);
    return;
  }
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());

  // 2. Each candidate's triangles, grouped through the edges at it that still have a spring (or,
  //    without springs, are shared by two triangles). Every group but the first (by triangle order)
  //    gets a copy of the particle, which takes that group's triangles and the springs to their
  //    corners. A pinned particle is not split: what holds it holds every side.
  struct Split
  {
    int original, copy;
    std::vector<int> neighbours;
    std::vector<Eigen::Vector3i> triangles;
    double area;  // [m²] at rest, of the group's triangles
  };
  std::vector<Split> splits;
  std::vector<double> kept_area;  // per split original, the first group's rest area
  const auto rest_area = [&](const Eigen::Vector3i& t) {
    return 0.5 *
           (rest_positions_[t[1]] - rest_positions_[t[0]]).cross(rest_positions_[t[2]] - rest_positions_[t[0]]).norm();
  };
  int next_copy = particles_.size();
  std::vector<int>& fan = split_fan_;
  std::vector<int>& group = split_group_;
  std::vector<int>& roots = split_roots_;
  for (int v : candidates)
  {
    if (pinned_[v]) continue;
    fan.clear();
    for (int t = 0; t < static_cast<int>(surface_.size()); ++t)
      if (surface_[t][0] == v || surface_[t][1] == v || surface_[t][2] == v) fan.push_back(t);
    if (fan.size() < 2) continue;
    // Union–find over the fan (a handful of triangles): joined through a shared, uncut edge at v.
    group.resize(fan.size());
    std::iota(group.begin(), group.end(), 0);
    const auto root = [&](int a) {
      while (group[a] != a)
        a = group[a];
      return a;
    };
    for (std::size_t a = 0; a < fan.size(); ++a)
      for (std::size_t b = a + 1; b < fan.size(); ++b)
        for (int k = 0; k < 3; ++k)
        {
          const int w = surface_[fan[a]][k];
          const bool shared =
              w != v && (surface_[fan[b]][0] == w || surface_[fan[b]][1] == w || surface_[fan[b]][2] == w);
          if (shared && !is_cut(v, w)) group[root(static_cast<int>(b))] = root(static_cast<int>(a));
        }
    // The groups in order of their first triangle; the first keeps v.
    roots.clear();
    for (std::size_t a = 0; a < fan.size(); ++a)
      if (std::find(roots.begin(), roots.end(), root(static_cast<int>(a))) == roots.end())
        roots.push_back(root(static_cast<int>(a)));
    if (roots.size() < 2) continue;
    double first_area = 0.0;
    for (std::size_t a = 0; a < fan.size(); ++a)
      if (root(static_cast<int>(a)) == roots[0]) first_area += rest_area(surface_[fan[a]]);
    kept_area.push_back(first_area);
    for (std::size_t g = 1; g < roots.size(); ++g)
    {
      Split split{v, next_copy++, {}, {}, 0.0};
      // The copy's rest position and origin now: the next candidates' triangles may hold it.
      rest_positions_.push_back(rest_positions_[v]);
      origin_of_.push_back(origin_of_[v]);
      for (std::size_t a = 0; a < fan.size(); ++a)
      {
        if (root(static_cast<int>(a)) != roots[g]) continue;
        Eigen::Vector3i& t = surface_[fan[a]];
        split.triangles.push_back(t);
        split.area += rest_area(t);
        for (int k = 0; k < 3; ++k)
          if (t[k] != v) split.neighbours.push_back(t[k]);
        for (int k = 0; k < 3; ++k)
          if (t[k] == v) t[k] = split.copy;
      }
      std::sort(split.neighbours.begin(), split.neighbours.end());
      split.neighbours.erase(std::unique(split.neighbours.begin(), split.neighbours.end()), split.neighbours.end());
      // The springs follow at once, so that the next candidates see the edges as they now are.
      forces_.splitParticle(v, split.copy, split.neighbours, split.triangles);
      splits.push_back(std::move(split));
    }
    joined.clear();
    for (const Spring& spring : springs())
      joined.push_back(orderedPair(spring.i, spring.j));
    std::sort(joined.begin(), joined.end());
  }

  // 3. The copies: the original's state, and a share of its mass by the groups' rest areas (the
  //    mass and the momentum are kept).
  if (!splits.empty())
  {
    std::vector<int> sources;
    for (const Split& split : splits)
      sources.push_back(split.original);
    appendCopies(sources);
    std::size_t first = 0, original_index = 0;
    while (first < splits.size())
    {
      const int v = splits[first].original;
      std::size_t last = first;
      double total_area = kept_area[original_index];
      while (last < splits.size() && splits[last].original == v)
        total_area += splits[last++].area;
      const double mass = mass_[v];
      double given = 0.0;
      for (std::size_t k = first; k < last; ++k)
      {
        const double share = total_area > 0.0 ? mass * splits[k].area / total_area : mass / (last - first + 1);
        mass_[splits[k].copy] = share;
        particles_.inverse_mass[splits[k].copy] = 1.0 / share;
        given += share;
      }
      mass_[v] = mass - given;
      particles_.inverse_mass[v] = 1.0 / mass_[v];
      first = last;
      ++original_index;
    }
    split_particles_ += static_cast<long long>(splits.size());
    rebuildPattern();
  }
  if (surface_.size() != before || !splits.empty()) forces_.setSurface(surface_);
}

void SpringNetworkBody::appendCopies(const std::vector<int>& sources)
{
  const int old_n = particles_.size();
  const int n = old_n + static_cast<int>(sources.size());
  auto grow = [&](Eigen::Matrix3Xd& m) {
    m.conservativeResize(3, n);
    for (std::size_t k = 0; k < sources.size(); ++k)
      m.col(old_n + static_cast<int>(k)) = m.col(sources[k]);
  };
  auto grow_scalars = [&](Eigen::VectorXd& m) {
    m.conservativeResize(n);
    for (std::size_t k = 0; k < sources.size(); ++k)
      m[old_n + static_cast<int>(k)] = m[sources[k]];
  };
  ParticlePool& p = particles_;
  grow(p.position);
  grow(p.velocity);
  grow(p.previous_position);
  grow_scalars(p.inverse_mass);
  grow_scalars(p.age);
  p.live_count = n;
  grow_scalars(mass_);
  grow(pin_target_);
  grow(saved_position_);
  grow(saved_velocity_);
  grow(substep_start_);
  grow(step_target_);
  grow(carried_force_);
  grow(carried_pin_velocity_);
  grow(start_pin_velocity_);
  pinned_.resize(n, 0);
  pinned_indices_.reserve(n);
  resting_contacts_.reserve(n);
  strain_limit_.resize(n);
}

void SpringNetworkBody::pinReactions(Eigen::Matrix3Xd& reactions) const
{
  // r_i = m_i a_i − f_i at the current state, for pinned particles only.
  const ParticlePool& p = particles_;
  const int n = p.size();
  computeForces(p.position.leftCols(n), p.velocity.leftCols(n), gravity_, reactions);
  for (int i = 0; i < n; ++i)
  {
    if (!pinned_[i])
    {
      reactions.col(i).setZero();
      continue;
    }
    const Eigen::Vector3d acceleration = last_dt_ > 0.0
                                             ? Eigen::Vector3d((p.velocity.col(i) - saved_velocity_.col(i)) / last_dt_)
                                             : Eigen::Vector3d::Zero();
    reactions.col(i) = mass_[i] * acceleration - reactions.col(i);
  }
}

SpringNetworkBody::PinLoad SpringNetworkBody::pinLoad(const std::vector<int>& indices,
                                                      const Eigen::Vector3d& about) const
{
  Eigen::Matrix3Xd reactions(3, particles_.size());
  pinReactions(reactions);
  PinLoad load;
  auto add = [&](int i) {
    load.force += reactions.col(i);
    load.torque += (particles_.position.col(i) - about).cross(Eigen::Vector3d(reactions.col(i)));
  };
  if (indices.empty())
  {
    for (int i = 0; i < particles_.size(); ++i)
    {
      if (pinned_[i]) add(i);
    }
  }
  else
  {
    for (int i : indices)
      add(i);
  }
  return load;
}

void SpringNetworkBody::substep(double h, IntegratorType type, const Environment& env)
{
  ParticlePool& p = particles_;
  // Boxes and capsules (thin ones, moving ones) are swept: each particle's path over the substep.
  const bool swept = !env.boxes.empty() || !env.capsules.empty();
  if (swept) substep_start_ = p.position;  // preallocated: same size

  // Pinned particles travel in a straight line to their target: give them that velocity now
  // (every integrator then moves them there, as their acceleration is 0).
  for (const int i : pinned_indices_)
    p.velocity.col(i) = (pin_target_.col(i) - p.position.col(i)) / h;

  // Implicit methods hold the particles resting on colliders inside their solve (stuck, or sliding
  // along the surface with Coulomb friction).
  if (isImplicit(type))
    findRestingContacts(env, p, def_.contact_thickness, resting_contacts_);
  else
    resting_contacts_.clear();
  last_solve_ = method(type).step(h, *this, integrator_);

  // Pinned particles end exactly on their target.
  for (const int i : pinned_indices_)
    p.position.col(i) = pin_target_.col(i);
  // Restriction forces: collisions, strain limiting, and collisions again for what it moved.
  const Eigen::Matrix3Xd* path_start = swept ? &substep_start_ : nullptr;
  resolveCollisions(env, p, &saved_velocity_, path_start, def_.contact_thickness, h, workers_);
  if (strain_limit_.enabled())
  {
    strain_limit_.apply(h, p);
    resolveCollisions(env, p, &saved_velocity_, path_start, def_.contact_thickness, h, workers_);
  }
}

DynamicSystem::StateArrays SpringNetworkBody::nextState()
{
  if (start_kept_by_swap_) return {&saved_position_, &saved_velocity_};
  return {&particles_.position, &particles_.velocity};
}

void SpringNetworkBody::stateWritten()
{
  if (!start_kept_by_swap_) return;
  start_kept_by_swap_ = false;
  particles_.position.swap(saved_position_);
  particles_.velocity.swap(saved_velocity_);
  for (const int i : pinned_indices_)
    saved_velocity_.col(i) = start_pin_velocity_.col(i);
}

IntegrationMethod& SpringNetworkBody::method(IntegratorType type)
{
  for (const auto& [method_type, method] : methods_)
  {
    if (method_type == type) return *method;
  }
  // Unreachable: `auto` is resolved before, validate() refuses an unregistered type and
  // setIntegrator() a type registered after the body was built.
  return *methods_.front().second;
}

void SpringNetworkBody::restartMethods()
{
  for (const auto& entry : methods_)
    entry.second->restart();
}

bool SpringNetworkBody::takeCarriedForces(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                                          Eigen::Matrix3Xd& force) const
{
  if (!carried_armed_) return false;
  carried_armed_ = false;
  bool same = &x == &particles_.position && &v == &particles_.velocity && force.cols() == carried_force_.cols();
  // Bit for bit (a −0 where there was +0 may change a force's zero's sign).
  for (std::size_t k = 0; same && k < pinned_indices_.size(); ++k)
    same = std::memcmp(v.col(pinned_indices_[k]).data(), carried_pin_velocity_.col(pinned_indices_[k]).data(),
                       3 * sizeof(double)) == 0;
  if (!same)
  {
    carry_pause_ = kCarryPause;
    return false;
  }
  force.swap(carried_force_);  // the arrays, not their numbers: the next carry overwrites the other
  ++carried_force_steps_;
  return true;
}

void SpringNetworkBody::accelerations(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v, Eigen::Matrix3Xd& a) const
{
  if (!takeCarriedForces(x, v, a)) computeForces(x, v, gravity_, a);
  shareLoop(workers_, static_cast<int>(a.cols()), kParticlesPerVectorChunk, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
      a.col(i) *= particles_.inverse_mass[i];  // 0 for pinned
  });
}

void SpringNetworkBody::addJacobians(const Eigen::Matrix3Xd& x, ImplicitEulerSolver& solver) const
{
  forces_.addJacobians(forceContext(gravity_), x, solver);
}

void SpringNetworkBody::updateStabilityBound(bool re_explain)
{
  // Gershgorin: each element adds k |∂C/∂x_i| Σ_n |∂C/∂x_n| to row i (springs: 2 k at both ends),
  // alike for damping; the bound is the largest row over the mass of its (free) particle.
  forgetEndState();  // whatever changed the bound may have changed the energy and the forces
  const int n = particles_.size();
  std::vector<double>& stiffness_rows = stiffness_rows_;
  std::vector<double>& damping_rows = damping_rows_;
  stiffness_rows.assign(n, 0.0);  // sized once: a tear recomputes the bound without allocating
  damping_rows.assign(n, 0.0);
  forces_.addStabilityRows(rest_positions_, stiffness_rows, damping_rows);
  omega_bound_ = 0.0;
  damping_bound_ = 0.0;
  // The pins change only through what calls this: their list too, for the step's loops over them.
  pinned_indices_.clear();  // reserved for every particle: no allocation
  for (int i = 0; i < n; ++i)
  {
    if (pinned_[i])
    {
      pinned_indices_.push_back(i);
      continue;
    }
    omega_bound_ = std::max(omega_bound_, std::sqrt(stiffness_rows[i] / mass_[i]));
    damping_bound_ = std::max(damping_bound_, damping_rows[i] / mass_[i]);
  }
  if (re_explain) guard_.forgetChoice();  // re-explain at the next step
}

}  // namespace core
}  // namespace particle_sim
