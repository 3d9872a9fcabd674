// Helpers of the fault-injection suite: run the CLI on a bad input and check that it fails with
// exit code 1 and one message naming what is wrong, and small inputs to break.
#ifndef IMPACTDIC_TESTS_RELIABILITY_FAULT_UTIL_H_
#define IMPACTDIC_TESTS_RELIABILITY_FAULT_UTIL_H_

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <utility>
#include <vector>

#include "../cli/cli_runner.h"
#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "impactdic/io/image_io.h"

namespace impactdic {

// Runs `impactdic <arguments>` and expects exit code 1 and every text in `parts` (file or
// option, value, what is expected) in its output. Returns the output for further checks.
inline std::string ExpectCliFailure(const std::string& arguments,
                                    std::initializer_list<std::string> parts) {
  const CliResult r = RunCli(arguments);
  EXPECT_EQ(r.exit_code, 1) << "impactdic " << arguments << "\n" << r.output;
  for (const std::string& part : parts)
    EXPECT_NE(r.output.find(part), std::string::npos)
        << "'" << part << "' missing from the output of impactdic " << arguments << ":\n"
        << r.output;
  return r.output;
}

// A blurred random speckle image (correlates well), seeded.
inline cv::Mat Speckle(int width, int height, int seed) {
  cv::Mat image(height, width, CV_8U);
  cv::RNG rng(static_cast<std::uint64_t>(seed) + 1);
  rng.fill(image, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(image, image, cv::Size(5, 5), 1.2);
  return image;
}

// Writes `count` copies of one speckle image as <folder>/<prefix><number>.png for the numbers
// first, first + 1, ... (skipping `skip` if >= 0), with `digits` digits.
inline void WriteFrames(const TestDir& dir, const std::string& folder, const std::string& prefix,
                        int first, int count, int skip = -1, int digits = 4) {
  std::filesystem::create_directories(dir.path() / folder);
  const cv::Mat image = Speckle(96, 80, 7);
  for (int k = first; k < first + count; ++k) {
    if (k == skip) continue;
    const std::string number = std::to_string(k);
    const std::string padded =
        std::string(std::max(0, digits - static_cast<int>(number.size())), '0') + number;
    WriteImage(dir.File(folder + "/" + prefix + padded + ".png"), image);
  }
}

inline std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

inline void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

// Single-quoted for the shell (paths with globs).
inline std::string Quoted(const std::string& text) { return "'" + text + "'"; }

// The sample scene (sample_frames/scene.yaml) with absolute input paths, figures and animation off,
// each (from, to) of `edits` applied to its text and `extra` appended; written to DIR/scene.yaml.
inline std::string SampleScene(const TestDir& dir,
                               const std::vector<std::pair<std::string, std::string>>& edits,
                               const std::string& extra = "") {
  const std::string kSample = std::string(impactdic::SourceDir()) + "/sample_frames";
  std::string text = ReadBytes(kSample + "/scene.yaml");
  std::vector<std::pair<std::string, std::string>> all = {
      {"\"frames/frame_", "\"" + kSample + "/frames/frame_"},
      {"\"../calibration/", "\"" + kSample + "/../calibration/"},
      {"sensor: sensor.csv", "sensor: " + kSample + "/sensor.csv"},
      {"truth: truth.h5", "truth: " + kSample + "/truth.h5"},
      {"figures: true", "figures: false"},
      {"animation: true", "animation: false"}};
  all.insert(all.end(), edits.begin(), edits.end());
  for (const auto& [from, to] : all) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
  }
  return dir.Write("scene.yaml", text + extra);
}

}  // namespace impactdic

#endif  // IMPACTDIC_TESTS_RELIABILITY_FAULT_UTIL_H_
