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
  // setForces()'s force on particle i, 0 + m_i g, written to its three numbers (on the arrays'
  // numbers: Eigen's 3-vector expressions cost some 46 instructions a particle in these passes).
  static void setForceOn(const ForceContext& context, int i, double* force)
  {
    const double m = context.mass[i];
    double* const f = force + 3L * i;
    f[0] = m * context.gravity.x() + 0.0;
    f[1] = m * context.gravity.y() + 0.0;
    f[2] = m * context.gravity.z() + 0.0;
  }
  // The energy of particle i at x (addEnergy()'s term): m_i g·x_i, the dot product as Eigen sums it,
  // (g_x x + g_y y) + g_z z.
  static double energyOf(const ForceContext& context, const double* x, int i)
  {
    const double* const p = x + 3L * i;
    const Eigen::Vector3d& g = context.gravity;
    return context.pinned[i] ? 0.0 : context.mass[i] * ((g.x() * p[0] + g.y() * p[1]) + g.z() * p[2]);
  }

  mutable std::vector<double> chunk_energy_;  // addEnergy(): per chunk of particles, its energy
  mutable double kept_sum_ = 0.0;             // setForcesKeepingEnergy(): addEnergy()'s sum at its x
  mutable bool energy_kept_ = false;          // kept_sum_ is of the last setForcesKeepingEnergy()'s x
};

}  // namespace core
}  // namespace particle_sim
