#pragma once

#include <string>

namespace particle_sim
{
namespace core
{
/// How a cloth resists deformation.
enum class ClothModel
{
  Springs,       ///< Provot's stretch, shear and bend springs
  BaraffWitkin,  ///< Baraff & Witkin's stretch and shear per triangle, bend per interior edge
};

const char* toString(ClothModel model);
/// Parses "springs" or "baraff_witkin"; false when unknown.
bool parseClothModel(const std::string& text, ClothModel& model);

}  // namespace core
}  // namespace particle_sim
