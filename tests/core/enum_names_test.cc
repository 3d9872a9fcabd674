// core/enum_names.h: one list of an enum's names serves ToString, FromString, the scene's choices
// and the messages.
#include "impactdic/core/enum_names.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "expect_error.h"

namespace impactdic {
namespace {

enum class Colour { kRed, kGreen, kDarkBlue };
constexpr EnumNames<Colour, 3> kColourNames{{{{Colour::kRed, "red"},
                                              {Colour::kGreen, "green", "verde vert"},
                                              {Colour::kDarkBlue, "dark-blue"}}}};
constexpr EnumNames<Colour, 2> kCaseFreeNames{{{{Colour::kRed, "red"}, {Colour::kGreen, "green"}}},
                                              /*ignore_case=*/true};

TEST(EnumNames, NamesParseAndExpectedTextComeFromTheOneList) {
  EXPECT_STREQ(kColourNames.Name(Colour::kDarkBlue), "dark-blue");
  EXPECT_STREQ(kCaseFreeNames.Name(Colour::kDarkBlue), "?");  // Not listed there.
  EXPECT_EQ(kColourNames.Names(), (std::vector<std::string>{"red", "green", "dark-blue"}));
  EXPECT_EQ(kColourNames.Expected(), "one of red, green, dark-blue");
  for (const EnumName<Colour>& e : kColourNames.entries) {
    EXPECT_EQ(kColourNames.Parse(e.name, "colour"), e.value) << e.name;
  }
  EXPECT_EQ(kColourNames.Parse("verde", "colour"), Colour::kGreen);
  EXPECT_EQ(kColourNames.Parse("vert", "colour"), Colour::kGreen);
  // Neither part of an alias list nor a different case is a name.
  for (const std::string bad : {"verde vert", "ver", "", "Red", " red"}) {
    EXPECT_EQ(ErrorText([&] { kColourNames.Parse(bad, "scene.colour"); }),
              "scene.colour: invalid value (got '" + bad + "'); expected one of red, green, " +
                  "dark-blue")
        << bad;
  }
  EXPECT_EQ(kCaseFreeNames.Parse("GREEN", "colour"), Colour::kGreen);
}

}  // namespace
}  // namespace impactdic
