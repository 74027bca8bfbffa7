#include "particle_sim/core/forces/force_set.h"

#include <algorithm>

namespace particle_sim
{
namespace core
{
void ForceSet::add(std::unique_ptr<ForceElement> element)
{
  energy_order_.push_back(static_cast<int>(elements_.size()));
  elements_.push_back(std::move(element));
}

void ForceSet::setEnergyOrder(std::vector<int> order)
{
  energy_order_ = std::move(order);
}

void ForceSet::computeForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                             Eigen::Matrix3Xd& force) const
{
  if (elements_.empty())
  {
    force.setZero();
    return;
  }
  // The first element writes its forces onto nothing (gravity, in every body, without a pass of
  // its own to zero them); the others add theirs.
  elements_.front()->setForces(context, x, v, force);
  for (std::size_t e = 1; e < elements_.size(); ++e)
    elements_[e]->addForces(context, x, v, force);
}

void ForceElement::setForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                             Eigen::Matrix3Xd& force) const
{
  shareLoop(context.workers, static_cast<int>(force.cols()), kParticlesPerVectorChunk,
            [&](int begin, int end) { force.middleCols(begin, end - begin).setZero(); });
  addForces(context, x, v, force);
}

void ForceSet::coupledPairs(std::vector<std::pair<int, int>>& pairs) const
{
  for (const std::unique_ptr<ForceElement>& element : elements_)
    element->coupledPairs(pairs);
}

void ForceSet::bindPattern(const ImplicitEulerSolver& solver)
{
  for (const std::unique_ptr<ForceElement>& element : elements_)
    element->bindPattern(solver);
}

void ForceSet::addJacobians(const ForceContext& context, const Eigen::Matrix3Xd& x, ImplicitEulerSolver& solver) const
{
  for (const std::unique_ptr<ForceElement>& element : elements_)
    element->addJacobians(context, x, solver);
}

void ForceSet::addStabilityRows(const std::vector<Eigen::Vector3d>& rest, std::vector<double>& stiffness_rows,
                                std::vector<double>& damping_rows) const
{
  for (const std::unique_ptr<ForceElement>& element : elements_)
    element->addStabilityRows(rest, stiffness_rows, damping_rows);
}

double ForceSet::uniformDampingRate(const ForceContext& context) const
{
  double rate = 0.0;
  for (const std::unique_ptr<ForceElement>& element : elements_)
    rate += element->uniformDampingRate(context);
  return rate;
}

double ForceSet::energy(const ForceContext& context, const Eigen::Matrix3Xd& x) const
{
  double energy = 0.0;
  for (int index : energy_order_)
    elements_[index]->addEnergy(context, x, energy);
  return energy;
}

double ForceSet::computeForcesAndEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x,
                                        const Eigen::Matrix3Xd& v, Eigen::Matrix3Xd& force) const
{
  if (elements_.empty())
  {
    force.setZero();
    return 0.0;
  }
  // computeForces()'s order, each element keeping its energy on the way where it can.
  elements_.front()->setForcesKeepingEnergy(context, x, v, force);
  for (std::size_t e = 1; e < elements_.size(); ++e)
    elements_[e]->addForcesKeepingEnergy(context, x, v, force);
  double energy = 0.0;
  for (int index : energy_order_)
    elements_[index]->addKeptEnergy(context, x, energy);
  return energy;
}

bool ForceSet::suppliesEnergy(const ForceContext& context) const
{
  for (const std::unique_ptr<ForceElement>& element : elements_)
  {
    if (element->suppliesEnergy(context)) return true;
  }
  return false;
}

bool ForceSet::hasClass(SpringClass spring_class) const
{
  for (const std::unique_ptr<ForceElement>& element : elements_)
  {
    if (element->hasClass(spring_class)) return true;
  }
  return false;
}

void ForceSet::setClassConstants(std::optional<SpringClass> spring_class, double stiffness, double damping)
{
  for (const std::unique_ptr<ForceElement>& element : elements_)
    element->setClassConstants(spring_class, stiffness, damping);
}

void ForceSet::resetConstants()
{
  for (const std::unique_ptr<ForceElement>& element : elements_)
    element->resetConstants();
}

double ForceSet::maxStrain(const Eigen::Matrix3Xd& x) const
{
  double strain = 0.0;
  for (const std::unique_ptr<ForceElement>& element : elements_)
    strain = std::max(strain, element->maxStrain(x));
  return strain;
}

void ForceSet::tear(const Eigen::Matrix3Xd& x, double tear_strain, TearRecord& torn)
{
  torn.clear();
  for (const std::unique_ptr<ForceElement>& element : elements_)
    element->tear(x, tear_strain, torn);
}

void ForceSet::setSurface(const std::vector<Eigen::Vector3i>& triangles)
{
  for (const std::unique_ptr<ForceElement>& element : elements_)
    element->setSurface(triangles);
}

void ForceSet::mend()
{
  for (const std::unique_ptr<ForceElement>& element : elements_)
    element->mend();
}

void ForceSet::splitParticle(int original, int copy, const std::vector<int>& neighbours,
                             const std::vector<Eigen::Vector3i>& triangles)
{
  for (const std::unique_ptr<ForceElement>& element : elements_)
    element->splitParticle(original, copy, neighbours, triangles);
}

}  // namespace core
}  // namespace particle_sim
