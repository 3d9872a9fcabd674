// `impactdic init` and the scene template it writes (pipeline/scene_template.h): generated from the
// scene's option tables, it holds every key at the library's default and parses as written.
#include "impactdic/pipeline/scene_template.h"

#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "../cli/cli_runner.h"
#include "../core/test_paths.h"
#include "impactdic/io/yaml.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

const char* kPath = "study/scene.yaml";

// The line of `key` under `section` ("inputs", "frames"): the first line "  key:" after the
// section's own line; "" when absent.
std::string LineOf(const std::string& text, const std::string& section, const std::string& key) {
  const std::size_t begin = text.find("\n" + section + ":\n");
  if (begin == std::string::npos) return "";
  const std::size_t at = text.find("\n  " + key + ":", begin);
  if (at == std::string::npos) return "";
  return text.substr(at + 1, text.find('\n', at + 1) - at - 1);
}

// `text` with the line of `key` under `section` replaced by "  key: value".
std::string Fill(const std::string& text, const std::string& section, const std::string& key,
                 const std::string& value) {
  const std::string line = LineOf(text, section, key);
  EXPECT_FALSE(line.empty()) << section << "." << key;
  std::string filled = text;
  filled.replace(filled.find(line, filled.find("\n" + section + ":\n")), line.size(),
                 "  " + key + ": " + value);
  return filled;
}

// Every key of every table of `scene` shows the same default text as in `reference`.
void ExpectSameDefaults(Scene* scene, Scene* reference) {
  const std::vector<YamlOptionTable> got = SceneOptionTables(scene);
  const std::vector<YamlOptionTable> want = SceneOptionTables(reference);
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t t = 0; t < got.size(); ++t) {
    ASSERT_EQ(got[t].entries().size(), want[t].entries().size()) << want[t].section();
    for (std::size_t i = 0; i < got[t].entries().size(); ++i) {
      EXPECT_EQ(got[t].entries()[i].default_text, want[t].entries()[i].default_text)
          << want[t].section() << "." << want[t].entries()[i].key;
    }
  }
}

TEST(SceneTemplate, ParsesAsWrittenWithTheLibraryDefaults) {
  Scene parsed = ParseScene(SceneTemplate(), kPath);
  // What the template gives beyond the defaults: its frames placeholder (a scene needs frames).
  Scene reference = ParseScene(
      std::string("inputs: {frames: \"") + kSceneTemplateFramesPlaceholder + "\"}\n", kPath);
  ExpectSameDefaults(&parsed, &reference);
  EXPECT_EQ(parsed.stages, AllSceneStages());
  EXPECT_EQ(parsed.dic.roi, (std::array<int, 4>{0, 0, 0, 0}));
  EXPECT_TRUE(parsed.dic.roi_polygon.empty());
  EXPECT_FALSE(parsed.momentum.options.rect_mm.has_value());
  EXPECT_EQ(parsed.inputs.frames, "study/frames/*.png");
  // The non-path keys are also a default-constructed Scene's (no scene file folder involved).
  Scene plain;
  const std::vector<YamlOptionTable> got = SceneOptionTables(&parsed);
  const std::vector<YamlOptionTable> want = SceneOptionTables(&plain);
  for (std::size_t t = 0; t < got.size(); ++t) {
    for (std::size_t i = 0; i < got[t].entries().size(); ++i) {
      if (want[t].entries()[i].expected == "a path") continue;
      EXPECT_EQ(got[t].entries()[i].default_text, want[t].entries()[i].default_text)
          << want[t].section() << "." << want[t].entries()[i].key;
    }
  }
}

TEST(SceneTemplate, HasEveryKeyOfTheOptionTablesNestedAsInTheSceneFile) {
  const YAML::Node root = LoadYaml(SceneTemplate(), kPath, "the scene template");
  Scene scene;
  for (const YamlOptionTable& table : SceneOptionTables(&scene)) {
    std::vector<std::string> path;
    std::stringstream parts(table.section());
    for (std::string part; std::getline(parts, part, '.');) path.push_back(part);
    ASSERT_LE(path.size(), 2u) << table.section();
    const YAML::Node section = path.size() == 1 ? root[path[0]] : root[path[0]][path[1]];
    ASSERT_TRUE(section.IsMap()) << table.section() << " is not a map in the template";
    for (const YamlOptionTable::Entry& entry : table.entries()) {
      EXPECT_TRUE(section[entry.key].IsDefined())
          << table.section() << "." << entry.key << " is not in the template";
    }
  }
}

