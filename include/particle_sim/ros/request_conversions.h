#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>

#include "particle_sim/PinParticle.h"
#include "particle_sim/SetWind.h"
#include "particle_sim/SpawnCloth.h"
#include "particle_sim/SpawnCollider.h"
#include "particle_sim/SpawnEmitter.h"
#include "particle_sim/SpawnJelly.h"
#include "particle_sim/SpawnRope.h"
#include "particle_sim/core/builders/cloth_grid.h"
#include "particle_sim/core/builders/jelly.h"
#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/emitter.h"
#include "particle_sim/core/environment.h"
#include "particle_sim/core/integrator.h"
#include "particle_sim/core/spring.h"
#include "particle_sim/core/spring_network.h"
#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace ros_interface
{
// Service requests to core definitions: pure functions of the request (and the few world values
// they need, passed in), with no node handle and no master. A request field left at 0 (or empty)
// keeps the definition's default, as the .srv files say. What these functions refuse is what only
// the request can get wrong (an unknown name, a count beyond int, a material next to spring
// constants, see material_conversions.h); every range is then checked by the core's validate(),
// which the world runs when the definition is added.

/// The integrator name of a spawn request into `integrator`; empty keeps `integrator` as it is
/// (the world's default). Refuses an unknown name, listing the allowed ones.
core::Status parseIntegratorField(const std::string& name, core::BodyIntegratorDef& integrator);

/// ~spawn_emitter: the EmitterDef a scene file would build. `world_seed` gives the seed of a
/// request whose seed is 0 (core::deriveSeed of the world seed and the name).
core::Status toEmitterDef(const SpawnEmitter::Request& req, std::uint64_t world_seed, core::EmitterDef& def);

/// ~spawn_rope: the RopeDef a scene file would build, integrated by `default_integrator` unless the
/// request names one, of the request's material or, when it sets neither a material nor a mass or
/// spring constant, of the preset `default_material` (dynamic_reconfigure's rope_material; empty =
/// none). See material_conversions.h.
core::Status toRopeDef(const SpawnRope::Request& req, const core::IntegratorDef& default_integrator, core::RopeDef& def,
                       const std::string& default_material = {});

/// ~spawn_cloth: the grid cloth a scene file would build (springs or Baraff–Witkin), its material
/// as toRopeDef()'s (`default_material`: dynamic_reconfigure's cloth_material).
core::Status toClothGridDef(const SpawnCloth::Request& req, const core::IntegratorDef& default_integrator,
                            core::ClothGridDef& def, const std::string& default_material = {});

/// ~spawn_jelly: the JellyDef a scene file would build.
core::Status toJellyDef(const SpawnJelly::Request& req, const core::IntegratorDef& default_integrator,
                        core::JellyDef& def);

/// ~spawn_collider: the box (`is_box` true) or the capsule the request describes, as a scene file
/// would build it. An all-zero quaternion means no turn; any other must be a unit quaternion.
/// Refuses an unknown shape and a size, length or radius given for the other shape; the core's
/// validate() checks the ranges when the world adds it.
core::Status toColliderDef(const SpawnCollider::Request& req, bool& is_box, core::BoxColliderDef& box,
                           core::CapsuleColliderDef& capsule);

/// Which ~spawn_* request a refusal of the core answers (see inRequestTerms).
enum class SpawnRequest
{
  Emitter,
  Rope,
  Cloth,
  Jelly
};

/// The core's refusal of a converted definition names the definition's field (`stretch.stiffness`,
/// `resolution[0]`, `particle_mass`); a service caller knows the request's (`stretch_stiffness`,
/// `nu`, `mass`). Renames the field the message starts with to the request's; the rest of the
/// message (value as received, range, unit) is kept. A field whose name is the same in both is
/// left alone.
core::Status inRequestTerms(SpawnRequest request, core::Status status);

/// ~set_spring_constants and dynamic_reconfigure's spring_class: "stretch", "shear" or "bend" is
/// that class, "all" is every class (no value). Refuses anything else, listing the allowed names.
core::Status parseSpringClassSelection(const std::string& name, std::optional<core::SpringClass>& spring_class);

/// ~set_wind: the wind velocity [m/s] asked for (the world checks its range when it is set).
Eigen::Vector3d toWind(const SetWind::Request& req);

/// Where a ~pin_particle request holds a particle.
enum class PinTarget
{
  Current,  ///< where the particle is now
  Point,    ///< at the request's point
  Frame,    ///< following a tf frame (looked up by the node)
};

/// A ~pin_particle request resolved against its body.
struct PinSpec
{
  int index = 0;                                     ///< the particle, in [0, count − 1]
  PinTarget target = PinTarget::Current;             ///< what it is held to
  Eigen::Vector3d point = Eigen::Vector3d::Zero();   ///< [m] sim frame: the target (Current, Point)
  std::string frame;                                 ///< tf frame followed (Frame)
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< [m] in `frame`: where on it the particle is held (Frame)
};

/// ~pin_particle against `body` (found by the node): index -1 takes the particle nearest to a
/// finite point, any other index must be a particle; the target must be 0, 1 or 2, and a frame
/// target needs a frame name and a finite offset.
core::Status toPinSpec(const PinParticle::Request& req, const core::SpringNetworkBody& body, PinSpec& spec);

}  // namespace ros_interface
}  // namespace particle_sim
