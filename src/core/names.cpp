#include "particle_sim/core/names.h"

#include <algorithm>
#include <cctype>

#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace core
{
Status validateBodyName(const std::string& name)
{
  if (name.empty()) return Status::failure("name is empty: every body needs a unique name");
  // The length first, so that a long name is refused without echoing it whole: the quote is cut
  // at the longest name allowed and followed by the length, e.g. 'aaa...' (65 characters).
  if (characterCount(name) > limits::kMaxNameLength)
    return Status::failure("name = " + quoteReceived(name, limits::kMaxNameLength) + " is too long: must be 1 to " +
                           std::to_string(limits::kMaxNameLength) + " characters");
  if (name[0] == '_') return Status::failure("name = " + quoteReceived(name) + " starts with '_', which is reserved");
  for (std::size_t at = 0; at < name.size(); ++at)
  {
    const char c = name[at];
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '/'))
    {
      // The whole character, not one byte of it.
      const std::size_t bytes = std::max<std::size_t>(1, utf8CharacterLength(name, at));
      return Status::failure("name = " + quoteReceived(name) + " has the character " +
                             quoteReceived(name.substr(at, bytes)) + "; allowed: letters, digits, '_', '-', '/'");
    }
  }
  return Status::success();
}

}  // namespace core
}  // namespace particle_sim
