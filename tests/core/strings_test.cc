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

}  // namespace
}  // namespace impactdic
