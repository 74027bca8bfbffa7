#include "particle_sim/core/spring.h"

namespace particle_sim
{
namespace core
{
const char* toString(SpringClass spring_class)
{
  switch (spring_class)
  {
    case SpringClass::Stretch:
      return "stretch";
    case SpringClass::Shear:
      return "shear";
    case SpringClass::Bend:
      return "bend";
  }
  return "unknown";
}

bool parseSpringClass(const std::string& text, SpringClass& spring_class)
{
  for (SpringClass candidate : {SpringClass::Stretch, SpringClass::Shear, SpringClass::Bend})
  {
    if (text == toString(candidate))
    {
      spring_class = candidate;
      return true;
    }
  }
  return false;
}

}  // namespace core
}  // namespace particle_sim
