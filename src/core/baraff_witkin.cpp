#include "particle_sim/core/baraff_witkin.h"

#include <Eigen/Geometry>
#include <cmath>
#include <unsupported/Eigen/AutoDiff>

namespace particle_sim
{
namespace core
{
bool makeBwTriangle(int i, int j, int k, const Eigen::Vector2d& uv_i, const Eigen::Vector2d& uv_j,
                    const Eigen::Vector2d& uv_k, BwTriangle& t)
{
  // (Δu_1 Δu_2; Δv_1 Δv_2)⁻¹ = (1/D) (Δv_2 −Δu_2; −Δv_1 Δu_1), D = Δu_1 Δv_2 − Δu_2 Δv_1, so
  // w_u = (Δx_1 Δv_2 − Δx_2 Δv_1) / D and w_v = (Δx_2 Δu_1 − Δx_1 Δu_2) / D.
  const Eigen::Vector2d d1 = uv_j - uv_i, d2 = uv_k - uv_i;
  const double det = d1.x() * d2.y() - d2.x() * d1.y();
  if (!(std::abs(det) > 1e-14 * (d1.squaredNorm() + d2.squaredNorm())) || !std::isfinite(det)) return false;
  t.v = {i, j, k};
  t.area = 0.5 * std::abs(det);
  t.dwu = {0.0, d2.y() / det, -d1.y() / det};
  t.dwv = {0.0, -d2.x() / det, d1.x() / det};
  t.dwu[0] = -(t.dwu[1] + t.dwu[2]);
  t.dwv[0] = -(t.dwv[1] + t.dwv[2]);
  return true;
}

void stretchCondition(const BwTriangle& t, const Eigen::Matrix3d& x, double b_u, double b_v, Eigen::Vector2d& c,
                      std::array<Gradient9, 2>& gradients, std::array<Hessian9, 2>* hessians)
{
  // Each direction d ∈ {u, v}: C_d = a (|w_d| − b_d); ∂C_d/∂x_m = a dw_d[m] ŵ_d;
  // ∂²C_d/∂x_m∂x_n = a dw_d[m] dw_d[n] (I − ŵ_d ŵ_dᵀ) / |w_d|.
  const std::array<const std::array<double, 3>*, 2> coefficients = {&t.dwu, &t.dwv};
  const double rest[2] = {b_u, b_v};
  for (int d = 0; d < 2; ++d)
  {
    const auto& dw = *coefficients[d];
    const Eigen::Vector3d w = dw[0] * x.col(0) + dw[1] * x.col(1) + dw[2] * x.col(2);
    const double length = w.norm();
    const Eigen::Vector3d unit = length > 0.0 ? Eigen::Vector3d(w / length) : Eigen::Vector3d::Zero();
    c[d] = t.area * (length - rest[d]);
    for (int m = 0; m < 3; ++m)
      gradients[d].segment<3>(3 * m) = t.area * dw[m] * unit;
    if (!hessians) continue;
    const Eigen::Matrix3d projector =
        length > 0.0 ? Eigen::Matrix3d((Eigen::Matrix3d::Identity() - unit * unit.transpose()) / length)
                     : Eigen::Matrix3d::Zero();
    for (int m = 0; m < 3; ++m)
      for (int n = 0; n < 3; ++n)
        (*hessians)[d].block<3, 3>(3 * m, 3 * n) = t.area * dw[m] * dw[n] * projector;
  }
}

void shearCondition(const BwTriangle& t, const Eigen::Matrix3d& x, double& c, Gradient9& gradient, Hessian9* hessian)
{
  // C = a w_u·w_v; ∂C/∂x_m = a (dwu[m] w_v + dwv[m] w_u); ∂²C/∂x_m∂x_n = a (dwu[m] dwv[n] + dwv[m] dwu[n]) I.
  const Eigen::Vector3d wu = t.dwu[0] * x.col(0) + t.dwu[1] * x.col(1) + t.dwu[2] * x.col(2);
  const Eigen::Vector3d wv = t.dwv[0] * x.col(0) + t.dwv[1] * x.col(1) + t.dwv[2] * x.col(2);
  c = t.area * wu.dot(wv);
  for (int m = 0; m < 3; ++m)
    gradient.segment<3>(3 * m) = t.area * (t.dwu[m] * wv + t.dwv[m] * wu);
  if (!hessian) return;
  for (int m = 0; m < 3; ++m)
    for (int n = 0; n < 3; ++n)
      hessian->block<3, 3>(3 * m, 3 * n) =
          t.area * (t.dwu[m] * t.dwv[n] + t.dwv[m] * t.dwu[n]) * Eigen::Matrix3d::Identity();
}

double dihedralAngle(const Eigen::Matrix<double, 3, 4>& x)
{
  // Normals of (x_0, x_1, x_2) and (x_3, x_2, x_1), and the angle from the first to the second
  // measured about the edge x_2 → x_1 (the sign for which the gradient below holds).
  const Eigen::Vector3d na = (x.col(1) - x.col(0)).cross(x.col(2) - x.col(0));
  const Eigen::Vector3d nb = (x.col(2) - x.col(3)).cross(x.col(1) - x.col(3));
  const Eigen::Vector3d edge = (x.col(2) - x.col(1)).normalized();
  return std::atan2(nb.cross(na).dot(edge), na.dot(nb));
}

namespace
{
// The gradient of the dihedral angle (Bridson, Marino & Fedkiw 2003), written for any scalar type
// so that differentiating it automatically gives the exact Hessian. With N_a, N_b the triangle
// normals (unnormalised), E the shared edge and |E| its length:
//   ∂θ/∂x_0 = |E| N_a/|N_a|²,   ∂θ/∂x_3 = |E| N_b/|N_b|²,
//   ∂θ/∂x_1 = ((x_0 − x_2)·E/|E|) N_a/|N_a|² + ((x_3 − x_2)·E/|E|) N_b/|N_b|²,
//   ∂θ/∂x_2 = −((x_0 − x_1)·E/|E|) N_a/|N_a|² − ((x_3 − x_1)·E/|E|) N_b/|N_b|².
template <typename Scalar>
Eigen::Matrix<Scalar, 12, 1> dihedralGradient(const Eigen::Matrix<Scalar, 3, 4>& x)
{
  using Vector = Eigen::Matrix<Scalar, 3, 1>;
  const Vector x0 = x.col(0), x1 = x.col(1), x2 = x.col(2), x3 = x.col(3);
  const Vector na = (x1 - x0).cross(x2 - x0);
  const Vector nb = (x2 - x3).cross(x1 - x3);
  const Vector e = x2 - x1;
  const Scalar length = e.norm();
  const Vector ua = na / na.squaredNorm();
  const Vector ub = nb / nb.squaredNorm();
  Eigen::Matrix<Scalar, 12, 1> g;
  g.template segment<3>(0) = length * ua;
  g.template segment<3>(3) = ((x0 - x2).dot(e) / length) * ua + ((x3 - x2).dot(e) / length) * ub;
  g.template segment<3>(6) = -((x0 - x1).dot(e) / length) * ua - ((x3 - x1).dot(e) / length) * ub;
  g.template segment<3>(9) = length * ub;
  return g;
}
}  // namespace

void bendCondition(const BwBend& b, const Eigen::Matrix<double, 3, 4>& x, double& c, Gradient12& gradient,
                   Hessian12* hessian)
{
  c = std::remainder(dihedralAngle(x) - b.rest_angle, 2.0 * M_PI);
  gradient = dihedralGradient<double>(x);
  if (!hessian) return;
  // Forward-mode automatic differentiation of the gradient: one derivative per coordinate.
  using Dual = Eigen::AutoDiffScalar<Eigen::Matrix<double, 12, 1>>;
  Eigen::Matrix<Dual, 3, 4> xd;
  for (int m = 0; m < 4; ++m)
    for (int a = 0; a < 3; ++a)
      xd(a, m) = Dual(x(a, m), 12, 3 * m + a);
  const Eigen::Matrix<Dual, 12, 1> g = dihedralGradient<Dual>(xd);
  for (int r = 0; r < 12; ++r)
    hessian->row(r) = g[r].derivatives().transpose();
}

}  // namespace core
}  // namespace particle_sim
