// `impactdic run` on a camera file: the frames of a synthesised scene written
// as a Photron .mraw recording give exactly the results of the same frames as PNG files, with the
// frame rate taken from the file (the scene needs no inputs.fps), whether the frames are timed by
// the DAQ's exposure channel or by the camera's own time stamps; an inputs.fps that disagrees with
// the file is refused naming both. The same frames as a time-stamped Phantom .cine give the same
// results, timed by the file's stamps.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <opencv2/core.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../io/cine_test_writer.h"
#include "../io/mraw_test_writer.h"
#include "../io/test_dir.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/image_io.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/kinematics/kinematics_results.h"
#include "impactdic/sensor/sensor.h"
#include "small_scene_spec.h"

namespace impactdic {
namespace {

namespace L = results_layout;

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The synthesised scene once for every case (one synth per test program).
class CameraFileRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TestDir("CameraFileRun");
    // 2000 fps, not the default inputs.fps (1600): the file's rate must be the one used.
    const std::string spec =
        std::regex_replace(std::string(kSmallSceneSpec), std::regex("mm_per_px: 1.5\\}"),
                           "mm_per_px: 1.5, fps: 2000}");
    ASSERT_NE(spec.find("fps: 2000"), std::string::npos) << spec;
    const CliResult synth =
        RunCli("-q synth " + dir_->Write("spec.yaml", spec) + " -o " + dir_->File("scene"));
    ASSERT_EQ(synth.exit_code, 0) << synth.output;
    // The PNG frames as one 8-bit .mraw recording at the scene's frame rate.
    std::vector<cv::Mat> frames;
    for (const std::string& f : ListFrameSequence(dir_->File("scene/frames/frame_*.png")))
      frames.push_back(ReadGreyImage(f));
    ASSERT_FALSE(frames.empty());
    ASSERT_EQ(frames[0].depth(), CV_8U);
    test::MrawWriteOptions o;
    o.color_bit = 8;
    o.fps = Fps();
    o.start_frame = -3;  // Frames before the trigger: negative camera numbers.
    cih_ = new std::string(test::WriteMraw(dir_->File("scene/rec"), frames, o));
    // The same frames as an 8-bit Phantom .cine (rows bottom-up, as cameras save them) with
    // TIME64 time stamps 1 / fps apart, frame 0 of the file at camera frame -3.
    test::SyntheticCine cine;
    cine.width = frames[0].cols;
    cine.height = frames[0].rows;
    cine.bi_height = frames[0].rows;
    cine.bit_count = 8;
    cine.real_bpp = 8;
    cine.first_image_no = -3;
    cine.frame_rate = static_cast<std::uint32_t>(Fps());
    for (std::size_t k = 0; k < frames.size(); ++k) {
      cv::Mat flipped;
      cv::flip(frames[k], flipped, 0);
      cine.images.emplace_back(flipped.datastart, flipped.dataend);
      cine.time_s.push_back((static_cast<double>(k) - 3) / Fps());
    }
    test::WriteCineFile(dir_->File("scene/rec.cine"), cine);
  }
  static void TearDownTestSuite() {
    delete cih_;
    delete dir_;
  }

  // The scene's inputs.fps (synth writes an integer rate).
  static double Fps() {
    std::smatch m;
    const std::string text = ReadText(dir_->File("scene/scene.yaml"));
    EXPECT_TRUE(std::regex_search(text, m, std::regex(R"(\n  fps: ([0-9.]+)\n)"))) << text;
    return m.empty() ? 0 : std::stod(m[1]);
  }

  // A copy of the scene beside the original (relative paths keep working) with its frames and
  // fps lines replaced, without figures and animation; returns its path.
  // `sensor_lines` replace the sensor section's exposure_column line.
  static std::string Scene(const std::string& name, const std::string& frames,
                           const std::string& fps_line, const std::string& sensor_lines = "") {
    std::string text = ReadText(dir_->File("scene/scene.yaml"));
    text = std::regex_replace(text, std::regex(R"(\n  frames: [^\n]*\n)"),
                              "\n  frames: \"" + frames + "\"\n");
    text = std::regex_replace(text, std::regex(R"(\n  fps: [^\n]*\n)"), "\n" + fps_line);
    text = std::regex_replace(text, std::regex(R"(\nname: [^\n]*\n)"), "\nname: " + name + "\n");
    if (!sensor_lines.empty()) {
      text = std::regex_replace(text, std::regex(R"(\n  exposure_column: [^\n]*\n)"),
                                "\n" + sensor_lines);
    }
    for (const std::string key : {"figures", "animation"}) {
      text = std::regex_replace(text, std::regex("\n  " + key + ": true\n"),
                                "\n  " + key + ": false\n");
    }
    const std::string path = dir_->File("scene/" + name + ".yaml");
    std::ofstream(path) << text;
    return path;
  }

  static CliResult Run(const std::string& scene, const std::string& out) {
    return RunCli("-q run " + scene + " -o " + dir_->File(out));
  }

  static std::vector<double> Dataset(const std::string& run, const std::string& name) {
    return H5Reader(dir_->File(run + "/results.h5")).ReadDouble(name);
  }

  // The sensor lines that time the frames without the exposure channel, from
  // sensor.frame_time_offset_s set to the first exposure edge: a PNG run (offset + k / fps) is
  // then the same experiment as one timed by the camera's stamps.
  static std::string NoExposureLines() {
    const CsvTable csv = ReadCsv(dir_->File("scene/sensor.csv"));
    const std::vector<double> edges =
        ExposureRisingEdges(csv.Column("time_s"), csv.Column("exposure"));
    EXPECT_FALSE(edges.empty());
    return fmt::format("  exposure_column: \"\"\n  frame_time_offset_s: {:.17g}\n",
                       edges.empty() ? 0.0 : edges.front());
  }

