#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "particle_sim/core/baraff_witkin.h"
#include "particle_sim/core/forces/force_element.h"
#include "particle_sim/core/integrators/implicit_euler_solver.h"
#include "particle_sim/core/spring.h"
#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// A cloth's Baraff–Witkin energies: rest data per triangle and per interior edge, and the
/// stiffness and damping of each condition class.
///
/// The scene's stiffness is per unit rest area, so a cloth behaves the same whatever its
/// triangulation: a triangle of rest area a gets k = stiffness / a for stretch and shear, so its
/// energy k/2 |C|² = stiffness · a · ε²/2 with ε the strain [stiffness in N/m]; a bend element gets
/// k = stiffness · |e|² / (a₁ + a₂) (its rest edge length e and the areas of its two triangles),
/// the discrete-shells scaling [stiffness in N·m]. Damping scales alike.
/// Default constants of a Baraff–Witkin cloth, defined here only: stretch and shear per unit area
/// [N/m] and [N·s/m], bend [N·m] and [N·m·s].
constexpr SpringConstants kBaraffWitkinStretch{1000.0, 1.0};
constexpr SpringConstants kBaraffWitkinShear{100.0, 0.1};
constexpr SpringConstants kBaraffWitkinBend{0.005, 5e-5};
/// Default rest stretch b_u, b_v of a Baraff–Witkin cloth [-] (1 = the rest shape as given).
constexpr double kBaraffWitkinRestStretch = 1.0;

struct BaraffWitkinDef
{
  std::vector<BwTriangle> triangles;
  std::vector<BwBend> bends;
  std::vector<double> bend_weights;                ///< per bend, |e|² / (a₁ + a₂) [-]
  SpringConstants stretch = kBaraffWitkinStretch;  ///< [N/m], [N·s/m]
  SpringConstants shear = kBaraffWitkinShear;      ///< [N/m], [N·s/m]
  SpringConstants bend = kBaraffWitkinBend;        ///< [N·m], [N·m·s]
  double b_u = kBaraffWitkinRestStretch;           ///< rest stretch along u (< 1 shrinks, > 1 grows the cloth)
  double b_v = kBaraffWitkinRestStretch;           ///< rest stretch along v

  bool empty() const { return triangles.empty(); }
};

/// Builds the Baraff–Witkin rest data of a triangle surface from per-vertex (u, v) coordinates
/// [m] and the rest positions (for the rest dihedral angles); false (with `error`) when a
/// triangle is degenerate in (u, v).
bool buildBaraffWitkin(const std::vector<Eigen::Vector3d>& positions, const std::vector<Eigen::Vector2d>& uvs,
                       const std::vector<Eigen::Vector3i>& triangles, BaraffWitkinDef& def, std::string& error);

/// Baraff & Witkin's (1998) cloth conditions as a force element: stretch, shear and bend
/// (kernels in baraff_witkin.h; bend gradient after Bridson et al. 2003). Evaluates forces,
/// energy, Jacobians and stability rows. The implicit solver's block indices of every element
/// are looked up once, in bindPattern(). A triangle stretched past the body's tear strain is
/// removed with its stretch and shear conditions and every bend condition across its edges
/// (tear(); mend() puts them back).
class BaraffWitkinModel : public ForceElement
{
public:
  explicit BaraffWitkinModel(const BaraffWitkinDef& def);

  const BaraffWitkinDef& definition() const { return def_; }
  /// Sets stiffness and damping of one class (stretch, shear or bend).
  void setConstants(SpringClass spring_class, double stiffness, double damping);
  const SpringConstants& constants(SpringClass spring_class) const;

  /// The particle pairs each element couples (for the solver's pattern).
  void coupledPairs(std::vector<std::pair<int, int>>& pairs) const override;
  /// Looks up every element's blocks in `solver` (after its pattern is set).
  void bindPattern(const ImplicitEulerSolver& solver) override;

