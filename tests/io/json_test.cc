#include "impactdic/io/json.h"

#include <gtest/gtest.h>

#include <cmath>

namespace impactdic {
namespace {

TEST(Json, NanBecomesNullAndStringsAreEscaped) {
  JsonObject j;
  j.Add("a", 1.5)
      .Add("nan", std::nan(""))
      .Add("s", "x\"y\n")
      .Add("list", std::vector<std::string>{"w"});
  j.Add("n", 3).Add("v", std::vector<double>{1, INFINITY});
  EXPECT_EQ(j.Dump(0),
            R"({"a": 1.5, "nan": null, "s": "x\"y\n", "list": ["w"], "n": 3, "v": [1, null]})");
}

}  // namespace
}  // namespace impactdic
