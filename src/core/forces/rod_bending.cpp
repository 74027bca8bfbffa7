#include "particle_sim/core/forces/rod_bending.h"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace particle_sim
{
namespace core
{
namespace
{
using Gradient9 = Eigen::Matrix<double, 9, 1>;
using Block9 = Eigen::Matrix<double, 9, 9>;

Eigen::Matrix3d cross(const Eigen::Vector3d& a)
{
  Eigen::Matrix3d m;
  m << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return m;
}

/// Spectral norm of a 3×3 block [same unit as the block].
double spectralNorm(const Eigen::Matrix3d& block)
{
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(block.transpose() * block, Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, solver.eigenvalues().maxCoeff()));
}
}  // namespace

bool rodCurvature(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                  Eigen::Vector3d& kappa, Eigen::Matrix<double, 3, 9>& jacobian)
{
  const Eigen::Vector3d e1 = x1 - x0, e2 = x2 - x1;
  const double l1 = e1.norm(), l2 = e2.norm();
  // d = |e₁||e₂| (1 + cos θ) vanishes when the rod folds back (θ = π) and with a zero-length edge.
  const double d = l1 * l2 + e1.dot(e2);
  if (!(l1 > 0.0 && l2 > 0.0 && d > 1e-12 * l1 * l2)) return false;
  kappa = 2.0 * e1.cross(e2) / d;
  // κ = 2 b / d, b = e₁ × e₂: ∂b/∂e₁ = −[e₂]×, ∂b/∂e₂ = [e₁]×, ∂d/∂e₁ = |e₂| ê₁ + e₂, ∂d/∂e₂ = |e₁| ê₂ + e₁.
  const Eigen::Matrix3d de1 = (-2.0 * cross(e2) - kappa * (l2 / l1 * e1 + e2).transpose()) / d;
  const Eigen::Matrix3d de2 = (2.0 * cross(e1) - kappa * (l1 / l2 * e2 + e1).transpose()) / d;
  // e₁ = x₁ − x₀, e₂ = x₂ − x₁.
  jacobian.block<3, 3>(0, 0) = -de1;
  jacobian.block<3, 3>(0, 3) = de1 - de2;
  jacobian.block<3, 3>(0, 6) = de2;
  return true;
}

void RodBendingForce::addForces(const ForceContext& /*context*/, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                                Eigen::Matrix3Xd& force) const
{
  // f = −J ᵀ (k κ + d κ̇), κ̇ = J u (u the corner velocities).
  for (const RodBend& bend : def_.bends)
  {
    Eigen::Vector3d kappa;
    Eigen::Matrix<double, 3, 9> jacobian;
    if (!rodCurvature(x.col(bend.v[0]), x.col(bend.v[1]), x.col(bend.v[2]), kappa, jacobian)) continue;
    Gradient9 u;
    for (int m = 0; m < 3; ++m)
      u.segment<3>(3 * m) = v.col(bend.v[m]);
    const Gradient9 f = -jacobian.transpose() * (bend.stiffness * kappa + bend.damping * (jacobian * u));
    for (int m = 0; m < 3; ++m)
      force.col(bend.v[m]) += f.segment<3>(3 * m);
  }
}

void RodBendingForce::coupledPairs(std::vector<std::pair<int, int>>& pairs) const
{
  for (const RodBend& bend : def_.bends)
  {
    pairs.emplace_back(bend.v[0], bend.v[1]);
    pairs.emplace_back(bend.v[1], bend.v[2]);
    pairs.emplace_back(bend.v[0], bend.v[2]);
  }
}

void RodBendingForce::bindPattern(const ImplicitEulerSolver& solver)
{
  blocks_.clear();
  for (const RodBend& bend : def_.bends)
  {
    std::array<int, 9> blocks;
    for (int m = 0; m < 3; ++m)
      for (int n = 0; n < 3; ++n)
        blocks[3 * m + n] = solver.blockIndex(bend.v[m], bend.v[n]);
    blocks_.push_back(blocks);
  }
}

void RodBendingForce::jacobians(const RodBend& bend, const Eigen::Matrix3Xd& x, Eigen::Matrix<double, 9, 9>& dfdx,
                                Eigen::Matrix<double, 9, 9>& dfdv) const
{
  Eigen::Vector3d kappa;
  Eigen::Matrix<double, 3, 9> jacobian;
  if (!rodCurvature(x.col(bend.v[0]), x.col(bend.v[1]), x.col(bend.v[2]), kappa, jacobian))
  {
    dfdx.setZero();
    dfdv.setZero();
    return;
  }
  const Block9 outer = jacobian.transpose() * jacobian;
  dfdx = -bend.stiffness * outer;
  dfdv = -bend.damping * outer;
}

void RodBendingForce::addJacobians(const ForceContext& /*context*/, const Eigen::Matrix3Xd& x,
                                   ImplicitEulerSolver& solver) const
{
  Block9 dfdx, dfdv;
  for (std::size_t k = 0; k < def_.bends.size(); ++k)
  {
    jacobians(def_.bends[k], x, dfdx, dfdv);
    for (int m = 0; m < 3; ++m)
      for (int n = 0; n < 3; ++n)
        solver.addBlock(blocks_[k][3 * m + n], dfdx.block<3, 3>(3 * m, 3 * n), dfdv.block<3, 3>(3 * m, 3 * n));
  }
}

void RodBendingForce::addStabilityRows(const std::vector<Eigen::Vector3d>& rest, std::vector<double>& stiffness_rows,
                                       std::vector<double>& damping_rows) const
{
  for (const RodBend& bend : def_.bends)
  {
    Eigen::Vector3d kappa;
    Eigen::Matrix<double, 3, 9> jacobian;
    if (!rodCurvature(rest[bend.v[0]], rest[bend.v[1]], rest[bend.v[2]], kappa, jacobian)) continue;
    std::array<double, 3> norms;
    double sum = 0.0;
    for (int m = 0; m < 3; ++m)
    {
      norms[m] = spectralNorm(jacobian.block<3, 3>(0, 3 * m));
      sum += norms[m];
    }
    for (int m = 0; m < 3; ++m)
    {
      stiffness_rows[bend.v[m]] += bend.stiffness * norms[m] * sum;
      damping_rows[bend.v[m]] += bend.damping * norms[m] * sum;
    }
  }
}

void RodBendingForce::addEnergy(const ForceContext& /*context*/, const Eigen::Matrix3Xd& x, double& energy) const
{
  for (const RodBend& bend : def_.bends)
  {
    Eigen::Vector3d kappa;
    Eigen::Matrix<double, 3, 9> jacobian;
    if (rodCurvature(x.col(bend.v[0]), x.col(bend.v[1]), x.col(bend.v[2]), kappa, jacobian))
      energy += 0.5 * bend.stiffness * kappa.squaredNorm();
  }
}

}  // namespace core
}  // namespace particle_sim
