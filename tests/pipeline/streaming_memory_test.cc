// Bounded memory: `impactdic run` streams the frames through reading,
// correlation and rendering, so its peak memory does not grow with the number of frames; only
// the DIC results (subsets x frames) do. One synthesised sequence (1024 x 768, 8-bit) is run
// twice as child processes, once over its first 8 frames (dic.last_frame) and once over all 32,
// and the children's peak resident set sizes (wait4's ru_maxrss) are compared: memory, never
// time, so the test does not depend on the load of the machine.
//
// The bound: 23 more frames of 1024 x 768 are 18 MB of 8-bit pixels; the longer run may use at
// most a third of that more (6 MB; half under AddressSanitizer, below): the results of 23 more
// frames of about 300 subsets, the few extra frames of the stored preview, allocator noise
// (measured: 0.8 MB). Keeping the frames, as
// `run` did before (the frames, their copy for results.h5 and the file image), grew by 64 MB and
// fails it (main at ecf0ddb: 110.6 -> 175.0 MB). The animation is off: the H.264 encoder holds
// its own lookahead of up to about 40 canvas frames (+80 MB at 1024 x 768 from 8 to 31 frames,
// the same with or without streaming), a bound of the encoder, not of the recording
// (docs/development.md, "Memory"); the snapshot still re-reads its frame.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "../cli/cli_runner.h"
#include "../cli/measured_child.h"
#include "../io/test_dir.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/pipeline/frame_stream.h"
#include "impactdic/render/animation.h"
#include "small_scene_spec.h"

namespace impactdic {
namespace {

namespace L = results_layout;

constexpr int kWidth = 1024, kHeight = 768, kFrames = 32, kShortLast = 8;

constexpr const char* kSpec = R"(
preset: small
name: streaming
camera: {lens: ideal, width: 1024, height: 768, mm_per_px: 0.5}
frames: {count: 32, before_impact: 2, supersampling: 1}
sensor: {tail_s: 0.05}
calibration: {render: false}
dic: {subset_size: 21, step: 40}
)";

// The scene written by synth with lines replaced (each `from` must occur).
std::string SceneVariant(const TestDir& dir, const std::string& name,
                         const std::vector<std::pair<std::string, std::string>>& replace) {
  std::ifstream in(dir.File("scene/scene.yaml"));
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  for (const auto& [from, to] : replace) {
    const std::size_t at = yaml.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) yaml.replace(at, from.size(), to);
  }
  return dir.Write("scene/" + name + ".yaml", yaml);
}

const std::pair<std::string, std::string> kShort = {
    "\ndic:\n", "\ndic:\n  last_frame: " + std::to_string(kShortLast) + "\n"};

class StreamingRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::make_unique<TestDir>("StreamingRun");
    const std::string spec = dir_->Write("spec.yaml", kSpec);
    synth_ = RunCli("synth " + spec + " -o " + dir_->File("scene"));
  }
  static void TearDownTestSuite() { dir_.reset(); }
  void SetUp() override { ASSERT_EQ(synth_.exit_code, 0) << synth_.output; }

  static std::unique_ptr<TestDir> dir_;
  static CliResult synth_;
};
std::unique_ptr<TestDir> StreamingRun::dir_;
CliResult StreamingRun::synth_;

