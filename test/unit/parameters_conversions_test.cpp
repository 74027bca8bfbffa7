// The node's parameters, checked before anything starts, without a ROS master: the defaults pass,
// and each bad value is refused with a message naming the parameter, the value as received and
// what is allowed (the ranges of core/limits.h where there is one).

#include <gtest/gtest.h>

#include <limits>

#include "particle_sim/core/limits.h"
#include "particle_sim/core/materials/cloth_material.h"
#include "particle_sim/core/materials/rope_material.h"
#include "particle_sim/ros/parameters.h"

using namespace particle_sim;
using namespace particle_sim::ros_interface;

namespace
{
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

std::string refusal(const NodeSettings& settings)
{
  const core::Status status = validate(settings);
  EXPECT_FALSE(status.ok);
  return status.message;
}
}  // namespace

TEST(ParametersConversions, DefaultsAreValidAndDocumented)
{
  const NodeSettings defaults;
  EXPECT_TRUE(validate(defaults).ok);
  EXPECT_EQ(defaults.rate, 50.0);             // [Hz]
  EXPECT_EQ(defaults.real_time_factor, 1.0);  // [-]
  EXPECT_EQ(defaults.max_lag, 0.5);           // [s]
  EXPECT_EQ(defaults.dt, 0.0);                // the scene's
  EXPECT_EQ(defaults.frame_id, "world");
  EXPECT_EQ(defaults.parent_frame_id, "map");
  EXPECT_EQ(defaults.particle_size, 0.05);     // [m]
  EXPECT_EQ(defaults.diagnostic_period, 1.0);  // [s]
}

TEST(ParametersConversions, RateAndRealTimeFactorAreRefusedOutsideTheirLimits)
{
  NodeSettings s;
  s.rate = 0.05;  // below limits::kPublishRate.min = 0.1 Hz
  EXPECT_EQ(refusal(s), "~rate = 0.05 is out of range: must be in [0.1, 1000] Hz");
  s.rate = kNaN;
  EXPECT_EQ(refusal(s), "~rate = nan is out of range: must be in [0.1, 1000] Hz");
  s.rate = core::limits::kPublishRate.max;  // the bounds are allowed
  EXPECT_TRUE(validate(s).ok);

  s.real_time_factor = -1.0;
  EXPECT_EQ(refusal(s),
            "~real_time_factor = -1 is out of range: must be in [0, 1000] - (0 = as fast as possible; negative "
            "values have no meaning)");
  s.real_time_factor = 0.0;  // as fast as possible
  EXPECT_TRUE(validate(s).ok);

  s.max_lag = -0.1;
  EXPECT_EQ(refusal(s), "~max_lag = -0.1 is out of range: must be in [0, 60] s (0 = never make up a late tick)");
  s.max_lag = kInf;
  EXPECT_EQ(refusal(s), "~max_lag = inf is out of range: must be in [0, 60] s (0 = never make up a late tick)");
  s.max_lag = 0.0;
  EXPECT_TRUE(validate(s).ok);
}

TEST(ParametersConversions, SizesPeriodsAndStrainsMustBePositiveAndFinite)
{
  NodeSettings s;
  s.particle_size = 0.0;
  EXPECT_EQ(refusal(s), "~particle_size = 0 must be > 0 m");
  s = NodeSettings();
  s.strain_color_max = -0.1;
  EXPECT_EQ(refusal(s), "~strain_color_max = -0.1 must be > 0");
  s = NodeSettings();
  s.diagnostic_period = kInf;
  EXPECT_EQ(refusal(s), "~diagnostic_period = inf must be > 0 s");
  s = NodeSettings();
  s.diagnostic_max_strain = kNaN;
  EXPECT_EQ(refusal(s), "~diagnostic_max_strain = nan must be > 0");
}

TEST(ParametersConversions, FramesMustBeNamedDistinctAndTheOffsetThreeFiniteNumbers)
{
  NodeSettings s;
  s.frame_id.clear();
  EXPECT_EQ(refusal(s), "~frame_id is empty");
  s = NodeSettings();
  s.parent_frame_id = "world";
  EXPECT_EQ(refusal(s), "~parent_frame_id = 'world' must be set and differ from ~frame_id");
  s = NodeSettings();
  s.frame_offset = {1.0, 2.0};
  EXPECT_EQ(refusal(s), "~frame_offset must be a list of 3 finite numbers [x, y, z] in m");
  s.frame_offset = {1.0, kNaN, 2.0};
  EXPECT_EQ(refusal(s), "~frame_offset must be a list of 3 finite numbers [x, y, z] in m");
}

TEST(ParametersConversions, DefaultMaterialsMustBeEmptyOrAPreset)
{
  NodeSettings s;
  EXPECT_TRUE(s.rope_material.empty());  // no default material: spawned bodies as before
  EXPECT_TRUE(s.cloth_material.empty());
  s.rope_material = core::ropePresets().front().name;
  s.cloth_material = core::clothPresets().front().name;
  EXPECT_TRUE(validate(s).ok) << validate(s).message;

  s.rope_material = "hemp?";
  EXPECT_EQ(refusal(s), "~rope_material = 'hemp?' is not a rope material preset; allowed: " + core::ropePresetNames());
  s.rope_material.clear();
  s.cloth_material = "Cotton ";  // names are exact
  EXPECT_EQ(refusal(s),
            "~cloth_material = 'Cotton ' is not a cloth material preset; allowed: " + core::clothPresetNames());
}

TEST(ParametersConversions, ThreadsAreTheScenesByDefaultAndRefusedOutsideTheirLimits)
{
  NodeSettings s;
  EXPECT_EQ(s.threads, -1);  // the scene's world.threads
  for (int threads : {0, 1, 2, static_cast<int>(core::limits::kThreads.max)})
  {
    s.threads = threads;
    EXPECT_TRUE(validate(s).ok) << threads;
  }
  s.threads = -2;
  EXPECT_EQ(refusal(s),
            "~threads = -2 is out of range: must be in [0, 256] threads (0 = one per core; -1 = the scene's "
            "world.threads)");
  s.threads = 257;
  EXPECT_EQ(refusal(s),
            "~threads = 257 is out of range: must be in [0, 256] threads (0 = one per core; -1 = the scene's "
            "world.threads)");
}
