#pragma once
// Helpers shared by the scene-file unit tests: parse a scene text expecting success or a refusal,
// check that a message contains a part (showing both when it does not), and write a scene back and
// read it again.

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

// How many times `key` occurs in `text`.
inline int occurrences(const std::string& text, const std::string& key)
{
  int n = 0;
  for (std::size_t at = text.find(key); at != std::string::npos; at = text.find(key, at + 1))
    ++n;
  return n;
}

// Writes `def` back: `key` must occur `expected` times in the text (the bodies that set it, only
// those). Reads the text back, runs `check` on what it read, and writing that again must give the
// same text.
template <class Check>
void expectRoundTrip(const particle_sim::scene::SceneDef& def, const std::string& key, int expected, Check check)
{
  const std::string written = particle_sim::scene::toYaml(def);
  EXPECT_EQ(occurrences(written, key), expected) << written;
  const particle_sim::scene::SceneDef again = parseOk(written);
  check(again);
  EXPECT_EQ(particle_sim::scene::toYaml(again), written);
}

inline ::testing::AssertionResult contains(const std::string& message, const std::string& part)
{
  if (message.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << message << "' does not contain '" << part << "'";
}
}  // namespace particle_sim_test
