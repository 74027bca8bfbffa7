#pragma once
// Helpers shared by the scene-file unit tests: parse a scene text expecting success or a refusal,
// and check that a message contains a part (showing both when it does not).

#include <gtest/gtest.h>

#include <string>

#include "particle_sim/scene/scene.h"

namespace particle_sim_test
{
// Parses `text` (as "test.yaml"), expects it to be accepted and returns what it read.
inline particle_sim::scene::SceneDef parseOk(const std::string& text)
{
  particle_sim::scene::SceneDef def;
  const particle_sim::core::Status status = particle_sim::scene::parseScene(text, "test.yaml", def);
  EXPECT_TRUE(status.ok) << status.message;
  return def;
}

// Parses `text`, expects a refusal and returns its message.
inline std::string refusal(const std::string& text)
{
  particle_sim::scene::SceneDef def;
  const particle_sim::core::Status status = particle_sim::scene::parseScene(text, "test.yaml", def);
  EXPECT_FALSE(status.ok) << "accepted:\n" << text;
  return status.message;
}

inline ::testing::AssertionResult contains(const std::string& message, const std::string& part)
{
  if (message.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << message << "' does not contain '" << part << "'";
}
}  // namespace particle_sim_test
