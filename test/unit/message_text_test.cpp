// Unit tests of the node's message text: valid UTF-8 of bounded length, values as received.

#include "particle_sim/ros/message_text.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

using particle_sim::ros_interface::formatReceived;
using particle_sim::ros_interface::quoteName;
using particle_sim::ros_interface::toMessageText;

TEST(MessageText, KeepsValidUtf8AsItIs)
{
  const std::string text = "frame = 'gr\xC3\xBC\xC3\x9F' \xE2\x86\x92 \xF0\x9F\x98\x80 ok";  // ü ß → 😀
  EXPECT_EQ(toMessageText(text), text);
}

TEST(MessageText, WritesBytesThatAreNotUtf8AsHex)
{
  EXPECT_EQ(toMessageText("a\xC3"
                          "b"),
            "a\\xC3b");                                                  // lead byte without its continuation
  EXPECT_EQ(toMessageText("\xA9x"), "\\xA9x");                           // stray continuation byte
  EXPECT_EQ(toMessageText("\xC0\xAF"), "\\xC0\\xAF");                    // overlong '/'
  EXPECT_EQ(toMessageText("\xED\xA0\x80"), "\\xED\\xA0\\x80");           // UTF-16 surrogate
  EXPECT_EQ(toMessageText("\xF4\x90\x80\x80"), "\\xF4\\x90\\x80\\x80");  // beyond U+10FFFF
  EXPECT_EQ(toMessageText("tab\there"), "tab\\x09here");                 // control characters too
}

TEST(MessageText, CutsLongTextOnACharacterBoundary)
{
  // "é" is two bytes: a 9-byte budget holds 4 of them (8 bytes), never half of the fifth.
  std::string text;
  for (int i = 0; i < 10; ++i)
    text += "\xC3\xA9";
  EXPECT_EQ(toMessageText(text, 9), "\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9... (20 bytes in all)");
  EXPECT_EQ(quoteName(std::string(100000, 'a')), "'" + std::string(80, 'a') + "... (100000 bytes in all)'");
  EXPECT_EQ(quoteName("rope"), "'rope'");
}

TEST(MessageText, FormatsNumbersAsReceived)
{
  EXPECT_EQ(formatReceived(1e300), "1e+300");
  EXPECT_EQ(formatReceived(0.1), "0.1");
  EXPECT_EQ(formatReceived(-1.0), "-1");
  EXPECT_EQ(formatReceived(1.0000001), "1.0000001");  // not rounded to 6 digits
  EXPECT_EQ(formatReceived(std::numeric_limits<double>::quiet_NaN()), "nan");
  EXPECT_EQ(formatReceived(-std::numeric_limits<double>::quiet_NaN()), "nan");  // never "-nan"
  EXPECT_EQ(formatReceived(-std::numeric_limits<double>::infinity()), "-inf");
}
