#include "particle_sim/core/materials/cloth_material.h"

#include "particle_sim/core/limits.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
Status validate(const ClothMaterial& material)
{
  if (Status s = checkRange("material.areal_density", material.areal_density, limits::kArealDensity); !s) return s;
  if (Status s = checkRange("material.tensile_stiffness", material.tensile_stiffness, limits::kTensileStiffness); !s)
    return s;
  if (Status s = checkRange("material.shear_stiffness", material.shear_stiffness, limits::kShearStiffness); !s)
    return s;
  if (Status s = checkRange("material.bending_rigidity", material.bending_rigidity, limits::kBendingRigidity); !s)
    return s;
  return checkRange("material.damping_ratio", material.damping_ratio, limits::kDampingRatio);
}

// Sources and conversions. The values are representative figures of each fabric type measured with
// the Kawabata Evaluation System for Fabrics (KES-F: S. Kawabata, "The Standardization and Analysis of
// Hand Evaluation", 2nd ed., Textile Machinery Society of Japan, 1980; typical ranges also in
// B. P. Saville, "Physical Testing of Textiles", Woodhead 1999, ch. 9), rounded, warp and weft
// averaged. They describe a fabric type, not one measured sample. KES-F units to SI:
//   - tensile: KES-FB1 gives EMT, the strain [%] at 500 gf/cm = 490 N/m; the secant stiffness is
//     E·t = 490 N/m / (EMT/100) [N/m];
//   - shear: KES-FB1 gives G [gf/(cm·deg)]; 1 gf/(cm·deg) = 9.807e-3 N / 1e-2 m × 180/π = 56.2 N/m;
//   - bending: KES-FB2 gives B [gf·cm²/cm]; 1 gf·cm²/cm = 9.807e-5 N·m;
//   - weight: the fabric's mass per area W [g/m²] → areal density W/1000 [kg/m²].
// Damping ratio: KES-F measures hysteresis (2HB, 2HG), not a modal damping ratio; every preset gets
// ζ = 0.05 (light damping, an assumption: change it per scene with damping_ratio).
const std::vector<ClothMaterial>& clothPresets()
{
  static const std::vector<ClothMaterial> presets = {
      // Cotton plain-weave shirting, W = 130 g/m²: EMT ≈ 5 %, G ≈ 0.8 gf/(cm·deg), B ≈ 0.08 gf·cm²/cm.
      {"cotton", 0.130, 9800.0, 45.0, 7.8e-6, 0.05},
      // Denim, 3/1 twill, 12 oz/yd² (W = 400 g/m²): EMT ≈ 4 %, G ≈ 2.5 gf/(cm·deg), B ≈ 0.8 gf·cm²/cm.
      {"denim", 0.400, 12250.0, 140.0, 7.8e-5, 0.05},
      // Silk habotai, W = 50 g/m²: EMT ≈ 6 %, G ≈ 0.3 gf/(cm·deg), B ≈ 0.02 gf·cm²/cm.
      {"silk", 0.050, 8200.0, 17.0, 2.0e-6, 0.05},
      // Polyester plain weave (filament), W = 100 g/m²: EMT ≈ 3 %, G ≈ 0.6 gf/(cm·deg), B ≈ 0.06 gf·cm²/cm.
      {"polyester", 0.100, 16300.0, 34.0, 5.9e-6, 0.05},
      // Wool worsted suiting, W = 250 g/m²: EMT ≈ 4 %, G ≈ 0.6 gf/(cm·deg), B ≈ 0.09 gf·cm²/cm
      // (Kawabata's men's suiting standard ranges).
      {"wool", 0.250, 12250.0, 34.0, 8.8e-6, 0.05},
      // Technical fabric: aramid (Kevlar 29) plain weave, W = 200 g/m². Tensile from the fibre: modulus
      // 70 GPa (DuPont Kevlar technical guide), density 1440 kg/m³, so 200 g/m² is 0.139 mm of fibre,
      // half of it per direction, times ≈ 0.2 for crimp (the weave's initial straightening):
      // E·t ≈ 70e9 × 0.069e-3 × 0.2 ≈ 1.0e6 N/m. Shear G ≈ 1 gf/(cm·deg) and B ≈ 0.3 gf·cm²/cm (KES-F
      // figures of comparable open plain weaves: the yarns trellis and bend nearly freely at small angles).
      {"aramid", 0.200, 1.0e6, 56.0, 2.9e-5, 0.05},
  };
  return presets;
}

std::optional<ClothMaterial> findClothPreset(const std::string& name)
{
  for (const ClothMaterial& preset : clothPresets())
  {
    if (preset.name == name) return preset;
  }
  return std::nullopt;
}

std::string clothPresetNames()
{
  std::string names;
  for (const ClothMaterial& preset : clothPresets())
    names += (names.empty() ? "" : ", ") + preset.name;
  return names;
}

}  // namespace core
}  // namespace particle_sim
