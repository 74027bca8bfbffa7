#include "particle_sim/core/implicit_euler_solver.h"

#include <Eigen/LU>
#include <cmath>

namespace particle_sim
{
namespace core
{
namespace
{
double dot(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b) { return a.cwiseProduct(b).sum(); }
}  // namespace

void ImplicitEulerSolver::resize(int particles, int springs)
{
  dfdx_.assign(springs, Eigen::Matrix3d::Zero());
  system_block_.assign(springs, Eigen::Matrix3d::Zero());
  inverse_diagonal_.assign(particles, Eigen::Matrix3d::Identity());
  for (Eigen::Matrix3Xd* m : {&delta_v_, &rhs_, &residual_, &direction_, &product_, &preconditioned_})
    m->setZero(3, particles);
}

void ImplicitEulerSolver::multiply(const std::vector<Spring>& springs, const Eigen::VectorXd& mass,
                                   const Eigen::Matrix3Xd& p, Eigen::Matrix3Xd& out) const
{
  for (int i = 0; i < p.cols(); ++i) out.col(i) = mass[i] * p.col(i);
  for (std::size_t s = 0; s < springs.size(); ++s)
  {
    const Eigen::Vector3d term = system_block_[s] * (p.col(springs[s].i) - p.col(springs[s].j));
    out.col(springs[s].i) -= term;
    out.col(springs[s].j) += term;
  }
}

void ImplicitEulerSolver::filter(const std::vector<char>& pinned, Eigen::Matrix3Xd& p)
{
  for (int i = 0; i < p.cols(); ++i)
  {
    if (pinned[i]) p.col(i).setZero();
  }
}

void ImplicitEulerSolver::precondition(const Eigen::Matrix3Xd& r, Eigen::Matrix3Xd& out) const
{
  for (int i = 0; i < r.cols(); ++i) out.col(i) = inverse_diagonal_[i] * r.col(i);
}

SolverReport ImplicitEulerSolver::step(double h, const std::vector<Spring>& springs, const Eigen::VectorXd& mass,
                                       const std::vector<char>& pinned, const Eigen::Matrix3Xd& force,
                                       double tolerance, int max_iterations, Eigen::Matrix3Xd& x,
                                       Eigen::Matrix3Xd& v)
{
  const int n = static_cast<int>(x.cols());

  // 1. Per-spring Jacobian blocks, the system blocks S and the right-hand side
  //    b = h (f0 + h ∂f/∂x v0).
  rhs_ = h * force;
  for (int i = 0; i < n; ++i) inverse_diagonal_[i] = mass[i] * Eigen::Matrix3d::Identity();
  for (std::size_t s = 0; s < springs.size(); ++s)
  {
    const Spring& spring = springs[s];
    Eigen::Matrix3d dfdv;
    springJacobians(x.col(spring.i), x.col(spring.j), spring.rest_length, spring.stiffness, spring.damping, true,
                    dfdx_[s], dfdv);
    system_block_[s] = h * dfdv + h * h * dfdx_[s];
    const Eigen::Vector3d kv = h * h * (dfdx_[s] * (v.col(spring.i) - v.col(spring.j)));
    rhs_.col(spring.i) += kv;
    rhs_.col(spring.j) -= kv;
    // The diagonal blocks of A gain −S at both ends.
    inverse_diagonal_[spring.i] -= system_block_[s];
    inverse_diagonal_[spring.j] -= system_block_[s];
  }
  for (int i = 0; i < n; ++i) inverse_diagonal_[i] = inverse_diagonal_[i].inverse().eval();

  // 2. Modified preconditioned CG from Δv = 0, with pinned rows filtered out.
  SolverReport report;
  delta_v_.setZero();
  residual_ = rhs_;
  filter(pinned, residual_);
  const double rhs_norm = std::sqrt(dot(residual_, residual_));
  precondition(residual_, direction_);
  filter(pinned, direction_);
  double delta_new = dot(residual_, direction_);
  double residual_norm = rhs_norm;
  while (residual_norm > tolerance * rhs_norm && report.iterations < max_iterations)
  {
    multiply(springs, mass, direction_, product_);
    filter(pinned, product_);
    const double curvature = dot(direction_, product_);
    if (!(curvature > 0.0))
    {
      report.breakdown = true;  // not positive definite (or NaN): the solve failed
      break;
    }
    const double alpha = delta_new / curvature;
    delta_v_ += alpha * direction_;
    residual_ -= alpha * product_;
    precondition(residual_, preconditioned_);
    const double delta_old = delta_new;
    delta_new = dot(residual_, preconditioned_);
    direction_ = preconditioned_ + (delta_new / delta_old) * direction_;
    filter(pinned, direction_);
    residual_norm = std::sqrt(dot(residual_, residual_));
    ++report.iterations;
  }
  report.relative_residual = rhs_norm > 0.0 ? residual_norm / rhs_norm : 0.0;
  report.converged = residual_norm <= tolerance * rhs_norm;

  // 3. v1 = v0 + Δv, x1 = x0 + h v1 (pinned particles keep the velocity that carries them to
  //    their target, since their Δv is 0).
  v += delta_v_;
  x += h * v;
  return report;
}

}  // namespace core
}  // namespace particle_sim