TEST_F(StreamingRun, PeakMemoryDoesNotGrowWithTheNumberOfFrames) {
  const std::pair<std::string, std::string> no_animation = {"animation: true", "animation: false"};
  const std::string short_scene = SceneVariant(*dir_, "short", {kShort, no_animation});
  const std::string long_scene = SceneVariant(*dir_, "long", {no_animation});
  const MeasuredChild a = RunMeasured(
      {"-q", "run", short_scene, "-o", dir_->File("short"), "--threads", "2", "--allow-partial"});
  const MeasuredChild b = RunMeasured(
      {"-q", "run", long_scene, "-o", dir_->File("long"), "--threads", "2", "--allow-partial"});
  ASSERT_EQ(a.exit_code, 0);
  ASSERT_EQ(b.exit_code, 0);
  // Analysed: frames 1..kShortLast and 1..kFrames-1 (frame 0 is before the impact).
  const double extra_frames_mb = (kFrames - 1 - kShortLast) * double(kWidth) * kHeight / 1e6;
  const double growth_mb = (b.peak_rss_kb - a.peak_rss_kb) / 1e3;
  RecordProperty("peak_rss_short_kb", std::to_string(a.peak_rss_kb));
  RecordProperty("peak_rss_long_kb", std::to_string(b.peak_rss_kb));
  // Under AddressSanitizer (the asan preset, quarantine off) its allocator keeps more of the
  // per-frame working memory resident: 5.8-6.3 MB measured on 2026-11-27 for the same runs that
  // grow by 0.9 MB in the release build, at the edge of the release bound. There the bound is
  // half the pixels (9 MB), still far below keeping the frames (64 MB).
#if defined(__SANITIZE_ADDRESS__)
  constexpr double kBoundShare = 1.0 / 2;
#else
  constexpr double kBoundShare = 1.0 / 3;
#endif
  EXPECT_LT(growth_mb, extra_frames_mb * kBoundShare)
      << "peak RSS " << a.peak_rss_kb << " kB with dic.last_frame " << kShortLast << ", "
      << b.peak_rss_kb << " kB for all " << kFrames << " (" << extra_frames_mb
      << " MB of 8-bit pixels more)";
  // The snapshot was drawn over a frame re-read from the source.
  EXPECT_TRUE(std::filesystem::exists(dir_->File("long/velocity_field_te.png")));
}

// results.h5 is built in a temporary file beside it (io/hdf5_store.h, Backing::kFile), a few MB
// of it in memory at a time: with `outputs.frames: all` (the file grows by a compressed frame per
// frame) the peak does not grow with the file. Without figures and animation the commit is the
// run's peak. The bound: the 4 MB the writer may hold before it returns the pages it wrote, and
// 3 MB for the scatter of a single run's peak, which moves in steps of the 2 MB huge pages the
// large buffers are given (core/memory.h). Measured (1024 x 768, 8 -> 31 analysed frames): file
// +14.2 MB, peak +1.6 to +2.4 MB; 2026-12-07, 8 runs each: +0.3 to +4.6 MB (main at 0c678fe),
// -1.6 to +3.3 MB (main at 49c723c), once +6.2 MB in a CI run; with the file in memory (main at
// f14896c) +13.0 MB, and with its image copied on commit (main at 9f1eed4) +32.6 MB; both fail.
TEST_F(StreamingRun, PeakMemoryDoesNotHoldTheResultsFile) {
  const std::vector<std::pair<std::string, std::string>> all_frames = {
      {"figures: true", "figures: false"},
      {"animation: true", "animation: false"},
      {"png_frames: false", "png_frames: false\n  frames: all"}};
  auto with_short = all_frames;
  with_short.push_back(kShort);
  const std::string short_scene = SceneVariant(*dir_, "short_all", with_short);
  const std::string long_scene = SceneVariant(*dir_, "long_all", all_frames);
  const MeasuredChild a = RunMeasured({"-q", "run", short_scene, "-o", dir_->File("short_all"),
                                       "--threads", "2", "--allow-partial"});
  const MeasuredChild b = RunMeasured(
      {"-q", "run", long_scene, "-o", dir_->File("long_all"), "--threads", "2", "--allow-partial"});
  ASSERT_EQ(a.exit_code, 0);
  ASSERT_EQ(b.exit_code, 0);
  const double file_growth_mb =
      (static_cast<double>(std::filesystem::file_size(dir_->File("long_all/results.h5"))) -
       static_cast<double>(std::filesystem::file_size(dir_->File("short_all/results.h5")))) /
      1e6;
  const double growth_mb = (b.peak_rss_kb - a.peak_rss_kb) * 1024.0 / 1e6;
  RecordProperty("results_file_growth_mb", std::to_string(file_growth_mb));
  RecordProperty("peak_rss_growth_mb", std::to_string(growth_mb));
  ASSERT_GT(file_growth_mb, 5.0);  // The frames are in it: 23 more of about 0.6 MB each.
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "peak RSS is not asserted under AddressSanitizer (its allocator keeps freed "
                  "memory resident); the release build asserts it";
#else
  EXPECT_LT(growth_mb, 7.0) << "peak RSS " << a.peak_rss_kb << " kB with dic.last_frame "
                            << kShortLast << ", " << b.peak_rss_kb << " kB for all " << kFrames
                            << "; results.h5 grew by " << file_growth_mb << " MB";
#endif
}

