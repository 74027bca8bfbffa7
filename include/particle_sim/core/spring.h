#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

namespace particle_sim
{
namespace core
{
/// Which family a spring belongs to; stiffness and damping are set per class.
enum class SpringClass
{
  Stretch,  ///< between neighbours (rope segments, cloth structural springs)
  Shear,    ///< cloth diagonals
  Bend,     ///< two apart (rope i, i+2; cloth bend springs)
};

const char* toString(SpringClass spring_class);
/// Parses "stretch", "shear" or "bend"; false when unknown.
bool parseSpringClass(const std::string& text, SpringClass& spring_class);

/// Stiffness and damping of one class of springs (or of Baraff–Witkin conditions).
struct SpringConstants
{
  double stiffness = 0.0;  ///< [N/m] >= 0
  double damping = 0.0;    ///< [N·s/m] >= 0
};

/// One spring between particles i and j.
struct Spring
{
  int i = 0;
  int j = 0;
  double rest_length = 1.0;  ///< [m] >= 0
  double stiffness = 100.0;  ///< k_e [N/m] >= 0
  double damping = 0.0;      ///< k_d [N·s/m] >= 0
  SpringClass spring_class = SpringClass::Stretch;
};

/// The lecture's spring force on particle i (the force on j is its opposite):
///   f_i = ( k_e (|x_j − x_i| − L) + k_d (v_j − v_i)·d ) d,   d = (x_j − x_i) / |x_j − x_i|.
/// Coincident particles (|x_j − x_i| = 0) have no direction and get no force.
/// Inline, always: it runs once per spring in the explicit methods' innermost loops (one thread's
/// and the shared one's), where a call into the shared library cost as much as the arithmetic.
[[gnu::always_inline]] inline Eigen::Vector3d springForce(const Eigen::Vector3d& xi, const Eigen::Vector3d& xj,
                                                          const Eigen::Vector3d& vi, const Eigen::Vector3d& vj,
                                                          double rest_length, double stiffness, double damping)
{
  const Eigen::Vector3d delta = xj - xi;
  const double length = delta.norm();
  if (length == 0.0) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d d = delta / length;
  return (stiffness * (length - rest_length) + damping * (vj - vi).dot(d)) * d;
}

/// Potential energy of the elastic part [J]: k_e (|x_j − x_i| − L)^2 / 2 (inline for the same reason).
[[gnu::always_inline]] inline double springEnergy(const Eigen::Vector3d& xi, const Eigen::Vector3d& xj,
                                                  double rest_length, double stiffness)
{
  const double stretch = (xj - xi).norm() - rest_length;
  return 0.5 * stiffness * stretch * stretch;
}

/// Jacobian blocks of f_i with respect to x_i and v_i. By symmetry of the spring,
///   ∂f_i/∂x_i = ∂f_j/∂x_j = −∂f_i/∂x_j = −∂f_j/∂x_i = dfdx, and likewise for dfdv.
///
/// dfdx is the lecture's tangent stiffness of the elastic force,
///   k_e ( −I + (L/l) (I − d dᵀ) ) = −k_e ( d dᵀ + (1 − L/l)(I − d dᵀ) ),   l = |x_j − x_i|;
/// dfdv = −k_d d dᵀ. The dependence of the damping force on positions (through d) is left out,
/// as in Baraff & Witkin 1998, which keeps the implicit system symmetric.
///
/// With `definite` set, the transverse factor (1 − L/l) is clamped at 0 for compressed springs,
/// so that −dfdx is positive semi-definite and the implicit solve stays a symmetric positive
/// definite system (Choi & Ko 2002). Without it the blocks are the exact derivatives.
/// Inline, as springForce is: an assembly calls it for every spring of every implicit step.
[[gnu::always_inline]] inline void springJacobians(const Eigen::Vector3d& xi, const Eigen::Vector3d& xj,
                                                   double rest_length, double stiffness, double damping, bool definite,
                                                   Eigen::Matrix3d& dfdx, Eigen::Matrix3d& dfdv)
{
  const Eigen::Vector3d delta = xj - xi;
  const double length = delta.norm();
  if (length == 0.0)
  {
    // No direction: take the along-spring stiffness in every direction.
    dfdx = -stiffness * Eigen::Matrix3d::Identity();
    dfdv = -damping * Eigen::Matrix3d::Identity();
    return;
  }
  const Eigen::Vector3d d = delta / length;
  const Eigen::Matrix3d along = d * d.transpose();
  double transverse = 1.0 - rest_length / length;
  if (definite) transverse = std::max(transverse, 0.0);
  dfdx = -stiffness * (along + transverse * (Eigen::Matrix3d::Identity() - along));
  dfdv = -damping * along;
}

/// springJacobians() with `definite` set, by its parts: dfdx = along_x d dᵀ + isotropic_x I and
/// dfdv = along_v d dᵀ, with along_x = −k_e (1 − t), isotropic_x = −k_e t and along_v = −k_d, t the
/// clamped transverse factor (1 − L/l). False for coincident particles, whose blocks are not of this
/// form (springJacobians() gives them). For the implicit assembly, which builds its blocks from
/// these numbers with a fraction of the arithmetic of the full ones.
[[gnu::always_inline]] inline bool springJacobianParts(const Eigen::Vector3d& xi, const Eigen::Vector3d& xj,
                                                       double rest_length, double stiffness, double damping,
                                                       Eigen::Vector3d& d, double& along_x, double& isotropic_x,
                                                       double& along_v)
{
  const Eigen::Vector3d delta = xj - xi;
  const double length = delta.norm();
  if (length == 0.0) return false;
  d = delta / length;
  const double transverse = std::max(1.0 - rest_length / length, 0.0);
  along_x = -stiffness * (1.0 - transverse);
  isotropic_x = -stiffness * transverse;
  along_v = -damping;
  return true;
}

/// The forces of the consecutive springs [first, last) from the positions x and velocities v (3
/// numbers a particle): springForce() added to `force` at each spring's end i (if add_i) and taken
/// from it at its end j (if add_j), spring after spring in the order of the list; with `energy` not
/// null, each spring's springEnergy() into energy[s − first] as well, and with `energy_sum` not null
/// (and `energy` given) added to *energy_sum one after the other in the order of the list. The
/// explicit methods' force pass (SpringForces), one thread's whole list or a chunk's run of springs.
/// With `vectorized` (where the processor has AVX2: springPartsVectorized()), four springs at a time,
/// each lane in springForce()'s operations and order (no fused multiply-add), so the same bits as
/// without.
void addSpringForcesOf(const Spring* first, const Spring* last, const double* x, const double* v, double* force,
                       double* energy, double* energy_sum, bool add_i, bool add_j, bool vectorized);

/// springJacobianParts() of many springs, one entry a spring in each array: d = (d_x, d_y, d_z),
/// along_x and isotropic_x (along_v is −k_d), and `coincident` 1 where it returned false (then the
/// other numbers are not used).
struct SpringJacobianParts
{
  std::vector<double> d_x, d_y, d_z, along_x, isotropic_x;
  std::vector<char> coincident;
  /// Room for `springs` springs (allocates only when it grows).
  void resize(std::size_t springs);
};

/// The parts of springs [first, last) of `springs` into the same places of `parts`, from the
/// positions x (3 numbers a particle). With `vectorized` (where the processor has AVX2: see
/// springPartsVectorized()), four springs at a time, their square roots and divisions in one
/// instruction each: every lane does springJacobianParts()'s operations in its order (no fused
/// multiply-add), so the numbers are the same bits as one spring at a time.
void springJacobianPartsOf(const Spring* springs, int first, int last, const double* x, bool vectorized,
                           SpringJacobianParts& parts);
/// Whether this processor runs springJacobianPartsOf() and addSpringForcesOf() four springs at a time
/// (x86-64 with AVX2).
bool springPartsVectorized();

}  // namespace core
}  // namespace particle_sim
