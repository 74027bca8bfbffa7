#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "particle_sim/core/forces/force_element.h"
#include "particle_sim/core/integrators/implicit_euler_solver.h"

namespace particle_sim
{
namespace core
{
/// Isotropic plate bending of a triangle mesh that is flat at rest, one stencil per interior vertex.
/// A stencil is the vertex's row of the cotangent Laplacian of the flat rest pattern:
///   y_v = Σ_k w_k x_k = ½ Σ_j (cot α_vj + cot β_vj) (x_v − x_j)   [m²]
/// (j its neighbours, α and β the angles opposite the edge vj), the mean curvature normal integrated
/// over the vertex's area, y_v ≈ 2 H n A_v. Each stencil's weights sum to zero, and y_v = 0 for
/// every interior vertex of a flat mesh.
struct PlateBendingDef
{
  std::vector<int> row_start;        ///< stencil s has entries row_start[s] .. row_start[s + 1] − 1
  std::vector<int> particles;        ///< per entry: the particle
  std::vector<double> weights;       ///< per entry: its cotangent weight w_k [-]
  std::vector<double> inverse_area;  ///< per stencil: 1 / A_v, A_v a third of the rest area of its triangles [1/m²]
  double rigidity = 0.0;             ///< B [N·m]
  double damping = 0.0;              ///< bending viscosity [N·m·s] (B times a time)

  int stencils() const { return static_cast<int>(inverse_area.size()); }
  bool empty() const { return inverse_area.empty(); }
};

/// The plate bending of the flat pattern `rest` (2-D points [m], e.g. a cloth's texture coordinates
/// scaled to its area) and its `triangles`: one stencil per interior vertex (a vertex on an edge used
/// by one triangle only is on the border and has none). False (with `error`) when a triangle has no
/// area in the pattern.
bool buildPlateBending(const std::vector<Eigen::Vector2d>& rest, const std::vector<Eigen::Vector3i>& triangles,
                       double rigidity, double damping, PlateBendingDef& def, std::string& error);

/// Isotropic plate bending as a force element (Wardetzky et al. 2007, "Discrete quadratic curvature
/// energies"; Bergou et al. 2006, "A quadratic bending model for inextensible surfaces"):
///   E = B/2 Σ_v |y_v|² / A_v   [J],
/// which tends to B/2 ∫ (κ₁ + κ₂)² dA, the plate's B/2 ∫ (κ₁² + κ₂²) dA wherever the sheet is not
/// stretched (an isometric bending of a flat sheet has κ₁ κ₂ = 0): the same B bends the same in every
/// direction and at every resolution (unit test: a cylinder at any angle to the mesh, second-order).
/// E is quadratic in x, so its Hessian is constant: f = −∂E/∂x − (η/B) ∂²E/∂x² v, and the Jacobian
/// blocks ∂f_a/∂x_b = −B Σ_v w_va w_vb / A_v I (∂f/∂v alike with η) are symmetric negative
/// semi-definite. It is invariant under rigid motions (y_v turns with the sheet) and under
/// stretching it does not see (it reads positions, not lengths): the membrane is another element's.
class PlateBendingForce : public ForceElement
{
public:
  explicit PlateBendingForce(PlateBendingDef def)
      : def_(std::move(def)), built_rigidity_(def_.rigidity), built_damping_(def_.damping)
  {}

  const PlateBendingDef& definition() const { return def_; }

  void addForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                 Eigen::Matrix3Xd& force) const override;
  /// Each stencil couples all of its particles with each other (a vertex's neighbours across it too).
  void coupledPairs(std::vector<std::pair<int, int>>& pairs) const override;
  void bindPattern(const ImplicitEulerSolver& solver) override;
  void addJacobians(const ForceContext& context, const Eigen::Matrix3Xd& x, ImplicitEulerSolver& solver) const override;
  /// Gershgorin rows B / A_v |w_va| Σ_b |w_vb| (alike with η).
  void addStabilityRows(const std::vector<Eigen::Vector3d>& rest, std::vector<double>& stiffness_rows,
                        std::vector<double>& damping_rows) const override;
  /// B/2 Σ_v |y_v|² / A_v [J].
  void addEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, double& energy) const override;

  /// The bend class: B [N·m] and the bending viscosity [N·m·s], as Baraff–Witkin's bend.
  bool hasClass(SpringClass spring_class) const override { return spring_class == SpringClass::Bend; }
  void setClassConstants(std::optional<SpringClass> spring_class, double stiffness, double damping) override;
  void resetConstants() override;

private:
  // y_v of stencil s at x.
  Eigen::Vector3d curvatureNormal(int s, const Eigen::Matrix3Xd& x) const;

  PlateBendingDef def_;
  double built_rigidity_, built_damping_;  // what resetConstants() puts back
  std::vector<int> blocks_;  // per stencil, its m × m blocks (row-major) from blocks_start_[s]
  std::vector<int> blocks_start_;
};

}  // namespace core
}  // namespace particle_sim
