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

void GravityForce::setForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& /*v*/,
                             Eigen::Matrix3Xd& force) const
{
  // 0.0 + (m g) rather than m g: the sum with the zeroed force the other elements start from
  // (it turns a −0 into +0), kept by the compiler as it would change that sign.
  double* const fs = force.data();
  shareLoop(context.workers, static_cast<int>(x.cols()), kParticlesPerVectorChunk, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
      setForceOn(context, i, fs);
  });
}

void GravityForce::addEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, double& energy) const
{
  // Summed in fixed chunks of particles, shared between threads: the same bits at any thread count.
  const double* const xs = x.data();
  energy -= sumByChunks(context.workers, static_cast<int>(x.cols()), kParticlesPerVectorChunk, chunk_energy_,
                        [&](int i) { return energyOf(context, xs, i); });
}

void GravityForce::setForcesKeepingEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x,
                                          const Eigen::Matrix3Xd& /*v*/, Eigen::Matrix3Xd& force) const
{
  // setForces()'s forces and addEnergy()'s chunks, summed in its order: the same bits as both.
  const double* const xs = x.data();
  double* const fs = force.data();
  kept_sum_ = sumChunks(context.workers, static_cast<int>(x.cols()), kParticlesPerVectorChunk, chunk_energy_,
                        [&](int first, int last) {
                          double sum = 0.0;
                          for (int i = first; i < last; ++i)
                          {
                            setForceOn(context, i, fs);
                            sum += energyOf(context, xs, i);
                          }
                          return sum;
                        });
  energy_kept_ = true;
}

void GravityForce::addKeptEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, double& energy) const
{
  if (!energy_kept_)
  {
    addEnergy(context, x, energy);
    return;
  }
  energy_kept_ = false;
  energy -= kept_sum_;
}

}  // namespace core
}  // namespace particle_sim
