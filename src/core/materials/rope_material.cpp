#include "particle_sim/core/materials/rope_material.h"

#include "particle_sim/core/limits.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
namespace
{
constexpr double kPi = 3.14159265358979323846;

/// Second moment of area of a solid circular section of diameter d [m]: π d⁴ / 64 [m⁴].
constexpr double solidSecondMoment(double diameter)
{
  return kPi * diameter * diameter * diameter * diameter / 64.0;
}

/// Fraction of a solid rod's EI that a rope of twisted or braided fibres keeps once its fibres slip
/// against each other [-]. An estimate (there is no handbook value for fibre ropes): it puts the
/// bending length (EI / (μ g))^(1/3) of a 10 mm rope at 0.2–0.3 m, what a hand-held rope shows.
constexpr double kFibreRopeBendingFraction = 0.01;

std::vector<RopeMaterial> makePresets()
{
  std::vector<RopeMaterial> presets;

  // Three-strand nylon (polyamide 6,6) rope, 10 mm nominal (outer) diameter.
  //  μ:  6.4 kg per 100 m (Cordage Institute CI-1303 / manufacturers' tables for 10 mm three-strand nylon).
  //  EA: secant stiffness to break: minimum breaking strength ≈ 20 kN at ≈ 20 % elongation (same tables)
  //      → 20 kN / 0.20 = 1.0e5 N.
  //  EI: nylon 6,6 Young's modulus ≈ 3 GPa (polymer handbooks: 1.6–3.8 GPa) on a solid 10 mm rod,
  //      3e9 · π (0.010)⁴ / 64 = 1.47 N·m², × kFibreRopeBendingFraction (estimate, see above).
  //  ζ:  half of nylon's loss factor tan δ ≈ 0.05 at room temperature (dynamic mechanical analysis).
  presets.push_back({"nylon_rope", 0.064, 1.0e5, 3.0e9 * solidSecondMoment(0.010) * kFibreRopeBendingFraction, 0.025});

  // Three-strand polyester (PET) rope, 10 mm nominal (outer) diameter.
  //  μ:  7.5 kg per 100 m (Cordage Institute CI-1304 / manufacturers' tables; PET is denser than nylon, 1.38 g/cm³).
  //  EA: minimum breaking strength ≈ 20 kN at ≈ 12 % elongation (same tables) → 20 kN / 0.12 = 1.7e5 N.
  //  EI: PET Young's modulus ≈ 3 GPa (polymer handbooks: 2.8–3.1 GPa) on a solid 10 mm rod,
  //      × kFibreRopeBendingFraction (estimate).
  //  ζ:  half of PET's loss factor tan δ ≈ 0.02 below its glass transition → 0.01.
  presets.push_back(
      {"polyester_rope", 0.075, 1.7e5, 3.0e9 * solidSecondMoment(0.010) * kFibreRopeBendingFraction, 0.01});

  // Steel wire rope 6x19 IWRC (independent wire rope core), 10 mm nominal (outer) diameter.
  //  μ:  0.40 kg/m (metric wire rope tables for 10 mm 6x19 IWRC; the Wire Rope Users Manual, 4th ed., Wire
  //      Rope Technical Board, gives 0.26 lb/ft for 3/8 in = 9.5 mm, 0.43 kg/m scaled to 10 mm).
  //  EA: rope modulus ≈ 103 GPa (15 000 ksi, same manual, 6x19 IWRC) on the metallic area 0.471 d²
  //      = 47.1 mm² → 4.85e6 N.
  //  EI: the lower bound once the wires slip (Papailiou 1997, "On the bending stiffness of transmission
  //      line conductors"): the sum of the wires' own EI, 163 wires of ≈ 0.6 mm, E = 205 GPa (steel,
  //      handbook): 163 · 205e9 · π (0.6e-3)⁴ / 64 ≈ 0.21 N·m².
  //  ζ:  0.01, an estimate (inter-wire friction; wire ropes ring when struck).
  presets.push_back(
      {"steel_cable", 0.40, 103e9 * 0.471 * 0.010 * 0.010, 163 * 205e9 * solidSecondMoment(0.6e-3), 0.01});

  // Dynamic kernmantle climbing rope (single rope, EN 892), 9.8 mm diameter.
  //  μ:  64 g/m (EN 892 makes makers print the mass per metre; 9.8 mm single ropes weigh 60–65 g/m).
  //  EA: EN 892 static elongation: ≤ 10 % under 80 kg (784.8 N), typical 8 % → 784.8 N / 0.08 = 9.8e3 N.
  //  EI: estimate from a bending length (EI / (μ g))^(1/3) ≈ 0.2 m of a hand-held kernmantle rope:
  //      0.064 · 9.81 · 0.2³ = 5.0e-3 N·m².
  //  ζ:  0.1, an estimate: a dynamic rope is made to absorb a fall's energy (wide hysteresis loop).
  presets.push_back({"climbing_rope", 0.064, 784.8 / 0.08, 0.064 * 9.81 * 0.2 * 0.2 * 0.2, 0.1});

  // Twelve-strand braided HMPE (Dyneema SK75) rope, 10 mm nominal (outer) diameter.
  //  μ:  6.5 kg per 100 m (manufacturers' tables for 10 mm 12-strand HMPE; fibre density 0.97 g/cm³).
  //  EA: minimum breaking strength ≈ 90 kN at ≈ 3.5 % elongation (same tables) → 90 kN / 0.035 = 2.6e6 N.
  //  EI: fibre modulus ≈ 110 GPa (DSM Dyneema SK75 data sheet) on a solid 10 mm rod
  //      × kFibreRopeBendingFraction / 10 (braided HMPE is limper than laid rope; estimate).
  //  ζ:  0.02, an estimate (low-loss fibre).
  presets.push_back(
      {"hmpe_rope", 0.065, 90e3 / 0.035, 110e9 * solidSecondMoment(0.010) * kFibreRopeBendingFraction / 10.0, 0.02});

  return presets;
}
}  // namespace

Status validate(const RopeMaterial& material)
{
  if (Status s = checkRange("linear_density", material.linear_density, limits::kLinearDensity); !s) return s;
  if (Status s = checkRange("axial_stiffness", material.axial_stiffness, limits::kAxialStiffness); !s) return s;
  if (Status s = checkRange("bending_stiffness", material.bending_stiffness, limits::kBendingStiffness); !s) return s;
  return checkRange("damping_ratio", material.damping_ratio, limits::kDampingRatio);
}

const std::vector<RopeMaterial>& ropePresets()
{
  static const std::vector<RopeMaterial> presets = makePresets();
  return presets;
}

std::optional<RopeMaterial> findRopePreset(const std::string& name)
{
  for (const RopeMaterial& preset : ropePresets())
  {
    if (preset.name == name) return preset;
  }
  return std::nullopt;
}

std::string ropePresetNames()
{
  std::string names;
  for (const RopeMaterial& preset : ropePresets())
    names += (names.empty() ? "" : ", ") + preset.name;
  return names;
}

}  // namespace core
}  // namespace particle_sim
