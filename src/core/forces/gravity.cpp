#include "particle_sim/core/forces/gravity.h"

namespace particle_sim
{
namespace core
{
void GravityForce::addForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& /*v*/,
                             Eigen::Matrix3Xd& force) const
{
  shareLoop(context.workers, static_cast<int>(x.cols()), kParticlesPerVectorChunk, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
      force.col(i) += context.mass[i] * context.gravity;
  });
}

void GravityForce::addEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, double& energy) const
{
  for (int i = 0; i < x.cols(); ++i)
  {
    if (!context.pinned[i]) energy -= context.mass[i] * context.gravity.dot(x.col(i));
  }
}

}  // namespace core
}  // namespace particle_sim
