// Each results group's names are declared once, by its owner (io/results_layout.h
// lists them). No other source file of the library spells a results path ("/sensor/t_s",
// "momentum/p_gran", "/model") as a string literal: it uses the owner's names, so that a renamed
// dataset cannot leave a writer or reader behind.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "../core/test_paths.h"

namespace {
namespace fs = std::filesystem;

// Group -> the files allowed to spell its paths: the owner's schema header (names) and the
// owner's writer/reader.
const std::map<std::string, std::set<std::string>>& Owners() {
  static const std::map<std::string, std::set<std::string>> owners = {
      {"dic", {"include/impactdic/io/results_layout.h", "src/io/dic_results.cc"}},
      {"strain", {"include/impactdic/io/results_layout.h", "src/strain/strain_results.cc"}},
      {"time", {"include/impactdic/io/results_layout.h"}},
      {"frames", {"include/impactdic/io/results_layout.h"}},
      {"xdmf", {"include/impactdic/io/results_layout.h"}},
      {"sensor", {"include/impactdic/sensor/sensor_results.h", "src/sensor/sensor_results.cc"}},
      {"kinematics",
       {"include/impactdic/kinematics/kinematics_results.h",
        "src/kinematics/kinematics_results.cc"}},
      {"momentum",
       {"include/impactdic/momentum/momentum_results.h", "src/momentum/momentum_results.cc"}},
      {"model", {"include/impactdic/model/model_results.h", "src/model/model_results.cc"}},
  };
  return owners;
}

// Sources that spell paths of another file's layout, with the reason. synth writes the truth.h5
// of a synthetic scene (docs/synth.md: its own /momentum, /sensor, /frames ..., not results.h5's);
// validate-dem reads that truth file in ReadTruth (only that function is exempt).
bool Exempt(const std::string& file, const std::string& function) {
  if (file.rfind("src/synth/", 0) == 0) return true;
  return file == "src/render/dem_validation.cc" && function == "ReadTruth";
}

struct Hit {
  std::string file;
  int line;
  std::string literal;
};

// The group of the results path a string literal spells, "" if none: a dataset path
// "/group/name" or "group/name" (time and frames only with the leading slash: "frames/" is also
// a folder of frame images), or a group alone, "/group". A message or help text naming a path in
// prose ("view of /dic/x_px, ...") is not a path literal.
std::string ResultsGroupOf(const std::string& literal) {
  static const std::regex path(
      R"(^(/?(dic|strain|sensor|kinematics|momentum|model)/\w|/(dic|strain|sensor|kinematics|momentum|model|time|frames|xdmf)(/\w|$)))");
  std::smatch m;
  if (!std::regex_search(literal, m, path)) return "";
  return m[2].matched ? m[2].str() : m[3].str();
}

std::vector<Hit> ScanFile(const fs::path& root, const fs::path& path) {
  const std::string file = fs::relative(path, root).generic_string();
  std::ifstream in(path);
  std::vector<Hit> hits;
  static const std::regex literal_rx(R"re("((?:[^"\\]|\\.)*)")re");
  static const std::regex function_rx(R"(^[A-Za-z].*\b(\w+)\()");
  std::string line, function;
  for (int n = 1; std::getline(in, line); ++n) {
    std::smatch f;
    if (std::regex_search(line, f, function_rx)) function = f[1].str();
    const auto code_begin = line.find_first_not_of(' ');
    if (code_begin != std::string::npos && line.compare(code_begin, 2, "//") == 0) continue;
    if (line.rfind("#include", 0) == 0) continue;
    for (std::sregex_iterator it(line.begin(), line.end(), literal_rx), end; it != end; ++it) {
      const std::string text = (*it)[1].str();
      const std::string group = ResultsGroupOf(text);
      if (group.empty() || Owners().at(group).count(file) || Exempt(file, function)) continue;
      hits.push_back({file, n, text});
    }
  }
  return hits;
}

std::vector<Hit> ScanTree(const fs::path& root) {
  std::vector<Hit> hits;
  for (const char* dir : {"src", "include"}) {
    for (const auto& e : fs::recursive_directory_iterator(root / dir)) {
      const std::string ext = e.path().extension().string();
      if (!e.is_regular_file() || (ext != ".cc" && ext != ".h" && ext != ".def")) continue;
      for (Hit& h : ScanFile(root, e.path())) hits.push_back(std::move(h));
    }
  }
  return hits;
}

TEST(ResultsPaths, TheScannerFindsPathLiterals) {
  EXPECT_EQ(ResultsGroupOf("sensor/t_s"), "sensor");
  EXPECT_EQ(ResultsGroupOf("/model/z_m"), "model");
  EXPECT_EQ(ResultsGroupOf("/model"), "model");
  EXPECT_EQ(ResultsGroupOf("momentum/p_pounder"), "momentum");
  EXPECT_EQ(ResultsGroupOf("kinematics/vx_mm_s"), "kinematics");
  EXPECT_EQ(ResultsGroupOf("/time/t_ms"), "time");
  // Not paths: a stage name, a folder of images, prose naming a group or a dataset.
  EXPECT_EQ(ResultsGroupOf("model"), "");
  EXPECT_EQ(ResultsGroupOf("frames/frame_*.png"), "");
  EXPECT_EQ(ResultsGroupOf("/sensor, /kinematics, /momentum into the results HDF5"), "");
  EXPECT_EQ(ResultsGroupOf("view of /dic/x_px, /dic/y_px: subset centres"), "");
  EXPECT_EQ(ResultsGroupOf("units"), "");
}

TEST(ResultsPaths, NoResultsPathLiteralOutsideItsOwner) {
  const std::vector<Hit> hits = ScanTree(impactdic::SourceDir());
  std::ostringstream list;
  for (const Hit& h : hits) list << h.file << ":" << h.line << ": \"" << h.literal << "\"\n";
  EXPECT_TRUE(hits.empty()) << "results paths spelled outside their group's owner (use the "
                               "owner's names, io/results_layout.h lists them):\n"
                            << list.str();
}

}  // namespace
