#pragma once

#include <vector>

#include "particle_sim/core/forces/force_element.h"

namespace particle_sim
{
namespace core
{
/// Gravity, the lecture's f^g of the mass-spring loop: f_i = m_i g on every particle, with
/// potential energy −m_i g·x_i on free particles (z = 0 at 0). Constant in (x, v): no Jacobian,
/// no stability row.
class GravityForce : public ForceElement
{
public:
  void addForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                 Eigen::Matrix3Xd& force) const override;
  /// One pass that writes 0 + m_i g (without the zeroing pass).
  void setForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                 Eigen::Matrix3Xd& force) const override;
  void addEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, double& energy) const override;
  /// setForces() and addEnergy()'s sums in one pass over the particles.
  void setForcesKeepingEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                              Eigen::Matrix3Xd& force) const override;
  void addKeptEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, double& energy) const override;

private:
  // setForces()'s force on particle i: 0 + m_i g.
  static Eigen::Vector3d forceOn(const ForceContext& context, int i)
  {
    return (context.mass[i] * context.gravity).array() + 0.0;
  }
  // The energy of one particle at x (addEnergy()'s term).
  static double energyOf(const ForceContext& context, const Eigen::Matrix3Xd& x, int i)
  {
    return context.pinned[i] ? 0.0 : context.mass[i] * context.gravity.dot(x.col(i));
  }

  mutable std::vector<double> chunk_energy_;  // addEnergy(): per chunk of particles, its energy
  mutable double kept_sum_ = 0.0;             // setForcesKeepingEnergy(): addEnergy()'s sum at its x
  mutable bool energy_kept_ = false;          // kept_sum_ is of the last setForcesKeepingEnergy()'s x
};

}  // namespace core
}  // namespace particle_sim