TEST(SceneTemplate, MarksTheRequiredInputs) {
  const std::string text = SceneTemplate();
  for (const auto& [section, key] :
       std::vector<std::pair<std::string, std::string>>{{"inputs", "frames"},
                                                        {"inputs", "fps"},
                                                        {"inputs", "calibration"},
                                                        {"inputs", "mm_per_px"},
                                                        {"momentum", "pounder_center_x_px"},
                                                        {"momentum", "surface_y_px"}}) {
    EXPECT_NE(LineOf(text, section, key).find("# REQUIRED"), std::string::npos)
        << section << "." << key << ": " << LineOf(text, section, key);
  }
  EXPECT_NE(LineOf(text, "inputs", "frames").find(kSceneTemplateFramesPlaceholder),
            std::string::npos);
  // Optional keys are not marked.
  EXPECT_EQ(LineOf(text, "dic", "subset_size").find("REQUIRED"), std::string::npos);
  EXPECT_NE(text.find("impactdic run scene.yaml"), std::string::npos);
  EXPECT_NE(text.find("docs/scene_keys.md"), std::string::npos);
}

class InitCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = (fs::temp_directory_path() / ("impactdic_init_test_" + std::to_string(getpid())) /
            "new_study")
               .string();
    fs::remove_all(fs::path(dir_).parent_path());
  }
  void TearDown() override { fs::remove_all(fs::path(dir_).parent_path()); }
  std::string Read() const {
    std::ifstream in(scene_path());
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }
  std::string scene_path() const { return (fs::path(dir_) / "scene.yaml").string(); }
  std::string dir_;
};

TEST_F(InitCommand, WritesTheTemplateRefusesToOverwriteAndForceOverwrites) {
  const CliResult first = RunCli("init " + dir_);
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_EQ(Read(), SceneTemplate());

  std::ofstream(scene_path()) << "# the researcher's edits\n";
  const CliResult second = RunCli("init " + dir_);
  EXPECT_NE(second.exit_code, 0) << second.output;
  EXPECT_NE(second.output.find(scene_path()), std::string::npos) << second.output;
  EXPECT_NE(second.output.find("--force"), std::string::npos) << second.output;
  EXPECT_EQ(Read(), "# the researcher's edits\n");

  const CliResult forced = RunCli("init --force " + dir_);
  ASSERT_EQ(forced.exit_code, 0) << forced.output;
  EXPECT_EQ(Read(), SceneTemplate());
}

// The written file, its REQUIRED inputs filled from the sample (sample_frames/scene.yaml), is a
// scene that runs every stage.
TEST_F(InitCommand, WrittenSceneFilledWithTheSampleInputsParses) {
  ASSERT_EQ(RunCli("init " + dir_).exit_code, 0);
  const Scene sample = LoadScene(std::string(impactdic::SourceDir()) + "/sample_frames/scene.yaml");
  ASSERT_TRUE(sample.momentum.pounder_center_x_px && sample.momentum.surface_y_px);
  std::string text = Read();
  const auto quoted = [](const std::string& path) {
    std::string value = fs::absolute(path).lexically_normal().string();
    value.insert(value.begin(), '"');
    value.push_back('"');
    return value;
  };
  text = Fill(text, "inputs", "frames", quoted(sample.inputs.frames));
  text = Fill(text, "inputs", "fps", std::to_string(sample.inputs.fps));
  text = Fill(text, "inputs", "calibration", quoted(sample.inputs.calibration));
  text = Fill(text, "inputs", "sensor", quoted(sample.inputs.sensor));
  text = Fill(text, "momentum", "pounder_center_x_px",
              std::to_string(*sample.momentum.pounder_center_x_px));
  text = Fill(text, "momentum", "surface_y_px", std::to_string(*sample.momentum.surface_y_px));
  const Scene scene = ParseScene(text, scene_path());
  EXPECT_EQ(scene.inputs.frames, fs::absolute(sample.inputs.frames).lexically_normal().string());
  EXPECT_EQ(scene.inputs.fps, sample.inputs.fps);
  EXPECT_TRUE(scene.inputs.fps_given);
  EXPECT_EQ(scene.momentum.pounder_center_x_px, sample.momentum.pounder_center_x_px);
  EXPECT_TRUE(scene.HasStage("momentum"));
  EXPECT_TRUE(fs::exists(scene.inputs.calibration));
  EXPECT_TRUE(fs::exists(scene.inputs.sensor));
}

}  // namespace
}  // namespace impactdic
