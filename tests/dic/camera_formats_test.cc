// Camera formats: 12-bit data in 16-bit images correlate like the same speckle at 16 bits, and
// `impactdic correlate --frames VIDEO` correlates a video's frames as a sequence.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/csv.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

// The same speckle sequence (rigid translation) at 16 bits, full range.
std::vector<cv::Mat> SixteenBitSequence() {
  SpeckleOptions speckle;
  speckle.blob_radius_px = 2.0;
  SpecklePattern pattern(speckle, 140, 120);
  RenderOptions render;
  render.bits = 16;
  render.noise_sigma = 200;
  render.supersampling = 2;
  std::vector<cv::Mat> frames;
  for (int k = 0; k < 3; ++k) {
    render.noise_seed = static_cast<std::uint64_t>(k + 1);
    frames.push_back(RenderImage(pattern, 140, 120, Translation(0.35 * k, -0.2 * k), render));
  }
  return frames;
}

// 12-bit data in 16-bit images (values 0..4095), and the same data scaled to 16 bits (x 16).
void TwelveAndSixteen(std::vector<cv::Mat>* twelve, std::vector<cv::Mat>* sixteen) {
  for (const cv::Mat& f : SixteenBitSequence()) {
    cv::Mat t = f / 16;  // Rounded: 0..4096; a 12-bit camera's values stop at 4095.
    cv::min(t, 4095, t);
    twelve->push_back(t);
    sixteen->push_back(t * 16);
  }
}

TEST(TwelveBit, SameSpeckleAsTwelveAndSixteenBitGivesTheSameDisplacements) {
  std::vector<cv::Mat> twelve, sixteen;
  TwelveAndSixteen(&twelve, &sixteen);
  double max_value = 0;
  cv::minMaxLoc(twelve[0], nullptr, &max_value);
  ASSERT_LE(max_value, 4095);
  DicOptions options;
  options.grid.subset_size = 21;
  options.grid.step = 12;
  const DicResult a = CorrelateSequence(twelve, options);
  const DicResult b = CorrelateSequence(sixteen, options);
  EXPECT_EQ(a.summary.data_bits, 12);
  EXPECT_EQ(b.summary.data_bits, 16);
  EXPECT_NE(a.summary.FullReport().find("12-bit data in 16-bit images"), std::string::npos)
      << a.summary.FullReport();
  EXPECT_NE(a.summary.FullReport().find("saturation at grey level 4095"), std::string::npos);
  EXPECT_EQ(b.summary.BriefReport().find("12-bit"), std::string::npos);
  ASSERT_EQ(a.frames.size(), 2u);
  ASSERT_EQ(a.positions.size(), b.positions.size());
  // ZNSSD is invariant to the grey scale and the scale is a power of two (exact in floating
  // point): the same subsets pass and their displacements agree to rounding.
  for (std::size_t k = 0; k < a.frames.size(); ++k) {
    int converged = 0;
    for (std::size_t i = 0; i < a.positions.size(); ++i) {
      ASSERT_EQ(ToString(a.frames[k].status[i]), ToString(b.frames[k].status[i]))
          << "frame " << k << " subset " << i;
      if (a.frames[k].status[i] != SubsetStatus::kConverged) continue;
      ++converged;
      EXPECT_NEAR(a.frames[k].u_px[i], b.frames[k].u_px[i], 1e-6);
      EXPECT_NEAR(a.frames[k].v_px[i], b.frames[k].v_px[i], 1e-6);
      EXPECT_NEAR(a.frames[k].u_px[i], 0.35 * (k + 1), 0.05);
    }
    EXPECT_EQ(converged, static_cast<int>(a.positions.size())) << "frame " << k;
  }
}

TEST(TwelveBit, SubsetsSaturatedAtTheTwelveBitLimitAreFlagged) {
  std::vector<cv::Mat> twelve, sixteen;
  TwelveAndSixteen(&twelve, &sixteen);
  // Glare over the left half of every frame: values clip at 4095, the 12-bit saturation level.
  for (cv::Mat& f : twelve) {
    cv::Mat left = f(cv::Rect(0, 0, 70, 120));
    left += 2500;
    cv::min(left, 4095, left);
  }
  DicOptions options;
  options.grid.subset_size = 21;
  options.grid.step = 12;
  const DicResult r = CorrelateSequence(twelve, options);
  int saturated_left = 0, left = 0, converged_right = 0, right = 0;
  for (std::size_t i = 0; i < r.positions.size(); ++i) {
    const SubsetStatus s = r.frames[0].status[i];
    if (r.positions[i].x + 10 < 70) {
      ++left;
      saturated_left += s == SubsetStatus::kSaturated;
    } else if (r.positions[i].x - 10 >= 70) {
      ++right;
      converged_right += s == SubsetStatus::kConverged;
    }
  }
  ASSERT_GT(left, 0);
  ASSERT_GT(right, 0);
  EXPECT_EQ(saturated_left, left);
  EXPECT_EQ(converged_right, right);
}

