#pragma once

#include <vector>

#include "particle_sim/core/forces/force_element.h"

namespace particle_sim
{
namespace core
{
/// Air on the surface triangles of cloth and jelly: Provot's (1995) viscous fluid force
/// f = C ((u_fluid − v)·n) n, taken per triangle of area A and unit normal n moving at the mean
/// velocity v̄ of its corners: f = drag · A · ((wind − v̄)·n) n, shared equally by the three
/// corners (AirDef). Treated explicitly by the implicit step (no Jacobian); with wind it does
/// work on the body.
class AirForce : public ForceElement
{
public:
  explicit AirForce(std::vector<Eigen::Vector3i> triangles) : built_(triangles), triangles_(std::move(triangles)) {}

  void addForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                 Eigen::Matrix3Xd& force) const override;
  bool suppliesEnergy(const ForceContext& context) const override
  {
    return context.air.drag != 0.0 && !context.air.wind.isZero();
  }

  /// The air acts on the triangles a tear left.
  void setSurface(const std::vector<Eigen::Vector3i>& triangles) override { triangles_ = triangles; }
  void mend() override { triangles_ = built_; }

private:
  std::vector<Eigen::Vector3i> built_;  // the surface as built
  std::vector<Eigen::Vector3i> triangles_;
};

}  // namespace core
}  // namespace particle_sim