  // Dataset `name` of two runs' results.h5: equal element by element, NaN where NaN.
  static void ExpectSameDataset(const std::string& run_a, const std::string& run_b,
                                const std::string& name) {
    const std::vector<double> a = Dataset(run_a, name), b = Dataset(run_b, name);
    ASSERT_EQ(a.size(), b.size()) << name;
    for (std::size_t k = 0; k < a.size(); ++k) {
      if (std::isnan(a[k]) != std::isnan(b[k]) || (!std::isnan(a[k]) && a[k] != b[k]))
        ADD_FAILURE() << name << "[" << k << "]: " << a[k] << " vs " << b[k];
    }
  }

  static TestDir* dir_;
  static std::string* cih_;
};
TestDir* CameraFileRun::dir_ = nullptr;
std::string* CameraFileRun::cih_ = nullptr;

TEST_F(CameraFileRun, AMrawGivesThePngResultsWithTheFilesFrameRate) {
  const CliResult png =
      Run(Scene("png", "frames/frame_*.png", "  fps: " + std::to_string(Fps()) + "\n"), "png");
  ASSERT_EQ(png.exit_code, 0) << png.output;
  // No inputs.fps: the rate comes from the .cih.
  const CliResult mraw = Run(Scene("mraw", "rec.cih", ""), "mraw");
  ASSERT_EQ(mraw.exit_code, 0) << mraw.output;
  for (const char* name : {L::kDicU, L::kDicV, L::kVy, L::kTimeMs}) {
    ExpectSameDataset("png", "mraw", name);
  }
  EXPECT_EQ(ReadText(dir_->File("png/summary.json")).size(),
            ReadText(dir_->File("mraw/summary.json")).size());
}

TEST_F(CameraFileRun, CameraTimeStampsTimeTheFramesWithoutAnExposureChannel) {
  const std::string no_exposure = NoExposureLines();
  const CliResult png = Run(
      Scene("png_t", "frames/frame_*.png", "  fps: " + std::to_string(Fps()) + "\n", no_exposure),
      "png_t");
  ASSERT_EQ(png.exit_code, 0) << png.output;
  const CliResult mraw = Run(Scene("mraw_t", "rec.cih", "", no_exposure), "mraw_t");
  ASSERT_EQ(mraw.exit_code, 0) << mraw.output;
  const std::vector<double> t_png = Dataset("png_t", L::kTimeMs);
  const std::vector<double> t_mraw = Dataset("mraw_t", L::kTimeMs);
  ASSERT_EQ(t_png.size(), t_mraw.size());
  for (std::size_t k = 0; k < t_png.size(); ++k) EXPECT_NEAR(t_png[k], t_mraw[k], 1e-9) << k;
  const std::vector<double> v_png = Dataset("png_t", L::kVy);
  const std::vector<double> v_mraw = Dataset("mraw_t", L::kVy);
  ASSERT_EQ(v_png.size(), v_mraw.size());
  for (std::size_t k = 0; k < v_png.size(); ++k) {
    if (std::isnan(v_png[k])) {
      EXPECT_TRUE(std::isnan(v_mraw[k])) << k;
    } else {
      EXPECT_NEAR(v_png[k], v_mraw[k], 1e-9 * std::abs(v_png[k]) + 1e-12) << k;
    }
  }
}

TEST_F(CameraFileRun, ATimeStampedCineGivesThePngResults) {
  const std::string no_exposure = NoExposureLines();
  const CliResult png = Run(
      Scene("png_c", "frames/frame_*.png", "  fps: " + std::to_string(Fps()) + "\n", no_exposure),
      "png_c");
  ASSERT_EQ(png.exit_code, 0) << png.output;
  const CliResult cine = Run(Scene("cine", "rec.cine", "", no_exposure), "cine");
  ASSERT_EQ(cine.exit_code, 0) << cine.output;
  for (const char* name : {L::kDicU, L::kDicV}) {
    ExpectSameDataset("png_c", "cine", name);
  }
  const std::vector<double> t_png = Dataset("png_c", L::kTimeMs);
  const std::vector<double> t_cine = Dataset("cine", L::kTimeMs);
  ASSERT_EQ(t_png.size(), t_cine.size());
  for (std::size_t k = 0; k < t_png.size(); ++k) EXPECT_NEAR(t_png[k], t_cine[k], 1e-6) << k;
  // The camera's numbers of the analysed frames.
  const std::vector<double> numbers = Dataset("cine", L::kDicFrameNumber);
  ASSERT_FALSE(numbers.empty());
  EXPECT_EQ(numbers.front(), Dataset("cine", L::kTimeFrameIndex).front() - 3);
}

TEST_F(CameraFileRun, AnFpsThatDisagreesWithTheFileIsRefusedNamingBoth) {
  const CliResult r = Run(
      Scene("wrong_fps", "rec.cih", "  fps: " + std::to_string(1.05 * Fps()) + "\n"), "wrong_fps");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("inputs.fps"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("rec.mraw"), std::string::npos) << r.output;
  // A rate within 1 % of the file's is the same rate, rounded.
  const CliResult close = Run(
      Scene("close_fps", "rec.cih", "  fps: " + std::to_string(1.005 * Fps()) + "\n"), "close_fps");
  EXPECT_EQ(close.exit_code, 0) << close.output;
}

}  // namespace
}  // namespace impactdic
