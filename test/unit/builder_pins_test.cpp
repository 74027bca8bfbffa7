// Pin indices as builders accept them: negative ones count from the end.

#include <gtest/gtest.h>

#include <vector>

#include "particle_sim/core/builders/pins.h"
#include "particle_sim/core/builders/rope.h"
#include "particle_sim/core/spring_network.h"

using namespace particle_sim::core;

TEST(BuilderPins, NegativeIndicesCountFromTheEnd)
{
  EXPECT_EQ(resolvePinIndex(0, 5), 0);
  EXPECT_EQ(resolvePinIndex(4, 5), 4);
  EXPECT_EQ(resolvePinIndex(-1, 5), 4);
  EXPECT_EQ(resolvePinIndex(-5, 5), 0);
  std::vector<int> out{7};
  appendPins({0, -1, -2}, 10, out);
  EXPECT_EQ(out, (std::vector<int>{7, 0, 9, 8}));  // appended after what was there, in order

  // The rope builder resolves its pins through it.
  RopeDef rope;
  rope.name = "rope";
  rope.particles = 6;
  rope.pins = {0, -1};
  ASSERT_TRUE(validate(rope, 100).ok);
  EXPECT_EQ(buildRope(rope).pins, (std::vector<int>{0, 5}));
}
