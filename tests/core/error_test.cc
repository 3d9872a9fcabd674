#include "impactdic/core/error.h"

#include <gtest/gtest.h>

namespace impactdic {
namespace {

TEST(Error, NamesWhereFoundAndExpected) {
  Error e(ErrorKind::kInvalidValue, "dic.subset_size", "24", "an odd integer >= 5");
  e.WithFile("scene.yaml", 12, 3);
  EXPECT_STREQ(
      e.what(),
      "scene.yaml:12:3: dic.subset_size: invalid value (got 24); expected an odd integer >= 5");
  EXPECT_EQ(e.line(), 12);
  EXPECT_EQ(ExitCode(e.kind()), 1);
}

TEST(Error, CheckValueThrowsOnlyWhenViolated) {
  EXPECT_NO_THROW(CheckValue(true, "x", "1", "anything"));
  try {
    CheckValue(false, "--rtol", "-1", "a number > 0");
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--rtol"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("-1"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("a number > 0"), std::string::npos);
  }
}

}  // namespace
}  // namespace impactdic