TEST_F(StreamingRun, ResultsFileHoldsABoundedPreviewByDefault) {
  const std::string scene = SceneVariant(*dir_, "preview", {});
  const CliResult run =
      RunCli("-q run " + scene + " -o " + dir_->File("preview") + " --allow-partial --threads 2");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const H5Reader in(dir_->File("preview/results.h5"));
  Dims dims, time_dims;
  in.ReadDouble(L::kTimeMs, &time_dims);
  in.ReadInt(L::kFrameImages, &dims);
  const FramePreviewPlan plan =
      PlanFramePreview(static_cast<int>(time_dims[0]), cv::Size(kWidth, kHeight));
  ASSERT_EQ(dims.size(), 3u);
  EXPECT_LE(dims[0], static_cast<std::size_t>(kPreviewFrames));
  EXPECT_EQ(dims[0], plan.rows.size());
  // 1024 x 768 shrunk by 2 (the smallest factor to <= kPreviewLongSidePx = 640).
  EXPECT_EQ(dims[2], static_cast<std::size_t>(kWidth / 2));
  EXPECT_EQ(dims[1], static_cast<std::size_t>(kHeight / 2));
  const std::vector<double> rows = in.ReadDouble(L::kFrameRows);
  EXPECT_EQ(rows, std::vector<double>(plan.rows.begin(), plan.rows.end()));
  // `impactdic render` draws the snapshot and the animation from the preview alone.
  const CliResult render =
      RunCli("-q render " + dir_->File("preview/results.h5") + " -o " + dir_->File("rendered"));
  ASSERT_EQ(render.exit_code, 0) << render.output;
  EXPECT_TRUE(std::filesystem::exists(dir_->File("rendered/velocity_field_te.png")));
}

