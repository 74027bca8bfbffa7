#pragma once

#include <optional>
#include <string>
#include <vector>

#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// A rope's material in physical units (issue 17). The rope builder turns it into particle masses,
/// stretch springs and bending elements for the segment length it builds, so that the same
/// material behaves the same at any number of particles.
struct RopeMaterial
{
  std::string name;                ///< the preset's name, or empty for a material given by value
  double linear_density = 0.0;     ///< μ [kg/m], > 0
  double axial_stiffness = 0.0;    ///< EA [N], > 0
  double bending_stiffness = 0.0;  ///< EI [N·m²], >= 0 (0 = a chain that does not resist bending)
  double damping_ratio = 0.0;      ///< ζ [-], fraction of critical damping (see rope.cpp for the mode it refers to)
};

/// Each field in its range (limits.h); the message names the field, the value and the range.
Status validate(const RopeMaterial& material);

/// The named rope materials (nylon rope, steel cable, ...), each value's source in a comment.
const std::vector<RopeMaterial>& ropePresets();
/// The preset called `name`, or nothing.
std::optional<RopeMaterial> findRopePreset(const std::string& name);
/// "name1, name2, ..." for messages.
std::string ropePresetNames();

}  // namespace core
}  // namespace particle_sim
