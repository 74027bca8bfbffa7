#pragma once

#include <string>

#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace core
{
/// Body names: 1 to limits::kMaxNameLength characters, of letters, digits, '_', '-' and '/', not
/// starting with '_' (reserved).
Status validateBodyName(const std::string& name);

}  // namespace core
}  // namespace particle_sim
