#pragma once

#include <Eigen/Core>
#include <array>

namespace particle_sim
{
namespace core
{
/// Baraff & Witkin (1998) cloth conditions, as stateless kernels (the lecture's "B-W" slides).
///
/// Each triangle (x_0, x_1, x_2) has rest (u, v) coordinates; the map w(u, v) from rest to world
/// coordinates has the derivatives
///   (w_u w_v) = (Δx_1 Δx_2) (Δu_1 Δu_2; Δv_1 Δv_2)⁻¹,  Δx_1 = x_1 − x_0, Δx_2 = x_2 − x_0 (alike for u, v),
/// which are linear in the positions: w_u = Σ_m dwu[m] x_m, w_v = Σ_m dwv[m] x_m.
///
/// Conditions (energy E = k/2 CᵀC, force f = −k (∂C/∂x) C, Jacobian
/// K_mn = −k (∂C/∂x_m ∂C/∂x_nᵀ + ∂²C/∂x_m∂x_n C), damping f = −k_d (∂C/∂x) Ċ):
///   stretch  C = a (|w_u| − b_u, |w_v| − b_v)   a = rest area [m²]
///   shear    C = a w_uᵀ w_v
///   bend     C = θ − θ₀                          θ = dihedral angle across an interior edge
/// Units: stretch and shear stiffness [N/m³] (C is in m², so E = k C²/2 is in J), bend stiffness
/// [N·m] (J per rad²); damping likewise per second.

/// Rest data of one triangle: corner indices, rest area and the w_u, w_v coefficients.
struct BwTriangle
{
  std::array<int, 3> v{};
  double area = 0.0;                   ///< a [m²], in (u, v) space
  std::array<double, 3> dwu{}, dwv{};  ///< ∂w_u/∂x_m = dwu[m] I, ∂w_v/∂x_m = dwv[m] I
};

/// Rest data of one bend element: triangles (x_0, x_1, x_2) and (x_3, x_2, x_1) sharing the edge
/// x_1 → x_2; θ₀ is the dihedral angle at rest.
struct BwBend
{
  std::array<int, 4> v{};
  double rest_angle = 0.0;  ///< θ₀ [rad]
};

/// Builds a triangle's rest data from its (u, v) coordinates [m]; false when they are degenerate
/// (zero area in (u, v)).
bool makeBwTriangle(int i, int j, int k, const Eigen::Vector2d& uv_i, const Eigen::Vector2d& uv_j,
                    const Eigen::Vector2d& uv_k, BwTriangle& triangle);

using Gradient9 = Eigen::Matrix<double, 9, 1>;
using Hessian9 = Eigen::Matrix<double, 9, 9>;
using Gradient12 = Eigen::Matrix<double, 12, 1>;
using Hessian12 = Eigen::Matrix<double, 12, 12>;

/// Stretch condition of `t` at corner positions x (3 x 3, columns x_0..x_2): C, the gradients
/// ∂C_u/∂x and ∂C_v/∂x (9-vectors: corner-major), and when `hessians` is given their exact
/// Hessians ∂²C_u/∂x², ∂²C_v/∂x².
void stretchCondition(const BwTriangle& t, const Eigen::Matrix3d& x, double b_u, double b_v, Eigen::Vector2d& c,
                      std::array<Gradient9, 2>& gradients, std::array<Hessian9, 2>* hessians = nullptr);

/// Shear condition C = a w_uᵀ w_v, its gradient and (optionally) exact Hessian.
void shearCondition(const BwTriangle& t, const Eigen::Matrix3d& x, double& c, Gradient9& gradient,
                    Hessian9* hessian = nullptr);

/// The dihedral angle θ ∈ (−π, π] of a bend element at corner positions x (3 x 4), 0 when flat.
double dihedralAngle(const Eigen::Matrix<double, 3, 4>& x);

/// Bend condition C = θ − θ₀ (wrapped to (−π, π]), its gradient (Bridson et al. 2003) and,
/// optionally, its exact Hessian (by automatic differentiation; for checks and small meshes).
void bendCondition(const BwBend& b, const Eigen::Matrix<double, 3, 4>& x, double& c, Gradient12& gradient,
                   Hessian12* hessian = nullptr);

}  // namespace core
}  // namespace particle_sim
