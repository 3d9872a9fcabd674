#include "impactdic/core/strings.h"

#include <gtest/gtest.h>

namespace impactdic {
namespace {

TEST(Strings, ToLowerChangesOnlyAsciiLetters) {
  EXPECT_EQ(ToLower("Accel_G m/S^2"), "accel_g m/s^2");
  EXPECT_EQ(ToLower(""), "");
}

TEST(Strings, PrefixAndSuffix) {
  EXPECT_TRUE(StartsWith("force_1", "force"));
  EXPECT_FALSE(StartsWith("f", "force"));
  EXPECT_TRUE(EndsWith("out.h5", ".h5"));
  EXPECT_FALSE(EndsWith("out.H5", ".h5"));
  EXPECT_FALSE(EndsWith("h5", ".h5"));
  EXPECT_TRUE(EndsWithIgnoreCase("out.H5", ".h5"));
  EXPECT_FALSE(EndsWithIgnoreCase("out.csv", ".h5"));
}

TEST(Strings, JoinSeparatesItems) {
  EXPECT_EQ(Join({"a", "b", "c"}), "a, b, c");
  EXPECT_EQ(Join({"a"}, " or "), "a");
  EXPECT_EQ(Join({}), "");
}

TEST(Strings, ParseNumberTakesTheWholeTextOnly) {
  EXPECT_EQ(ParseNumber("0.25"), 0.25);
  EXPECT_EQ(ParseNumber("-1e-3"), -1e-3);
  EXPECT_EQ(ParseNumber("7"), 7.0);
  EXPECT_FALSE(ParseNumber(""));
  EXPECT_FALSE(ParseNumber("0.25px"));
  EXPECT_FALSE(ParseNumber("px"));
  EXPECT_FALSE(ParseNumber("1e999"));  // Out of range.
  EXPECT_FALSE(ParseNumber(" "));
}

}  // namespace
}  // namespace impactdic
