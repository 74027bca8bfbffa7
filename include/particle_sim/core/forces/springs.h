#pragma once

#include <array>
#include <atomic>
#include <memory>
#include <vector>

#include "particle_sim/core/forces/force_element.h"
#include "particle_sim/core/pair_chunks.h"
#include "particle_sim/core/spring.h"

namespace particle_sim
{
namespace core
{
/// The lecture's springs ("Interaction between particles", spring force = elastic + damping;
/// kernels in spring.h): forces, energy k_e (l − L)²/2, Jacobian blocks in the definite form of
/// Choi & Ko 2002 (compressed springs keep no transverse stiffness), and Gershgorin rows 2 k at
/// both ends. Stiffness and damping are set per SpringClass at run time. A spring stretched past
/// the body's tear strain breaks: it leaves the list (tear(); mend() puts every spring back).
class SpringForces : public ForceElement
{
public:
  explicit SpringForces(std::vector<Spring> springs);

  /// The springs with their current constants.
  const std::vector<Spring>& springs() const { return springs_; }

  void addForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                 Eigen::Matrix3Xd& force) const override;
  void coupledPairs(std::vector<std::pair<int, int>>& pairs) const override;
  void bindPattern(const ImplicitEulerSolver& solver) override;
  void addJacobians(const ForceContext& context, const Eigen::Matrix3Xd& x, ImplicitEulerSolver& solver) const override;
  void addStabilityRows(const std::vector<Eigen::Vector3d>& rest, std::vector<double>& stiffness_rows,
                        std::vector<double>& damping_rows) const override;
  void addEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, double& energy) const override;
  /// addForces() that also keeps the springs' energy, for addKeptEnergy(): each chunk's sum as
  /// addEnergy() takes it (kept_chunk_energy_); shared between threads, also the energy of each
  /// spring in a chunk's pieces that came out of order (kept_energy_), from which those chunks' sums go
  /// on after the pass (and each spring's, summed by addKeptEnergy(), when the pass is not by chunks
  /// of particles).
  void addForcesKeepingEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                              Eigen::Matrix3Xd& force) const override;
  void addKeptEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, double& energy) const override;
  bool hasClass(SpringClass spring_class) const override;
  void setClassConstants(std::optional<SpringClass> spring_class, double stiffness, double damping) override;
  void resetConstants() override;
  /// Breaks every spring of positive rest length whose strain (l − L) / L exceeds `tear_strain`.
  void tear(const Eigen::Matrix3Xd& x, double tear_strain, TearRecord& torn) override;
  void mend() override;
  /// Each spring joining `original` to one of `neighbours` now joins `copy` instead.
  void splitParticle(int original, int copy, const std::vector<int>& neighbours,
                     const std::vector<Eigen::Vector3i>& triangles) override;
  /// Largest (|x_j − x_i| − L) / L over the stretch and shear springs of positive rest length.
  double maxStrain(const Eigen::Matrix3Xd& x) const override;

private:
  /// addForces() shared between threads, by chunks of particles. Each chunk's thread computes
  /// the force of every spring that touches the chunk, in spring order, and adds it to the ends
  /// inside the chunk: each particle gets the one-thread loop's additions in its order (and so
  /// its bits). A spring across two chunks is computed twice; when that would be more than a
  /// quarter of the springs (a network numbered without locality), every spring's force goes into
  /// spring_force_ once and every particle then sums its springs' in spring order (PairChunks).
  /// `energy`: null, or where the springs' energies are kept (per spring of springs_). By chunks of
  /// particles, each chunk of springs' sum goes into kept_chunk_energy_, in the pass while the
  /// chunk's pieces come in order, and only the energies of the pieces out of order into `energy`
  /// (addForcesKeepingEnergy() goes on with those chunks' sums afterwards): returns true. By the two
  /// passes, every spring's energy goes into `energy` (no chunk's sum made): returns false.
  bool addForcesShared(WorkerPool& workers, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                       Eigen::Matrix3Xd& force, double* energy) const;
  /// Whether addForces() is shared between `context`'s threads (addForcesShared()).
  bool sharesForces(const ForceContext& context) const;
  /// Whether addJacobians() is shared between `context`'s threads (addJacobiansShared()): after the
  /// springs' parts of this step.
  bool sharesJacobians(const ForceContext& context, const ImplicitEulerSolver& solver, int particles) const;
  /// addJacobians()'s blocks shared by chunks of particles, from the springs' parts of this step
  /// (the pairs, A's diagonal blocks and b: ImplicitEulerSolver::addAlongPairEnds()).
  void addJacobiansShared(WorkerPool& workers, int particles, ImplicitEulerSolver& solver) const;
  /// Rebuilds the chunks' spring lists (or ends_) for `particles` particles shared by `threads`
  /// threads when the springs, the particle count or the chunk size changed.
  void indexEnds(int particles, int threads) const;

  std::vector<Spring> built_;                     // as built (reset puts these constants back)
  std::vector<std::array<int, 4>> built_blocks_;  // per built spring: its blocks ii, ij, ji, jj
  std::vector<Spring> springs_;                   // the springs not torn, with their current constants
  std::vector<std::array<int, 4>> blocks_;        // per spring of springs_: its blocks
  std::vector<int> origin_;                       // per spring of springs_: its index in built_

  // Scratch of addForcesShared(), sized at its first call and after a tear (never larger).
  mutable std::vector<Eigen::Vector3d> spring_force_;  // per spring of springs_: the force on its end i
  mutable std::vector<int> end_start_;  // per particle p: its ends are ends_[end_start_[p] … end_start_[p + 1])
  mutable std::vector<int> ends_;       // 2 s for end i of spring s, 2 s + 1 for end j, ascending s
  mutable bool ends_valid_ = false;
  mutable bool by_chunks_ = false;  // chunks_ in use (else the two passes); decided once
  mutable int particle_chunk_ = 0;  // particles per chunk of chunks_ (indexEnds())
  mutable bool mode_decided_ = false;
  mutable PairChunks chunks_;                 // the springs by chunks of particles (by_chunks_)
  mutable std::vector<double> chunk_energy_;  // addEnergy(): per chunk of springs, its energy
  mutable std::vector<double> kept_energy_;   // addForcesKeepingEnergy(): per spring of springs_, its energy
  mutable bool energy_kept_ = false;          // the kept energy is of the last addForcesKeepingEnergy()'s x
  // addForcesKeepingEnergy(): each chunk's sum of addEnergy() (energy_kept_by_chunks_), else each
  // spring's in kept_energy_.
  mutable std::vector<double> kept_chunk_energy_;
  mutable bool energy_kept_by_chunks_ = false;
  // Shared between threads, addForcesKeepingEnergy() sums a chunk of springs in the pass as one thread
  // does, while its pieces (the runs' parts in it) come in order: per chunk of springs, the first
  // spring not yet summed (kSummingChunk while a thread sums a piece); after the pass, the chunk's
  // sum goes on from there over kept_energy_. Sized at construction.
  mutable std::unique_ptr<std::atomic<int>[]> chunk_next_spring_;
  mutable SpringJacobianParts jacobian_parts_;  // addJacobians(): per spring of springs_, its parts
  mutable std::vector<char> jacobian_chunk_changed_;  // addJacobiansShared(): per chunk, a pair's ends changed
};

}  // namespace core
}  // namespace particle_sim