// An 8-bit grey MJPG AVI of `frames` (FFmpeg, else OpenCV's own writer); false if this OpenCV
// cannot write one.
bool WriteVideo(const std::string& path, const std::vector<cv::Mat>& frames) {
  cv::VideoWriter writer;
  for (int backend : {cv::CAP_FFMPEG, cv::CAP_OPENCV_MJPEG}) {
    if (writer.open(path, backend, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25,
                    frames[0].size(), /*isColor=*/false))
      break;
  }
  if (!writer.isOpened()) return false;
  for (const cv::Mat& f : frames) writer.write(f);
  writer.release();
  return fs::file_size(path) > 0;
}

class CorrelateVideoCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::temp_directory_path() / ("impactdic_correlate_video_test_" + std::to_string(getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  // Frame k moves by (0.5 k, -0.25 k) px.
  static std::vector<cv::Mat> Frames(int count) {
    SpeckleOptions speckle;
    speckle.blob_radius_px = 2.5;
    SpecklePattern pattern(speckle, 128, 96);
    RenderOptions render;
    render.supersampling = 2;
    std::vector<cv::Mat> frames;
    for (int k = 0; k < count; ++k)
      frames.push_back(RenderImage(pattern, 128, 96, Translation(0.5 * k, -0.25 * k), render));
    return frames;
  }
  fs::path dir_;
};

TEST_F(CorrelateVideoCli, CorrelatesTheFramesOfAVideoNumberedFromZero) {
  const std::string video = Path("clip.avi"), out = Path("out.csv");
  ASSERT_TRUE(WriteVideo(video, Frames(4))) << "OpenCV cannot write an MJPG AVI";
  const CliResult r = RunCli("correlate --frames " + video + " --subset 21 --step 16 -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const CsvTable t = ReadCsv(out, {.allow_non_finite = true, .text_columns = {"status"}});
  const auto& frame = t.Column("frame");
  const auto& u = t.Column("u_px");
  const auto& v = t.Column("v_px");
  const auto& status = t.TextColumn("status");
  // Deformed frames 1, 2, 3 (the video's 0-based frame indices; frame 0 is the reference).
  std::vector<double> labels(frame);
  labels.erase(std::unique(labels.begin(), labels.end()), labels.end());
  EXPECT_EQ(labels, (std::vector<double>{1, 2, 3}));
  int converged = 0;
  for (std::size_t i = 0; i < t.rows(); ++i) {
    if (status[i] != "converged") continue;
    ++converged;
    // MJPG compression: a few hundredths of a pixel.
    EXPECT_NEAR(u[i], 0.5 * frame[i], 0.1) << "row " << i;
    EXPECT_NEAR(v[i], -0.25 * frame[i], 0.1) << "row " << i;
  }
  EXPECT_GT(converged, static_cast<int>(t.rows() * 9 / 10));
}

TEST_F(CorrelateVideoCli, TruncatedVideoIsCorrelatedUpToItsLastFrameWithAWarning) {
  const std::string video = Path("cut.avi"), out = Path("cut.csv");
  ASSERT_TRUE(WriteVideo(video, Frames(20))) << "OpenCV cannot write an MJPG AVI";
  std::string bytes;
  {
    std::ifstream in(video, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  std::ofstream(video, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() / 2);
  const CliResult r = RunCli("correlate --frames " + video + " --subset 21 --step 16 -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("but the container declares 20"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("truncated or damaged"), std::string::npos) << r.output;
  const CsvTable t = ReadCsv(out, {.allow_non_finite = true, .text_columns = {"status"}});
  const auto& frame = t.Column("frame");
  const double last = *std::max_element(frame.begin(), frame.end());
  EXPECT_GE(last, 1);
  EXPECT_LT(last, 19);
}

TEST_F(CorrelateVideoCli, AVideoOfOneFrameIsRefused) {
  const std::string video = Path("one.avi");
  ASSERT_TRUE(WriteVideo(video, Frames(1))) << "OpenCV cannot write an MJPG AVI";
  const CliResult r = RunCli("correlate --frames " + video + " -o " + Path("one.csv"));
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(video), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("at least two frames"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(Path("one.csv")));
}

}  // namespace
}  // namespace impactdic
