#pragma once

#include <optional>
#include <string>

#include "particle_sim/ClothMaterial.h"
#include "particle_sim/RopeMaterial.h"
#include "particle_sim/SpawnCloth.h"
#include "particle_sim/SpawnRope.h"
#include "particle_sim/core/materials/cloth_material.h"
#include "particle_sim/core/materials/rope_material.h"
#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace ros_interface
{
// Materials in physical units in the node's interfaces (issue 17): the `material` field of
// ~spawn_rope and ~spawn_cloth (msg/RopeMaterial.msg, msg/ClothMaterial.msg), the rope_material and
// cloth_material presets of dynamic_reconfigure and of the node's parameters. Pure functions, no
// node handle, no master. Each refusal names the field, the value as received and what is allowed
// (the preset names, or the range and unit of the core's validate()).
//
// A request's material is one of:
//   - none: preset empty and every value 0 (the request's mass and spring constants, as before);
//   - a preset: that preset, each value != 0 replacing the preset's (the material then has no
//     name: it is no longer the preset);
//   - by value: preset empty, the values given; those that must be > 0 must be set.
// A material and a mass or spring constant != 0 in the same request are refused, naming both.

/// `name` is empty or a rope preset; `field` names where it came from ("~rope_material").
core::Status checkRopePresetName(const std::string& field, const std::string& name);
/// `name` is empty or a cloth preset; `field` names where it came from ("~cloth_material").
core::Status checkClothPresetName(const std::string& field, const std::string& name);

/// The material of a RopeMaterial message: nothing when the message is empty, else the preset
/// with the values != 0 replacing its own, or the material by value, checked by core::validate().
core::Status toRopeMaterial(const RopeMaterial& msg, std::optional<core::RopeMaterial>& material);
/// The material of a ClothMaterial message (as toRopeMaterial()).
core::Status toClothMaterial(const ClothMaterial& msg, std::optional<core::ClothMaterial>& material);

/// The material a ~spawn_rope request builds its rope of: its own `material` (refused together
/// with a mass or spring constant != 0), else, when it sets no mass and no spring constant,
/// `default_preset` (dynamic_reconfigure's rope_material; empty = none), else none.
core::Status ropeMaterialOf(const SpawnRope::Request& req, const std::string& default_preset,
                            std::optional<core::RopeMaterial>& material);
/// The material a ~spawn_cloth request builds its cloth of (as ropeMaterialOf(), with
/// cloth_material).
core::Status clothMaterialOf(const SpawnCloth::Request& req, const std::string& default_preset,
                             std::optional<core::ClothMaterial>& material);

/// How an answer or ~status names a material: "material 'cotton'" for a preset, "material by
/// value" for one given by value (empty name).
std::string materialText(const std::string& material_name);

}  // namespace ros_interface
}  // namespace particle_sim
