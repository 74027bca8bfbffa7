#pragma once

#include "particle_sim/core/forces/force_element.h"

namespace particle_sim
{
namespace core
{
/// Global damping (Environment::damping c [1/s]), mass-proportional Rayleigh damping:
/// f_i = −c m_i v_i, with ∂f_i/∂v_i = −c m_i I. It adds the same rate c to every row of the
/// stability bound. Dissipative: no energy.
class GlobalDampingForce : public ForceElement
{
public:
  void addForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                 Eigen::Matrix3Xd& force) const override;
  void addJacobians(const ForceContext& context, const Eigen::Matrix3Xd& x, ImplicitEulerSolver& solver) const override;
  double uniformDampingRate(const ForceContext& context) const override { return context.damping; }
};

}  // namespace core
}  // namespace particle_sim
