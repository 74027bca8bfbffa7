#pragma once

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

namespace particle_sim_test
{
/// The folder of the shipped scene files (config/scenes of the source tree).
inline const std::string kShippedScenesDir = std::string(PARTICLE_SIM_SOURCE_DIR) + "/config/scenes";

/// Every shipped scene file, as its path relative to kShippedScenesDir ("hard/long_rope.yaml"),
/// subfolders included, sorted.
inline std::vector<std::string> shippedScenes()
{
  std::vector<std::string> scenes;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(kShippedScenesDir))
    if (entry.is_regular_file() && entry.path().extension() == ".yaml")
      scenes.push_back(std::filesystem::relative(entry.path(), kShippedScenesDir).generic_string());
  std::sort(scenes.begin(), scenes.end());
  return scenes;
}

}  // namespace particle_sim_test