  /// force += −k ∂C C − k_d ∂C Ċ for every condition.
  void addForces(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v, Eigen::Matrix3Xd& force) const;
  void addForces(const ForceContext& /*context*/, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                 Eigen::Matrix3Xd& force) const override
  {
    addForces(x, v, force);
  }
  /// Adds every element's blocks K_mn = −k (∂C_m ∂C_nᵀ + H_mn C) and D_mn = −k_d ∂C_m ∂C_nᵀ to the
  /// solver, in the definite form: the H C term only for stretched stretch conditions (where it
  /// is negative semi-definite), never for shear and bend (Gauss–Newton), so the system stays
  /// positive definite.
  void addJacobians(const Eigen::Matrix3Xd& x, ImplicitEulerSolver& solver) const;
  void addJacobians(const ForceContext& /*context*/, const Eigen::Matrix3Xd& x,
                    ImplicitEulerSolver& solver) const override
  {
    addJacobians(x, solver);
  }
  /// Adds each element's Gershgorin row sums k |∂C/∂x_m| Σ_n |∂C/∂x_n| (and alike with damping) at
  /// the rest positions `x`, for the body's stability bound.
  void addStabilityRows(const std::vector<Eigen::Vector3d>& x, std::vector<double>& stiffness_rows,
                        std::vector<double>& damping_rows) const override;
  /// Σ k/2 C² [J].
  double energy(const Eigen::Matrix3Xd& x) const;
  void addEnergy(const ForceContext& /*context*/, const Eigen::Matrix3Xd& x, double& energy_sum) const override
  {
    energy_sum += energy(x);
  }
  /// Stretch and shear always; bend when the surface has an interior edge.
  bool hasClass(SpringClass spring_class) const override
  {
    return spring_class != SpringClass::Bend || !def_.bends.empty();
  }
  void setClassConstants(std::optional<SpringClass> spring_class, double stiffness, double damping) override;
  void resetConstants() override;
  /// Per triangle, max(|w_u|/b_u, |w_v|/b_v) − 1; the largest over the cloth.
  double maxStrain(const Eigen::Matrix3Xd& x) const override;
  /// Per vertex, the largest strain of its triangles (assigned into `strains`, sized by the caller).
  void vertexStrains(const Eigen::Matrix3Xd& x, std::vector<double>& strains) const;
  /// Removes every triangle whose strain max(|w_u|/b_u, |w_v|/b_v) − 1 exceeds `tear_strain`, and
  /// the bends of its edges; appends the removed triangles' corners to `torn`.
  void tear(const Eigen::Matrix3Xd& x, double tear_strain, TearRecord& torn) override;
  void mend() override;
  /// Each triangle among `triangles`, and each bend whose triangle on `original`'s side is among them,
  /// now uses `copy` in `original`'s place.
  void splitParticle(int original, int copy, const std::vector<int>& neighbours,
                     const std::vector<Eigen::Vector3i>& triangles) override;

private:
  Eigen::Matrix3d corners(const Eigen::Matrix3Xd& x, const BwTriangle& t) const;
  Eigen::Matrix<double, 3, 4> corners(const Eigen::Matrix3Xd& x, const BwBend& b) const;

  BaraffWitkinDef def_;                   // the triangles and bends not torn, with the current constants
  BaraffWitkinDef built_def_;             // as built (mend() puts its triangles and bends back)
  std::array<SpringConstants, 3> built_;  // stretch, shear, bend as built (reset puts them back)
  std::vector<std::array<int, 9>> triangle_blocks_, built_triangle_blocks_;  // block (m, n) at 3m + n
  std::vector<std::array<int, 16>> bend_blocks_, built_bend_blocks_;         // block (m, n) at 4m + n
  std::vector<std::array<int, 2>> bend_sides_;  // per bend of def_: its two triangles' indices in built_def_
  std::vector<std::array<int, 2>> built_bend_sides_;
  std::vector<int> triangle_origin_;  // per triangle of def_: its index in built_def_
  std::vector<char> triangle_torn_;   // per triangle of built_def_
};

}  // namespace core
}  // namespace particle_sim
