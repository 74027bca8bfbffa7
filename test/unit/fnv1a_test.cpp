// The core's FNV-1a 64 hash (core/fnv1a.h) against its authors' published test vectors, and the
// per-body seed derived from it (core::deriveSeed).

#include "particle_sim/core/fnv1a.h"

#include <gtest/gtest.h>

#include <string>

#include "particle_sim/core/world.h"

using namespace particle_sim::core;

namespace
{
std::uint64_t hashOf(const std::string& text)
{
  return fnv1a64(text.data(), text.size());
}
}  // namespace

TEST(Fnv1a64, MatchesThePublishedTestVectors)
{
  EXPECT_EQ(hashOf(""), 0xcbf29ce484222325ULL);
  EXPECT_EQ(hashOf("a"), 0xaf63dc4c8601ec8cULL);
  EXPECT_EQ(hashOf("foobar"), 0x85944171f73967e8ULL);
  // Hashing in pieces continues from the hash so far.
  EXPECT_EQ(fnv1a64("bar", 3, hashOf("foo")), hashOf("foobar"));
}

// A body's seed is the FNV-1a 64 hash of its name XOR the world seed.
TEST(DeriveSeed, IsTheFnv1a64HashOfTheNameXorTheWorldSeed)
{
  EXPECT_EQ(deriveSeed(0, "a"), 0xaf63dc4c8601ec8cULL);
  EXPECT_EQ(deriveSeed(0, ""), 0xcbf29ce484222325ULL);
  EXPECT_EQ(deriveSeed(7, "foobar"), 0x85944171f73967e8ULL ^ 7ULL);
  EXPECT_NE(deriveSeed(1, "fountain"), deriveSeed(1, "fountain2"));
}
