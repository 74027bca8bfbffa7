#include "particle_sim/ros/material_conversions.h"

#include <algorithm>
#include <vector>

#include "particle_sim/core/limits.h"
#include "particle_sim/ros/message_text.h"

namespace particle_sim
{
namespace ros_interface
{
namespace
{
// One value of a material message: its field, unit, the value received and where it goes in the
// core's material; `required` values must be > 0 in a material given by value.
template <class Material>
struct MaterialValue
{
  const char* field;
  const char* unit;
  double received;
  double Material::*member;
  bool required;
};

// What the core knows of one kind of material.
template <class Material>
struct MaterialKind
{
  const char* kind;                                          // "rope", "cloth"
  std::optional<Material> (*find)(const std::string& name);  // findRopePreset, findClothPreset
  std::string (*names)();                                    // ropePresetNames, clothPresetNames
};

const MaterialKind<core::RopeMaterial> kRope{"rope", core::findRopePreset, core::ropePresetNames};
const MaterialKind<core::ClothMaterial> kCloth{"cloth", core::findClothPreset, core::clothPresetNames};

// A value counts as given when it is not 0 (NaN too: validate() then refuses it as received).
bool given(double value)
{
  return value != 0.0;
}

template <class Material>
core::Status checkPresetName(const MaterialKind<Material>& kind, const std::string& field, const std::string& name)
{
  if (name.empty() || kind.find(name)) return core::Status::success();
  return core::Status::failure(field + " = " + quoteName(name) + " is not a " + kind.kind +
                               " material preset; allowed: " + kind.names());
}

// The material of a message: none, a preset with the values given replacing its own, or a
// material by value (module comment of material_conversions.h).
template <class Material>
core::Status toMaterial(const MaterialKind<Material>& kind, const std::string& preset,
                        const std::vector<MaterialValue<Material>>& values, std::optional<Material>& material)
{
  material.reset();
  const bool any_value = std::any_of(values.begin(), values.end(), [](const auto& v) { return given(v.received); });
  if (preset.empty() && !any_value) return core::Status::success();

  Material m;
  if (!preset.empty())
  {
    if (core::Status s = checkPresetName(kind, "material.preset", preset); !s) return s;
    m = *kind.find(preset);
    if (any_value) m.name.clear();  // no longer the preset: a material by value
  }
  else
  {
    // By value: every required value must be there.
    std::string required;
    for (const auto& v : values)
    {
      if (v.required) required += std::string(required.empty() ? "" : ", ") + v.field + " > 0 " + v.unit;
    }
    for (const auto& v : values)
    {
      if (v.required && !given(v.received))
        return core::Status::failure(std::string("material.") + v.field + " = 0 is not set: a " + kind.kind +
                                     " material given by value (material.preset empty) needs " + required +
                                     "; or name a preset: " + kind.names());
    }
  }
  for (const auto& v : values)
  {
    if (given(v.received)) m.*v.member = v.received;
  }

  // The ranges are the core's (limits.h); its message names the material's field.
  core::Status s = core::validate(m);
  if (!s)
  {
    const std::string prefix = "material.";
    if (s.message.compare(0, prefix.size(), prefix) != 0) s.message = prefix + s.message;
    return s;
  }
  material = std::move(m);
  return core::Status::success();
}

// "material.preset = 'x'" or "material.<first value given> = v unit": how a refusal names the
// request's material.
template <class Material>
std::string describeMaterial(const std::string& preset, const std::vector<MaterialValue<Material>>& values)
{
  if (!preset.empty()) return "material.preset = " + quoteName(preset);
  for (const auto& v : values)
  {
    if (given(v.received))
      return std::string("material.") + v.field + " = " + formatReceived(v.received) + " " + v.unit;
  }
  return "material";
}

// A field of a spawn request that a material replaces (mass, spring constants).
struct ReplacedField
{
  const char* field;
  const char* unit;
  double received;
};

// The request's own material (refused next to a replaced field that is set), else the default
// preset when no replaced field is set, else none.
template <class Material>
core::Status materialOf(const MaterialKind<Material>& kind, const std::string& preset,
                        const std::vector<MaterialValue<Material>>& values, const std::vector<ReplacedField>& replaced,
                        const std::string& default_field, const std::string& default_preset,
                        std::optional<Material>& material)
{
  if (core::Status s = toMaterial(kind, preset, values, material); !s) return s;
  const auto set = std::find_if(replaced.begin(), replaced.end(), [](const auto& f) { return given(f.received); });
  if (material)
  {
    if (set == replaced.end()) return core::Status::success();
    material.reset();
    return core::Status::failure(describeMaterial(preset, values) + " and " + set->field + " = " +
                                 formatReceived(set->received) + " " + set->unit + " are both set: a " + kind.kind +
                                 " material gives the " + kind.kind + "'s mass and spring constants; leave " +
                                 set->field + " at 0 or spawn without a material");
  }
  if (set != replaced.end() || default_preset.empty()) return core::Status::success();
  if (core::Status s = checkPresetName(kind, default_field, default_preset); !s) return s;
  material = kind.find(default_preset);
  return core::Status::success();
}

std::vector<MaterialValue<core::RopeMaterial>> ropeValues(const RopeMaterial& msg)
{
  using M = core::RopeMaterial;
  namespace limits = core::limits;
  return {{"linear_density", limits::kLinearDensity.unit, msg.linear_density, &M::linear_density, true},
          {"axial_stiffness", limits::kAxialStiffness.unit, msg.axial_stiffness, &M::axial_stiffness, true},
          {"bending_stiffness", limits::kBendingStiffness.unit, msg.bending_stiffness, &M::bending_stiffness, false},
          {"damping_ratio", limits::kDampingRatio.unit, msg.damping_ratio, &M::damping_ratio, false}};
}

std::vector<MaterialValue<core::ClothMaterial>> clothValues(const ClothMaterial& msg)
{
  using M = core::ClothMaterial;
  namespace limits = core::limits;
  return {{"areal_density", limits::kArealDensity.unit, msg.areal_density, &M::areal_density, true},
          {"tensile_stiffness", limits::kTensileStiffness.unit, msg.tensile_stiffness, &M::tensile_stiffness, true},
          {"shear_stiffness", limits::kShearStiffness.unit, msg.shear_stiffness, &M::shear_stiffness, true},
          {"bending_rigidity", limits::kBendingRigidity.unit, msg.bending_rigidity, &M::bending_rigidity, false},
          {"damping_ratio", limits::kDampingRatio.unit, msg.damping_ratio, &M::damping_ratio, false}};
}
}  // namespace

core::Status checkRopePresetName(const std::string& field, const std::string& name)
{
  return checkPresetName(kRope, field, name);
}

core::Status checkClothPresetName(const std::string& field, const std::string& name)
{
  return checkPresetName(kCloth, field, name);
}

core::Status toRopeMaterial(const RopeMaterial& msg, std::optional<core::RopeMaterial>& material)
{
  return toMaterial(kRope, msg.preset, ropeValues(msg), material);
}

core::Status toClothMaterial(const ClothMaterial& msg, std::optional<core::ClothMaterial>& material)
{
  return toMaterial(kCloth, msg.preset, clothValues(msg), material);
}

core::Status ropeMaterialOf(const SpawnRope::Request& req, const std::string& default_preset,
                            std::optional<core::RopeMaterial>& material)
{
  const std::vector<ReplacedField> replaced = {{"mass", "kg", req.mass},
                                               {"stretch_stiffness", "N/m", req.stretch_stiffness},
                                               {"stretch_damping", "N·s/m", req.stretch_damping},
                                               {"bend_stiffness", "N/m", req.bend_stiffness},
                                               {"bend_damping", "N·s/m", req.bend_damping}};
  return materialOf(kRope, req.material.preset, ropeValues(req.material), replaced, "rope_material", default_preset,
                    material);
}

core::Status clothMaterialOf(const SpawnCloth::Request& req, const std::string& default_preset,
                             std::optional<core::ClothMaterial>& material)
{
  // Baraff–Witkin's bend condition is per unit length [N·m] (SpawnCloth.srv).
  const bool baraff_witkin = req.model == "baraff_witkin";
  const std::vector<ReplacedField> replaced = {{"mass", "kg", req.mass},
                                               {"stretch_stiffness", "N/m", req.stretch_stiffness},
                                               {"stretch_damping", "N·s/m", req.stretch_damping},
                                               {"shear_stiffness", "N/m", req.shear_stiffness},
                                               {"shear_damping", "N·s/m", req.shear_damping},
                                               {"bend_stiffness", baraff_witkin ? "N·m" : "N/m", req.bend_stiffness},
                                               {"bend_damping", baraff_witkin ? "N·m·s" : "N·s/m", req.bend_damping}};
  return materialOf(kCloth, req.material.preset, clothValues(req.material), replaced, "cloth_material", default_preset,
                    material);
}

std::string materialText(const std::string& material_name)
{
  return material_name.empty() ? "material by value" : "material " + quoteName(material_name);
}

}  // namespace ros_interface
}  // namespace particle_sim
