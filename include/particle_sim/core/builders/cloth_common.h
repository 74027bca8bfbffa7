#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "particle_sim/core/cloth_model.h"
#include "particle_sim/core/forces/baraff_witkin_model.h"
#include "particle_sim/core/materials/cloth_material.h"
#include "particle_sim/core/spring.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// Default constants of a spring cloth (Provot's springs) [N/m], [N·s/m]. Those of a Baraff–Witkin
/// cloth are kBaraffWitkinStretch, kBaraffWitkinShear and kBaraffWitkinBend (forces/baraff_witkin_model.h).
constexpr SpringConstants kSpringClothStretch{1000.0, 0.5};
constexpr SpringConstants kSpringClothShear{200.0, 0.2};
constexpr SpringConstants kSpringClothBend{20.0, 0.05};

/// Default total mass of a grid or mesh cloth [kg].
constexpr double kClothMass = 0.5;

/// The default constants of `spring_class` for a cloth of `model`: the one table of cloth defaults.
SpringConstants defaultClothConstants(ClothModel model, SpringClass spring_class);

/// One constant of a cloth, a stiffness or a damping, whose default depends on the cloth's model.
/// Assigned (`def.bend.stiffness = 0.0`), it is set. Left unset, the cloth gets its model's default
/// (defaultClothConstants()) when it is validated and built, so `ClothGridDef d(model)` and
/// `ClothGridDef d; d.model = model;` give the same cloth. An unset constant reads as the default of
/// the model the definition was constructed with; what the cloth gets is the definition's
/// constants().
class ClothConstant
{
public:
  ClothConstant(double value) : value_(value), set_(true) {}  // implicit: assigning a number sets it
  /// An unset constant that reads as `shown`.
  static ClothConstant unset(double shown)
  {
    ClothConstant constant(shown);
    constant.set_ = false;
    return constant;
  }

  operator double() const { return value_; }
  bool isSet() const { return set_; }
  /// The value when set, else `fallback`.
  double orDefault(double fallback) const { return set_ ? value_ : fallback; }

private:
  double value_;
  bool set_;
};

/// Stiffness [N/m] and damping [N·s/m] of one class of a cloth's springs or Baraff–Witkin conditions
/// (per unit area; bend [N·m], [N·m·s]), each set or left to the model's default (ClothConstant).
struct ClothConstants
{
  ClothConstant stiffness;
  ClothConstant damping;

  /// Both unset, reading as the defaults of `spring_class` for a cloth of `model`.
  static ClothConstants unset(ClothModel model, SpringClass spring_class);
  /// What a cloth of `model` gets for `spring_class`: each value set, else the model's default.
  SpringConstants resolve(ClothModel model, SpringClass spring_class) const;
  /// The values as they read (see ClothConstant).
  operator SpringConstants() const { return {stiffness, damping}; }
};

/// What a cloth of `model` gets for `spring_class`, given its stretch, shear and bend constants.
SpringConstants resolveClothConstants(ClothModel model, SpringClass spring_class, const ClothConstants& stretch,
                                      const ClothConstants& shear, const ClothConstants& bend);

// A cloth given by its material (issue 17) ------------------------------------------------------------
// The builders turn a ClothMaterial into particle masses and constants for the mesh they build, so
// that the same material behaves the same at any resolution (derivations: Baraff–Witkin and damping
// in cloth_common.cpp, the spring grid in cloth_grid.cpp, the spring mesh in mesh_cloth.cpp).

/// validate(material), then what a cloth with a material may not also set: any stretch, shear or
/// bend constant (the material gives them), and, for the spring model, a bending rigidity > 0 (see
/// cloth_common.cpp: distance springs cannot carry one). Success when `material` is empty.
Status validateClothMaterial(const std::optional<ClothMaterial>& material, ClothModel model,
                             const ClothConstants& stretch, const ClothConstants& shear, const ClothConstants& bend);

/// Stiffness-proportional damping times β = k_d / k [s] of a cloth of `material` and rest area
/// `area` [m²], per class, so that each class's fundamental mode of the whole cloth is damped at the
/// material's ratio ζ (the mode is in cloth_common.cpp). Zero for a bend class without rigidity.
struct ClothDampingTimes
{
  double stretch = 0.0;  ///< [s]
  double shear = 0.0;    ///< [s]
  double bend = 0.0;     ///< [s]
};
ClothDampingTimes clothDampingTimes(const ClothMaterial& material, double area);

/// Rest area of the triangles `triangles` of positions `x` [m²].
double clothArea(const std::vector<Eigen::Vector3d>& x, const std::vector<Eigen::Vector3i>& triangles);
/// Lumped particle masses [kg]: each triangle's rest area × areal density [kg/m²], a third to each
/// corner. A particle on no triangle gets no mass from this; callers build surfaces where every
/// particle is on a triangle.
std::vector<double> lumpedClothMasses(const std::vector<Eigen::Vector3d>& x,
                                      const std::vector<Eigen::Vector3i>& triangles, double areal_density);

/// Baraff–Witkin constants of `material` for a cloth of rest area `area` [m²]: stretch E·t [N/m],
/// shear G·t [N/m], bend B [N·m] (the energies are per unit area), damping β·k.
struct ClothClassConstants
{
  SpringConstants stretch, shear, bend;
};
ClothClassConstants baraffWitkinMaterialConstants(const ClothMaterial& material, double area);

// What the grid and mesh cloth builders share ------------------------------------------------------

/// The checks every cloth passes: contact thickness, name, mass, stretch and bend constants,
/// strain limit and integrator, in that order (the definition's form below checks its material first).
Status validateClothCommon(const std::string& name, const SpringConstants& stretch, const SpringConstants& bend,
                           double mass, const StrainLimitDef& strain_limit, const BodyIntegratorDef& integrator,
                           double contact_thickness);
/// validateClothCommon() of a grid or mesh cloth definition, with the constants it gets.
template <typename ClothDef>
Status validateClothCommon(const ClothDef& def)
{
  if (Status s = validateClothMaterial(def.material, def.model, def.stretch, def.shear, def.bend); !s) return s;
  return validateClothCommon(def.name, def.constants(SpringClass::Stretch), def.constants(SpringClass::Bend), def.mass,
                             def.strain_limit, def.integrator, def.contact_thickness);
}
/// Baraff–Witkin's rest stretch b_u, b_v > 0.
Status validateBaraffWitkinRest(double b_u, double b_v);
/// A cloth network (shape Cloth) with nothing in it yet.
SpringNetworkDef emptyCloth(const std::string& name, const BodyIntegratorDef& integrator, const StrainLimitDef& limit,
                            double contact_thickness);
/// A spring of class `cls` from particle i to j of `x`, at rest at their distance.
Spring clothSpring(const std::vector<Eigen::Vector3d>& x, int i, int j, const SpringConstants& c, SpringClass cls);
/// Adds the Baraff–Witkin energies of the triangles of `net`, whose particles have rest coordinates
/// `uvs` [m], with these constants and rest stretch. The triangles must have passed
/// buildBaraffWitkin()'s checks.
void addBaraffWitkin(const std::vector<Eigen::Vector2d>& uvs, const SpringConstants& stretch,
                     const SpringConstants& shear, const SpringConstants& bend, double b_u, double b_v,
                     SpringNetworkDef& net);

}  // namespace core
}  // namespace particle_sim
