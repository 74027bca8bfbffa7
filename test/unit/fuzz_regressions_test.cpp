// The fuzz targets' entry functions (test/fuzz/fuzz_entries.cpp) under gcc: every input a fuzzer
// once crashed on (test/fuzz_regressions/TARGET/) is replayed, the seeds run, and the requests
// target's decoding is checked against the README's session. Under `scripts/test --sanitize` the
// replay runs with ASan and UBSan, as the fuzzers do.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz_entries.h"

namespace
{
using particle_sim::fuzz::RequestAnswer;
using particle_sim::fuzz::RequestSeed;

const std::string kSourceDir = PARTICLE_SIM_SOURCE_DIR;

std::vector<std::uint8_t> readBytes(const std::filesystem::path& path)
{
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The regular files below `folder` (none when it does not exist), sorted.
std::vector<std::filesystem::path> filesIn(const std::filesystem::path& folder)
{
  std::vector<std::filesystem::path> files;
  if (std::filesystem::is_directory(folder))
    for (const auto& entry : std::filesystem::recursive_directory_iterator(folder))
      if (entry.is_regular_file()) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<RequestAnswer> answersTo(const RequestSeed& seed)
{
  const std::vector<std::uint8_t> bytes = particle_sim::fuzz::encodeRequests({}, seed.requests);
  return particle_sim::fuzz::answerRequests(bytes.data(), bytes.size());
}

const RequestSeed& seedNamed(const std::string& name)
{
  static const std::vector<RequestSeed> seeds = particle_sim::fuzz::requestSeeds();
  for (const RequestSeed& seed : seeds)
    if (seed.name == name) return seed;
  throw std::runtime_error("no request seed " + name);
}
}  // namespace

// Each file of test/fuzz_regressions/TARGET/ once crashed TARGET: it must now run to the end (a
// crash ends this test binary, which scripts/test counts as a failure).
TEST(FuzzRegressions, EveryRecordedInputRunsToTheEnd)
{
  const std::filesystem::path root = kSourceDir + "/test/fuzz_regressions";
  for (const std::filesystem::path& input : filesIn(root))
    EXPECT_TRUE(std::any_of(particle_sim::fuzz::targets().begin(), particle_sim::fuzz::targets().end(),
                            [&](const auto& t) { return input.parent_path() == root / t.name; }))
        << input << " is not in the folder of a fuzz target";
  for (const particle_sim::fuzz::Target& target : particle_sim::fuzz::targets())
  {
    for (const std::filesystem::path& input : filesIn(root / target.name))
    {
      SCOPED_TRACE(input.string());
      const std::vector<std::uint8_t> bytes = readBytes(input);
      EXPECT_EQ(target.entry(bytes.data(), bytes.size()), 0);
    }
  }
}

// The seed corpora run through the entries too: shipped scenes (built, stepped, written back and
// read again) and meshes.
TEST(FuzzSeeds, ShippedScenesAndMeshesRunThroughTheEntries)
{
  int scenes = 0, meshes = 0;
  for (const std::filesystem::path& file : filesIn(kSourceDir + "/config"))
  {
    SCOPED_TRACE(file.string());
    const std::vector<std::uint8_t> bytes = readBytes(file);
    if (file.extension() == ".yaml")
    {
      EXPECT_EQ(particle_sim::fuzz::runSceneYaml(bytes.data(), bytes.size()), 0);
    }
    else if (file.extension() == ".obj")
    {
      EXPECT_EQ(particle_sim::fuzz::runObjMesh(bytes.data(), bytes.size()), 0);
    }
    scenes += file.extension() == ".yaml";
    meshes += file.extension() == ".obj";
  }
  EXPECT_GE(scenes, 20);
  EXPECT_GE(meshes, 1);
}

// The bytes of the README's session decode into its requests: the answers are those the README
// shows (the core's wording, before the node's "spawned ..." summaries).
TEST(FuzzRequests, ReadmeSessionDecodesIntoTheReadmeRequests)
{
  const std::vector<RequestAnswer> answers = answersTo(seedNamed("readme_session"));
  ASSERT_EQ(answers.size(), 9u);
  EXPECT_EQ(answers[0].service, "settings");
  EXPECT_TRUE(answers[0].success) << answers[0].message;
  EXPECT_EQ(answers[1].service, "spawn_emitter");
  EXPECT_TRUE(answers[1].success) << answers[1].message;
  EXPECT_EQ(answers[2].service, "spawn_emitter");
  EXPECT_FALSE(answers[2].success);
  EXPECT_EQ(answers[2].message.rfind("rate = -5 is out of range: must be >= 0", 0), 0u) << answers[2].message;
  EXPECT_EQ(answers[3].service, "step");
  EXPECT_EQ(answers[4].service, "spawn_rope");
  EXPECT_TRUE(answers[4].success) << answers[4].message;
  EXPECT_EQ(answers[5].service, "pin_particle");
  EXPECT_TRUE(answers[5].success) << answers[5].message;
  EXPECT_EQ(answers[6].service, "pin_particle");
  EXPECT_TRUE(answers[6].success) << answers[6].message;
  EXPECT_EQ(answers[7].service, "set_spring_constants");
  EXPECT_TRUE(answers[7].success) << answers[7].message;
  EXPECT_NE(answers[7].message.find("set stretch springs of 'line' to 200 N/m, 0.1 N·s/m"), std::string::npos)
      << answers[7].message;
}

// Every seed's spawn and change is accepted, so that the corpus starts from working requests.
TEST(FuzzRequests, EverySeedExceptTheReadmeRefusalIsAccepted)
{
  for (const RequestSeed& seed : particle_sim::fuzz::requestSeeds())
  {
    const std::vector<RequestAnswer> answers = answersTo(seed);
    ASSERT_EQ(answers.size(), seed.requests.size() + 1) << seed.name;
    for (std::size_t i = 0; i < answers.size(); ++i)
    {
      const bool readme_refusal = seed.name == "readme_session" && i == 2;
      EXPECT_EQ(answers[i].success, !readme_refusal)
          << seed.name << " #" << i << " " << answers[i].service << ": " << answers[i].message;
    }
  }
}

// Node settings the node refuses to start with stop the sequence with the parameter's message.
TEST(FuzzRequests, RefusedSettingsStopBeforeAnyRequest)
{
  particle_sim::ros_interface::NodeSettings settings;
  settings.rate = 0.0;
  const std::vector<std::uint8_t> bytes =
      particle_sim::fuzz::encodeRequests(settings, seedNamed("spawn_rope").requests);
  const std::vector<RequestAnswer> answers = particle_sim::fuzz::answerRequests(bytes.data(), bytes.size());
  ASSERT_EQ(answers.size(), 1u);
  EXPECT_FALSE(answers[0].success);
  EXPECT_EQ(answers[0].message.rfind("~rate = 0 is out of range: must be in [0.1, 1000] Hz", 0), 0u)
      << answers[0].message;
}
