#include "particle_sim/core/constraints/strain_limit.h"

#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
namespace
{
// Relative slack allowed above the strain limit, for rounding.
constexpr double kStrainTolerance = 1e-9;
}  // namespace

Status validate(const StrainLimitDef& def)
{
  if (Status s = checkMin("max_strain", def.max_strain, 0.0); !s) return s;
  return checkIntRange("strain_iterations", def.iterations, 1, 100000);
}

StrainLimit::StrainLimit(const StrainLimitDef& def, const std::vector<Spring>& springs, int particles) : def_(def)
{
  setSprings(springs);
  unlimited_position_.setZero(3, particles);
}

void StrainLimit::setSprings(const std::vector<Spring>& springs)
{
  springs_.clear();
  for (const Spring& s : springs)
  {
    if (s.spring_class != SpringClass::Bend) springs_.push_back(s);
  }
}

void StrainLimit::apply(double h, ParticlePool& p)
{
  unlimited_position_ = p.position;

  // Relaxation passes (Provot 1995): each over-stretched spring is shortened to its longest allowed
  // length, its two ends moving in proportion to their inverse masses.
  for (int pass = 0; pass < def_.iterations; ++pass)
  {
    bool over = false;
    for (const Spring& s : springs_)
    {
      const double w_i = p.inverse_mass[s.i], w_j = p.inverse_mass[s.j];
      if (w_i + w_j == 0.0) continue;
      const Eigen::Vector3d delta = p.position.col(s.j) - p.position.col(s.i);
      const double length = delta.norm();
      const double longest = (1.0 + def_.max_strain) * s.rest_length;
      if (length <= longest * (1.0 + kStrainTolerance)) continue;
      over = true;
      const Eigen::Vector3d correction = (length - longest) / (length * (w_i + w_j)) * delta;
      p.position.col(s.i) += w_i * correction;
      p.position.col(s.j) -= w_j * correction;
    }
    if (!over) break;
  }

  // Velocities follow the positions: what the correction moved, over the step.
  p.velocity += (p.position - unlimited_position_) / h;
}

}  // namespace core
}  // namespace particle_sim
