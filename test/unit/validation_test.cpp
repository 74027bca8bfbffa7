// Refusals of bad values: one range per quantity (limits.h) in every definition and every entry
// point the node calls (World setters, spawns, spring constants); messages name the field, the
// value as received ("nan", "inf", never "-nan", never a clamped value), the range and the unit;
// received text is cut at a character boundary and never breaks UTF-8.

#include "particle_sim/core/validation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "particle_sim/core/world.h"

using namespace particle_sim::core;

namespace
{
::testing::AssertionResult contains(const std::string& message, const std::string& part)
{
  if (message.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << message << "' does not contain '" << part << "'";
}

// Whether `text` is well-formed UTF-8 (checked independently of the helpers under test).
bool validUtf8(const std::string& text)
{
  std::size_t i = 0;
  while (i < text.size())
  {
    const unsigned char lead = static_cast<unsigned char>(text[i]);
    const int extra = lead < 0x80 ? 0 : (lead >> 5) == 0x6 ? 1 : (lead >> 4) == 0xE ? 2 : (lead >> 3) == 0x1E ? 3 : -1;
    if (extra < 0) return false;  // a stray continuation byte or an invalid lead byte
    for (int k = 1; k <= extra; ++k)
    {
      if (i + k >= text.size() || (static_cast<unsigned char>(text[i + k]) & 0xC0) != 0x80) return false;
    }
    i += 1 + extra;
  }
  return true;
}

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

World makeWorld()
{
  WorldDef def;
  return World(def);
}

RopeDef rope(const std::string& name)
{
  RopeDef def;
  def.name = name;
  def.particles = 5;
  return def;
}
}  // namespace

TEST(Validation, NonFiniteValuesPrintAsNanAndInfNeverMinusNan)
{
  EXPECT_EQ(formatValue(kNaN), "nan");
  EXPECT_EQ(formatValue(-kNaN), "nan");  // a NaN with its sign bit set prints "-nan" through iostreams
  EXPECT_EQ(formatValue(std::copysign(kNaN, -1.0)), "nan");
  EXPECT_EQ(formatValue(kInf), "inf");
  EXPECT_EQ(formatValue(-kInf), "-inf");
  EXPECT_EQ(formatValue(Eigen::Vector3d(std::copysign(kNaN, -1.0), 1.5, -kInf)), "[nan, 1.5, -inf]");
  const Status s = checkRange("stiffness", std::copysign(kNaN, -1.0), limits::kStiffness);
  EXPECT_FALSE(s.ok);
  EXPECT_TRUE(contains(s.message, "stiffness = nan is not a finite number: must be in [0, 1e+09] N/m"));
  EXPECT_FALSE(contains(s.message, "-nan"));
}

TEST(Validation, RangeMessagesNameFieldValueRangeAndUnit)
{
  const Status s = checkRange("stiffness", 1e200, limits::kStiffness);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "stiffness = 1e+200 is out of range: must be in [0, 1e+09] N/m");
  EXPECT_TRUE(checkRange("stiffness", 1e9, limits::kStiffness).ok);  // the bounds are inclusive
  EXPECT_TRUE(checkRange("stiffness", 0.0, limits::kStiffness).ok);
  const Status wind = checkRange("wind", Eigen::Vector3d(0.0, 1e308, 0.0), limits::kWindComponent);
  EXPECT_EQ(wind.message, "wind.y = 1e+308 is out of range: must be in [-100, 100] m/s (wind = [0, 1e+308, 0])");
}

TEST(Validation, WorldSettersRefuseOutOfRangeValuesAndKeepTheOldOnes)
{
  World world = makeWorld();
  ASSERT_TRUE(world.setWind({1.0, 2.0, 3.0}).ok);
  const Status wind = world.setWind({1e308, 0.0, 0.0});
  EXPECT_FALSE(wind.ok);
  EXPECT_TRUE(contains(wind.message, "wind.x = 1e+308 is out of range: must be in [-100, 100] m/s"));
  EXPECT_EQ(world.environment().air.wind, Eigen::Vector3d(1.0, 2.0, 3.0));

  const Status gravity = world.setGravity({0.0, 0.0, -1e5});
  EXPECT_FALSE(gravity.ok);
  EXPECT_TRUE(contains(gravity.message, "gravity.z = -100000 is out of range: must be in [-100, 100] m/s^2"));
  EXPECT_EQ(world.environment().gravity, Eigen::Vector3d(0.0, 0.0, -9.81));

  const Status damping = world.setGlobalDamping(1e300);
  EXPECT_FALSE(damping.ok);
  EXPECT_TRUE(contains(damping.message, "global_damping = 1e+300 is out of range: must be in [0, 100] 1/s"));
  const Status negative = world.setGlobalDamping(-1.0);
  EXPECT_TRUE(contains(negative.message, "global_damping = -1 is out of range"));
  EXPECT_TRUE(world.setGlobalDamping(100.0).ok);
  EXPECT_EQ(world.environment().damping, 100.0);

  WorldDef def;
  def.air.wind = {0.0, 0.0, 200.0};
  EXPECT_TRUE(contains(validate(def).message, "air.wind.z = 200 is out of range: must be in [-100, 100] m/s"));
  def = WorldDef{};
  def.global_damping = 101.0;
  EXPECT_TRUE(contains(validate(def).message, "global_damping = 101 is out of range"));
  def.global_damping = 2.0;
  ASSERT_TRUE(validate(def).ok);
  EXPECT_EQ(World(def).environment().damping, 2.0);  // the world starts with it
}

