#pragma once

#include <optional>
#include <string>
#include <vector>

#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// A cloth's material in physical units (issue 17), as textile tests measure it. The grid and mesh
/// cloth builders turn it into particle masses and spring (or Baraff–Witkin) constants for the
/// mesh they build, so that the same material behaves the same at any resolution.
struct ClothMaterial
{
  std::string name;                ///< the preset's name, or empty for a material given by value
  double areal_density = 0.0;      ///< [kg/m²], > 0
  double tensile_stiffness = 0.0;  ///< Young's modulus × thickness [N/m], > 0
  double shear_stiffness = 0.0;    ///< shear modulus × thickness [N/m], > 0
  double bending_rigidity = 0.0;   ///< B [N·m], >= 0
  double damping_ratio = 0.0;      ///< ζ [-], fraction of critical damping (see cloth_common.cpp for the mode)
};

/// Each field in its range (limits.h); the message names the field, the value and the range.
Status validate(const ClothMaterial& material);

/// The named cloth materials (cotton, denim, silk, ...), each value's source in a comment.
const std::vector<ClothMaterial>& clothPresets();
/// The preset called `name`, or nothing.
std::optional<ClothMaterial> findClothPreset(const std::string& name);
/// "name1, name2, ..." for messages.
std::string clothPresetNames();

}  // namespace core
}  // namespace particle_sim
