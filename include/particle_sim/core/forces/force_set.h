#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "particle_sim/core/forces/force_element.h"

namespace particle_sim
{
namespace core
{
/// The force elements of one body, asked in a fixed order. Forces, Jacobian blocks and stability
/// rows are summed in the order the elements were added; energies in the energy order (by
/// default the same). Floating-point sums depend on their order, so these orders are part of
/// the engine's determinism.
class ForceSet
{
public:
  /// Appends `element` (not null).
  void add(std::unique_ptr<ForceElement> element);
  /// Sums energies over the elements in `order` (indices in add() order, each once).
  void setEnergyOrder(std::vector<int> order);

  /// force = Σ elements' forces at (x, v) [N].
  void computeForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                     Eigen::Matrix3Xd& force) const;
  /// Every element's coupled pairs, for the implicit solver's pattern.
  void coupledPairs(std::vector<std::pair<int, int>>& pairs) const;
  void bindPattern(const ImplicitEulerSolver& solver);
  void addJacobians(const ForceContext& context, const Eigen::Matrix3Xd& x, ImplicitEulerSolver& solver) const;
  void addStabilityRows(const std::vector<Eigen::Vector3d>& rest, std::vector<double>& stiffness_rows,
                        std::vector<double>& damping_rows) const;
  double uniformDampingRate(const ForceContext& context) const;
  /// Σ potential energies at x [J].
  double energy(const ForceContext& context, const Eigen::Matrix3Xd& x) const;
  /// computeForces(), returning energy(context, x) with the same bits: the springs' energy comes
  /// out of their force pass (no pass of its own over the springs).
  double computeForcesAndEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                                Eigen::Matrix3Xd& force) const;
  bool suppliesEnergy(const ForceContext& context) const;
  bool hasClass(SpringClass spring_class) const;
  void setClassConstants(std::optional<SpringClass> spring_class, double stiffness, double damping);
  void resetConstants();
  double maxStrain(const Eigen::Matrix3Xd& x) const;
  /// Every element's tear, in add() order; `torn` is cleared first.
  void tear(const Eigen::Matrix3Xd& x, double tear_strain, TearRecord& torn);
  void setSurface(const std::vector<Eigen::Vector3i>& triangles);
  void mend();
  void splitParticle(int original, int copy, const std::vector<int>& neighbours,
                     const std::vector<Eigen::Vector3i>& triangles);

  /// The first element of type `Element`, or null (for read-only views of one element's data).
  template <class Element>
  const Element* find() const
  {
    for (const std::unique_ptr<ForceElement>& element : elements_)
    {
      if (const Element* found = dynamic_cast<const Element*>(element.get())) return found;
    }
    return nullptr;
  }

private:
  std::vector<std::unique_ptr<ForceElement>> elements_;
  std::vector<int> energy_order_;
};

}  // namespace core
}  // namespace particle_sim
