#pragma once

#include <Eigen/Core>
#include <array>
#include <utility>
#include <vector>

#include "particle_sim/core/forces/force_element.h"
#include "particle_sim/core/integrators/implicit_euler_solver.h"

namespace particle_sim
{
namespace core
{
/// One bending element of a discrete rod at an interior particle: particles v[0] – v[1] – v[2]
/// in a chain (v[1] the vertex), straight at rest.
struct RodBend
{
  std::array<int, 3> v;
  double stiffness = 0.0;  ///< EI / l̄ [N·m], l̄ the rest length around the vertex (half of each segment)
  double damping = 0.0;    ///< η_b / l̄ [N·m·s], η_b the bending viscosity [N·m²·s]
};

/// The discrete rod bending of a body (ropes built from a material with EI > 0); empty = none.
struct RodBendingDef
{
  std::vector<RodBend> bends;

  bool empty() const { return bends.empty(); }
};

/// Curvature binormal of a discrete rod at a vertex (Bergou et al. 2008, "Discrete elastic rods"):
/// with edges e₁ = x₁ − x₀, e₂ = x₂ − x₁,
///   κ = 2 (e₁ × e₂) / (|e₁| |e₂| + e₁·e₂),   |κ| = 2 tan(θ / 2),
/// θ the turning angle between the edges (0 = straight) [-]. `jacobian` = ∂κ/∂(x₀, x₁, x₂) [1/m].
/// False (κ and jacobian untouched) when an edge has zero length or the rod folds back on itself
/// (θ = π), where κ is not defined.
bool rodCurvature(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                  Eigen::Vector3d& kappa, Eigen::Matrix<double, 3, 9>& jacobian);

/// Discrete rod bending as a force element, one RodBend per interior particle of a chain. Energy
///   E = EI / (2 l̄) |κ|² = (2 EI / l̄) tan²(θ / 2)   [J],
/// which for small angles is EI θ² / (2 l̄), the Euler–Bernoulli energy EI κ_c² / 2 of curvature
/// κ_c = θ / l̄ over the length l̄: the same EI gives the same rope at any segment length. The tan
/// form depends on the angle only (stretching the edges leaves it unchanged) and grows without bound
/// as the rod folds back. Forces f = −k Jᵀκ − d Jᵀ J v (J = ∂κ/∂x, k = EI / l̄, d = η_b / l̄): the
/// damping resists the rate of curvature (Kelvin–Voigt). Jacobian blocks in the Gauss–Newton form
/// ∂f/∂x ≈ −k JᵀJ (exact on a straight rope, where κ = 0; the dropped term −k Σ κ_a ∇²κ_a is
/// first order in the bend), ∂f/∂v = −d JᵀJ: symmetric negative semi-definite, so the implicit
/// system stays positive definite, as Baraff–Witkin's bend condition does.
class RodBendingForce : public ForceElement
{
public:
  explicit RodBendingForce(RodBendingDef def) : def_(std::move(def)) {}

  const RodBendingDef& definition() const { return def_; }

  void addForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                 Eigen::Matrix3Xd& force) const override;
  /// Each element couples its three particles with each other.
  void coupledPairs(std::vector<std::pair<int, int>>& pairs) const override;
  void bindPattern(const ImplicitEulerSolver& solver) override;
  void addJacobians(const ForceContext& context, const Eigen::Matrix3Xd& x, ImplicitEulerSolver& solver) const override;
  /// Gershgorin rows k ‖J_m‖ Σ_n ‖J_n‖ (spectral norms of the 3×3 blocks of J at the rest positions),
  /// alike with d: on a straight uniform rope 16 EI / l³ at an interior particle, the largest
  /// eigenvalue of the discrete beam operator.
  void addStabilityRows(const std::vector<Eigen::Vector3d>& rest, std::vector<double>& stiffness_rows,
                        std::vector<double>& damping_rows) const override;
  /// Σ k / 2 |κ|² [J].
  void addEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, double& energy) const override;

  /// The element's 9×9 blocks ∂f/∂x (Gauss–Newton) and ∂f/∂v over its particles (v[0], v[1], v[2])
  /// at x [N/m], [N·s/m]; zero where κ is not defined.
  void jacobians(const RodBend& bend, const Eigen::Matrix3Xd& x, Eigen::Matrix<double, 9, 9>& dfdx,
                 Eigen::Matrix<double, 9, 9>& dfdv) const;

private:
  RodBendingDef def_;
  std::vector<std::array<int, 9>> blocks_;  // per bend, block (m, n) at 3m + n
};

}  // namespace core
}  // namespace particle_sim
