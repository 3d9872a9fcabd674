// The one YAML section reader (io/yaml.h): every problem of a file at once, with line and key path;
// unknown keys suggest the closest known one; option tables bind keys to struct fields.
#include "impactdic/io/yaml.h"

#include <gtest/gtest.h>

#include <string>

#include "impactdic/core/error.h"

namespace impactdic {
namespace {

struct Options {
  int subset_px = 25;
  double min_zncc = 0.8;
  bool enabled = false;
  std::string mode = "auto";
};

YamlOptionTable Bind(Options* o) {
  YamlOptionTable t("dic");
  t.Add("subset_px", &o->subset_px, ValueRange{5, 201, "px"}, "subset size", "Subset side");
  t.Add("min_zncc", &o->min_zncc, ValueRange{-1, 1, "", false, /*max_open=*/true}, "a threshold",
        "Validity");
  t.Add("enabled", &o->enabled, "On/off");
  t.AddChoice(
      "mode", {"auto", "fixed"}, o->mode, [o](const std::string& v) { o->mode = v; }, "Mode");
  return t;
}

// Reads `text` into Options; returns the error text ("" when none).
std::string Read(const std::string& text, Options* o) {
  try {
    const YAML::Node root = LoadYaml(text, "spec.yaml", "a test file");
    YamlProblems problems("spec.yaml");
    YamlSection top(root, "", &problems);
    YamlSection dic = top.Sub("dic");
    Bind(o).Read(dic);
    dic.Finish();
    top.Finish();
    problems.ThrowIfAny("test file");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(YamlOptionTable, ReadsBoundFieldsAndLeavesAbsentKeysAtTheStructDefault) {
  Options o;
  EXPECT_EQ(Read("dic: {subset_px: 31, mode: fixed}\n", &o), "");
  EXPECT_EQ(o.subset_px, 31);
  EXPECT_EQ(o.mode, "fixed");
  EXPECT_EQ(o.min_zncc, Options{}.min_zncc);
  EXPECT_EQ(o.enabled, Options{}.enabled);
}

TEST(YamlOptionTable, DocumentsTheDefaultsOfTheBoundStruct) {
  Options o;
  const std::string rows = Bind(&o).Reference();
  EXPECT_NE(rows.find("| `dic.subset_px` | 25 | an integer subset size in [5, 201] px | Subset "
                      "side |"),
            std::string::npos)
      << rows;
  EXPECT_NE(rows.find("| `dic.min_zncc` | 0.8 | a threshold in [-1, 1) | Validity |"),
            std::string::npos)
      << rows;
  EXPECT_NE(rows.find("| `dic.mode` | auto | one of auto, fixed | Mode |"), std::string::npos)
      << rows;
}

TEST(YamlSection, EveryProblemIsReportedOnceWithLineKeyPathValueAndExpectation) {
  Options o;
  const std::string msg = Read(R"(dic:
  subset_px: 4
  min_zncc: 1
  enabled: maybe
  mode: fixd
  subset_pz: 25
tset: 1
)",
                               &o);
  for (const char* expected :
       {"6 problems in test file spec.yaml:",
        "spec.yaml:2: dic.subset_px: got '4'; expected an integer subset size in [5, 201] px",
        "spec.yaml:3: dic.min_zncc: got '1'; expected a threshold in [-1, 1)",
        "spec.yaml:4: dic.enabled: got 'maybe'; expected true or false",
        "spec.yaml:5: dic.mode: got 'fixd'; expected one of auto, fixed (did you mean 'fixed'?)",
        "spec.yaml:6: dic.subset_pz: unknown key (did you mean 'subset_px'?)",
        "spec.yaml:7: tset: unknown key"}) {
    EXPECT_NE(msg.find(expected), std::string::npos) << "missing: " << expected << "\nin:\n" << msg;
  }
  // A bad value leaves the field at its default.
  EXPECT_EQ(o.subset_px, Options{}.subset_px);
}

TEST(YamlSection, ASectionThatIsNotAMapIsOneProblem) {
  Options o;
  const std::string msg = Read("dic: [1, 2]\n", &o);
  EXPECT_NE(msg.find("spec.yaml:1: dic: got a list of 2; expected a map of keys"),
            std::string::npos)
      << msg;
}

TEST(ClosestMatch, OnlySuggestsCloseWords) {
  EXPECT_EQ(ClosestMatch("subset_sise", {"subset_size", "step"}), "subset_size");
  EXPECT_EQ(ClosestMatch("tset", {"test", "dic"}), "test");
  EXPECT_EQ(ClosestMatch("zzzzzz", {"subset_size", "step"}), "");
}

}  // namespace
}  // namespace impactdic
