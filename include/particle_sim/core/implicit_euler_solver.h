#pragma once

#include <Eigen/Core>
#include <vector>

#include "particle_sim/core/integrator.h"
#include "particle_sim/core/spring.h"

namespace particle_sim
{
namespace core
{
/// One step of linearised backward Euler for a mass-spring system (Baraff & Witkin 1998):
///
///   (M − h ∂f/∂v − h² ∂f/∂x) Δv = h (f0 + h ∂f/∂x v0),   v1 = v0 + Δv,   x1 = x0 + h v1,
///
/// solved by their modified preconditioned conjugate gradient: pinned particles' Δv is held at 0
/// by filtering every search direction and residual (no huge masses), with a 3x3 block-Jacobi
/// preconditioner. The matrix is never assembled: each spring keeps its 3x3 block
/// S = h ∂f_i/∂v_i + h² ∂f_i/∂x_i, which acts as +S on (i, j) and −S on (i, i) (and alike for j).
/// The spring Jacobians use the definite form (see springJacobians), so the system is symmetric
/// positive definite.
///
/// All memory is sized by resize(); step() allocates nothing.
class ImplicitEulerSolver
{
public:
  void resize(int particles, int springs);

  /// Advances x and v by h. `force` is f0 = f(x0, v0); `pinned[i]` marks kinematic particles,
  /// whose velocity in v must already be the one that carries them to their target (it is kept).
  SolverReport step(double h, const std::vector<Spring>& springs, const Eigen::VectorXd& mass,
                    const std::vector<char>& pinned, const Eigen::Matrix3Xd& force, double tolerance,
                    int max_iterations, Eigen::Matrix3Xd& x, Eigen::Matrix3Xd& v);

private:
  // out = A p, with A = M − Σ_springs (block pattern of S).
  void multiply(const std::vector<Spring>& springs, const Eigen::VectorXd& mass, const Eigen::Matrix3Xd& p,
                Eigen::Matrix3Xd& out) const;
  // Zeroes the rows of pinned particles (the filter S of Baraff & Witkin).
  static void filter(const std::vector<char>& pinned, Eigen::Matrix3Xd& p);
  // out = P⁻¹ r with the block-Jacobi preconditioner.
  void precondition(const Eigen::Matrix3Xd& r, Eigen::Matrix3Xd& out) const;

  std::vector<Eigen::Matrix3d> dfdx_;          // per spring, ∂f_i/∂x_i
  std::vector<Eigen::Matrix3d> system_block_;  // per spring, S = h ∂f/∂v + h² ∂f/∂x
  std::vector<Eigen::Matrix3d> inverse_diagonal_;  // per particle, (diagonal 3x3 block of A)⁻¹
  Eigen::Matrix3Xd delta_v_, rhs_, residual_, direction_, product_, preconditioned_;
};

}  // namespace core
}  // namespace particle_sim
