#include "particle_sim/core/cloth_model.h"

namespace particle_sim
{
namespace core
{
const char* toString(ClothModel model)
{
  return model == ClothModel::Springs ? "springs" : "baraff_witkin";
}

bool parseClothModel(const std::string& text, ClothModel& model)
{
  if (text == "springs")
    model = ClothModel::Springs;
  else if (text == "baraff_witkin")
    model = ClothModel::BaraffWitkin;
  else
    return false;
  return true;
}

}  // namespace core
}  // namespace particle_sim