TEST(Validation, SpringConstantsOutOfRangeAreRefusedInEveryDefinition)
{
  World world = makeWorld();
  const std::string range = "is out of range: must be in [0, 1e+09] N/m";

  RopeDef r = rope("r");
  r.stretch_stiffness = 1e200;
  EXPECT_TRUE(contains(world.addRope(r).message, "stretch.stiffness = 1e+200 " + range));
  r = rope("r");
  r.bend_damping = 1e308;
  EXPECT_TRUE(contains(world.addRope(r).message, "bend.damping = 1e+308 is out of range: must be in [0, 1e+06] N·s/m"));

  SpringNetworkDef net;
  net.name = "n";
  net.positions = {Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX()};
  net.masses = {1.0, 1.0};
  net.springs = {Spring{0, 1, 1.0, 1e308, 0.0, SpringClass::Stretch}};
  EXPECT_TRUE(contains(world.addSpringNetwork(net).message, "springs[0].stiffness = 1e+308 " + range));

  ClothGridDef grid;
  grid.name = "g";
  grid.shear.stiffness = 2e9;
  EXPECT_TRUE(contains(world.addClothGrid(grid).message, "shear.stiffness = 2e+09 " + range));
  ClothGridDef bw(ClothModel::BaraffWitkin);
  bw.name = "bw";
  bw.bend.stiffness = 1e200;
  EXPECT_TRUE(contains(world.addClothGrid(bw).message, "bend.stiffness = 1e+200 " + range));

  MeshClothDef mesh;
  mesh.name = "m";
  mesh.vertices = {Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY()};
  mesh.triangles = {Eigen::Vector3i(0, 1, 2)};
  mesh.stretch.stiffness = 1e10;
  EXPECT_TRUE(contains(world.addMeshCloth(mesh).message, "stretch.stiffness = 1e+10 " + range));

  JellyDef jelly;
  jelly.name = "j";
  jelly.stretch.damping = 1e7;
  EXPECT_TRUE(contains(world.addJelly(jelly).message, "stretch.damping = 1e+07 is out of range"));

  EXPECT_TRUE(world.bodies().empty());
}

TEST(Validation, SetSpringConstantsRefusesOutOfRangeAndKeepsTheOldConstants)
{
  World world = makeWorld();
  ASSERT_TRUE(world.addRope(rope("r")).ok);
  SpringNetworkBody& body = *world.findSpringBody("r");
  const double before = body.springs()[0].stiffness;
  const Status s = body.setSpringConstants(std::nullopt, 1e200, 0.1);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message, "stiffness = 1e+200 is out of range: must be in [0, 1e+09] N/m");
  EXPECT_TRUE(contains(body.setSpringConstants(std::nullopt, 10.0, -kInf).message,
                       "damping = -inf is not a finite number: must be in [0, 1e+06] N·s/m"));
  EXPECT_EQ(body.springs()[0].stiffness, before);
  EXPECT_TRUE(body.setSpringConstants(std::nullopt, 1e9, 1e6).ok);
}

TEST(Validation, NamesAreLimitedTo64CharactersAndTheMessageGivesTheLength)
{
  EXPECT_TRUE(validateBodyName(std::string(64, 'a')).ok);
  const Status s = validateBodyName(std::string(100000, 'a'));
  EXPECT_FALSE(s.ok);
  EXPECT_TRUE(contains(s.message, "name = 'aaaa")) << s.message;
  EXPECT_TRUE(contains(s.message, "(100000 characters) is too long: must be 1 to 64 characters")) << s.message;
  EXPECT_EQ(s.message.find("100000"), s.message.rfind("100000")) << "the length is said once: " << s.message;
  EXPECT_LT(s.message.size(), 300u) << "the message must not echo the whole name";

  World world = makeWorld();
  const Status spawn = world.addRope(rope(std::string(65, 'r')));
  EXPECT_TRUE(contains(spawn.message, "(65 characters) is too long: must be 1 to 64 characters")) << spawn.message;
  EmitterDef emitter;
  emitter.name = std::string(1000, 'e');
  EXPECT_TRUE(contains(world.addEmitter(emitter).message, "(1000 characters) is too long"));
  EXPECT_TRUE(world.bodies().empty());
}

TEST(Validation, ReceivedTextIsCutAtACharacterBoundaryAndStaysValidUtf8)
{
  // 'é' is two bytes: 100 of them are 200 bytes; a cut at any byte count must not split one.
  std::string accents;
  for (int k = 0; k < 100; ++k)
    accents += "\xC3\xA9";
  const std::string q = quoteReceived(accents);
  EXPECT_TRUE(validUtf8(q)) << q;
  EXPECT_TRUE(contains(q, "(100 characters)"));
  std::string shown;
  for (int k = 0; k < 64; ++k)
    shown += "\xC3\xA9";
  EXPECT_TRUE(contains(q, "'" + shown + "...'"));

  // A three-byte character straddling the 64th character, and a name refused for its length.
  const std::string name = std::string(63, 'a') + "\xE2\x82\xAC" + std::string(10, 'b');  // 'euro' sign at 64
  const Status s = validateBodyName(name);
  EXPECT_TRUE(contains(s.message, "(74 characters) is too long"));
  EXPECT_TRUE(validUtf8(s.message)) << s.message;

  // A refused character is shown whole, not as its first byte.
  const Status euro = validateBodyName("price_\xE2\x82\xAC");
  EXPECT_TRUE(contains(euro.message, "has the character '\xE2\x82\xAC'")) << euro.message;
  EXPECT_TRUE(validUtf8(euro.message));

  // Bytes that are not UTF-8 at all are escaped, never passed on.
  const Status broken = validateBodyName("bad\xC3");
  EXPECT_TRUE(validUtf8(broken.message)) << broken.message;
  EXPECT_TRUE(contains(broken.message, "\\xC3"));
}