TEST_F(StreamingRun, OutputsFramesAllStoresEveryFrameAndNoneNone) {
  const std::string all = SceneVariant(
      *dir_, "all", {kShort, {"png_frames: false", "png_frames: false\n  frames: all"}});
  const std::string none = SceneVariant(
      *dir_, "none", {kShort, {"png_frames: false", "png_frames: false\n  frames: none"}});
  ASSERT_EQ(RunCli("-q run " + all + " -o " + dir_->File("all") + " --allow-partial").exit_code, 0);
  ASSERT_EQ(RunCli("-q run " + none + " -o " + dir_->File("none") + " --allow-partial").exit_code,
            0);
  const H5Reader with(dir_->File("all/results.h5"));
  Dims dims, time_dims;
  with.ReadDouble(L::kTimeMs, &time_dims);
  const std::vector<std::int32_t> pixels = with.ReadInt(L::kFrameImages, &dims);
  EXPECT_EQ(dims, (Dims{time_dims[0], static_cast<std::size_t>(kHeight),
                        static_cast<std::size_t>(kWidth)}));
  // The last stored frame is the last analysed one, as read from its file (ideal lens, no
  // filter: preprocessing leaves it as it is).
  const cv::Mat file = cv::imread(
      dir_->File("scene/frames/frame_" + std::string(4 - std::to_string(kShortLast).size(), '0') +
                 std::to_string(kShortLast) + ".png"),
      cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(file.empty());
  const std::size_t last_offset = (dims[0] - 1) * dims[1] * dims[2];
  long long differ = 0;
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      differ += pixels[last_offset + static_cast<std::size_t>(y) * kWidth + x] !=
                file.at<std::uint8_t>(y, x);
  EXPECT_EQ(differ, 0);
  const H5Reader without(dir_->File("none/results.h5"));
  EXPECT_FALSE(without.Exists(L::kFrameImages));
  EXPECT_TRUE(std::filesystem::exists(dir_->File("none/velocity_field_te.png")));
}

// A video source is streamed too: decoded once to count its frames, then frame by frame while
// correlating, and again (from its start) for the snapshot and the animation.
TEST_F(StreamingRun, RunStreamsTheFramesOfAVideo) {
  const std::string video = dir_->File("scene/clip.avi");
  {
    cv::VideoWriter writer(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25,
                           cv::Size(kWidth, kHeight), /*isColor=*/false);
    ASSERT_TRUE(writer.isOpened()) << "OpenCV cannot write an MJPG AVI";
    for (int k = 0; k < kFrames; ++k) {
      char name[32];
      std::snprintf(name, sizeof name, "frames/frame_%04d.png", k);
      writer.write(cv::imread(dir_->File("scene/") + name, cv::IMREAD_GRAYSCALE));
    }
  }
  const std::string scene =
      SceneVariant(*dir_, "video", {kShort, {"frames/frame_*.png", "clip.avi"}});
  const CliResult run =
      RunCli("-q run " + scene + " -o " + dir_->File("video") + " --allow-partial --threads 2");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const H5Reader in(dir_->File("video/results.h5"));
  Dims time_dims;
  in.ReadDouble(L::kTimeMs, &time_dims);
  const std::vector<double> frame_index = in.ReadDouble(L::kTimeFrameIndex);
  ASSERT_FALSE(frame_index.empty());
  EXPECT_EQ(frame_index.back(), kShortLast);
  std::string animation = dir_->File("video/velocity.mp4");
  if (!std::filesystem::exists(animation)) animation = dir_->File("video/velocity.avi");
  EXPECT_EQ(CountVideoFrames(animation), time_dims[0]);
  EXPECT_TRUE(std::filesystem::exists(dir_->File("video/velocity_field_te.png")));
}

// A long recording: 200 frames of 320 x 240 against 20 of the same sequence,
// 2736 subsets (dic.step 4), the animation off (its encoder's lookahead is bounded by the encoder,
// docs/development.md "Memory"). What grows with the frames is the results, held once: the
// correlation rows (40 bytes per subset and frame) and the kinematics (48), 88 bytes; results.h5
// is built on the disk, the kinematics borrow the rows instead of copying them, and the rows and
// kinematics are released once results.h5 is written, before rendering. The peak may grow by the
// results' own size: 43 MB here. Measured: +17.2 MB (81.9 -> 99.0 MB); main at f14896c (the file
// in memory, the kinematics' copy of the rows, the renderer's field beside them) +54.3 MB, and
// fails.
TEST(LongRun, PeakMemoryGrowsByNoMoreThanTheResults) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "peak RSS is not asserted under AddressSanitizer (its allocator keeps freed "
                  "memory resident); the release build asserts it";
#else
  TestDir dir("LongRun");
  SmallScene long_recording;
  long_recording.frames = 202;
  long_recording.supersampling = 1;
  long_recording.tail_s = 0.12;  // Past the 200 frames at the preset's rate.
  long_recording.subset_size = 15;
  long_recording.step = 4;
  const std::string spec = dir.Write("spec.yaml", SmallSceneSpec(long_recording));
  const CliResult synth = RunCli("-q synth " + spec + " -o " + dir.File("scene"));
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  const std::pair<std::string, std::string> no_animation = {"animation: true", "animation: false"};
  const std::string short_scene =
      SceneVariant(dir, "short", {{"\ndic:\n", "\ndic:\n  last_frame: 21\n"}, no_animation});
  const std::string long_scene = SceneVariant(dir, "long", {no_animation});
  const MeasuredChild a = RunMeasured(
      {"-q", "run", short_scene, "-o", dir.File("short"), "--threads", "2", "--allow-partial"});
  const MeasuredChild b = RunMeasured(
      {"-q", "run", long_scene, "-o", dir.File("long"), "--threads", "2", "--allow-partial"});
  ASSERT_EQ(a.exit_code, 0);
  ASSERT_EQ(b.exit_code, 0);
  // The results' own size [MB] from the rows x subsets of /dic.
  auto results_mb = [&](const std::string& run) {
    std::vector<std::size_t> dims;
    H5Reader(dir.File(run + "/results.h5")).ReadDouble("/dic/u_px", &dims);
    EXPECT_EQ(dims.size(), 2u);
    return dims.size() == 2 ? double(dims[0]) * double(dims[1]) * 88 / 1e6 : 0.0;
  };
  const double short_mb = results_mb("short"), long_mb = results_mb("long");
  ASSERT_GT(long_mb, 40.0) << "200 frames of 2736 subsets";
  const double growth_mb = (b.peak_rss_kb - a.peak_rss_kb) * 1024.0 / 1e6;
  RecordProperty("peak_rss_short_kb", std::to_string(a.peak_rss_kb));
  RecordProperty("peak_rss_long_kb", std::to_string(b.peak_rss_kb));
  EXPECT_LT(growth_mb, long_mb - short_mb)
      << "peak RSS " << a.peak_rss_kb << " kB over 20 frames, " << b.peak_rss_kb
      << " kB over 200; the results grew by " << long_mb - short_mb << " MB";
#endif
}

}  // namespace
}  // namespace impactdic
