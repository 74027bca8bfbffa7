#include "particle_sim/core/builders/cloth_common.h"

#include "particle_sim/core/forces/baraff_witkin_model.h"
#include "particle_sim/core/names.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
SpringConstants defaultClothConstants(ClothModel model, SpringClass spring_class)
{
  const bool bw = model == ClothModel::BaraffWitkin;
  switch (spring_class)
  {
    case SpringClass::Stretch:
      return bw ? kBaraffWitkinStretch : kSpringClothStretch;
    case SpringClass::Shear:
      return bw ? kBaraffWitkinShear : kSpringClothShear;
    case SpringClass::Bend:
      return bw ? kBaraffWitkinBend : kSpringClothBend;
  }
  return {};
}

ClothConstants ClothConstants::unset(ClothModel model, SpringClass spring_class)
{
  const SpringConstants shown = defaultClothConstants(model, spring_class);
  return {ClothConstant::unset(shown.stiffness), ClothConstant::unset(shown.damping)};
}

SpringConstants ClothConstants::resolve(ClothModel model, SpringClass spring_class) const
{
  const SpringConstants defaults = defaultClothConstants(model, spring_class);
  return {stiffness.orDefault(defaults.stiffness), damping.orDefault(defaults.damping)};
}

SpringConstants resolveClothConstants(ClothModel model, SpringClass spring_class, const ClothConstants& stretch,
                                      const ClothConstants& shear, const ClothConstants& bend)
{
  const ClothConstants& set = spring_class == SpringClass::Stretch ? stretch
                              : spring_class == SpringClass::Shear ? shear
                                                                   : bend;
  return set.resolve(model, spring_class);
}

Status validateClothCommon(const std::string& name, const SpringConstants& stretch, const SpringConstants& bend,
                           double mass, const StrainLimitDef& strain_limit, const BodyIntegratorDef& integrator,
                           double contact_thickness)
{
  if (Status s = checkRange("contact_thickness", contact_thickness, limits::kContactThickness); !s) return s;
  if (Status s = validateBodyName(name); !s) return s;
  if (Status s = checkPositive("mass", mass); !s) return s;
  if (Status s = checkSpringConstants("stretch.", stretch.stiffness, stretch.damping); !s) return s;
  if (Status s = checkSpringConstants("bend.", bend.stiffness, bend.damping); !s) return s;
  if (Status s = validate(strain_limit); !s) return s;
  return validate(integrator);
}

Status validateBaraffWitkinRest(double b_u, double b_v)
{
  if (Status s = checkPositive("b_u", b_u); !s) return s;
  return checkPositive("b_v", b_v);
}

SpringNetworkDef emptyCloth(const std::string& name, const BodyIntegratorDef& integrator, const StrainLimitDef& limit,
                            double contact_thickness)
{
  SpringNetworkDef net;
  net.contact_thickness = contact_thickness;
  net.name = name;
  net.shape = NetworkShape::Cloth;
  net.integrator = integrator;
  net.strain_limit = limit;
  return net;
}

Spring clothSpring(const std::vector<Eigen::Vector3d>& x, int i, int j, const SpringConstants& c, SpringClass cls)
{
  return {i, j, (x[j] - x[i]).norm(), c.stiffness, c.damping, cls};
}

void addBaraffWitkin(const std::vector<Eigen::Vector2d>& uvs, const SpringConstants& stretch,
                     const SpringConstants& shear, const SpringConstants& bend, double b_u, double b_v,
                     SpringNetworkDef& net)
{
  BaraffWitkinDef& bw = net.baraff_witkin;
  std::string error;
  buildBaraffWitkin(net.positions, uvs, net.triangles, bw, error);  // validated before
  bw.stretch = stretch;
  bw.shear = shear;
  bw.bend = bend;
  bw.b_u = b_u;
  bw.b_v = b_v;
}

}  // namespace core
}  // namespace particle_sim
