// The animation: exactly one video frame per camera frame (counted by decoding the file), the
// H.264 -> MJPG fallback, PNG frames, and no file left behind on failure.
#include "impactdic/render/animation.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <limits>
#include <opencv2/videoio.hpp>

#include "impactdic/core/error.h"
#include "test_util.h"

namespace impactdic {
namespace {

using test::MakeSequence;
using test::ScratchDir;

// Small canvases keep the tests fast (no enlargement of the 320 px test frames).
AnimationOptions SmallOptions() {
  AnimationOptions o;
  o.overlay.min_width_px = 320;
  return o;
}

// Reads every frame with cv::VideoCapture::read and checks its size.
std::size_t ReadAllFrames(const std::string& path, cv::Size expected_size) {
  cv::VideoCapture cap(path);
  std::size_t n = 0;
  cv::Mat frame;
  while (cap.read(frame)) {
    EXPECT_EQ(frame.size(), expected_size) << "frame " << n;
    ++n;
  }
  return n;
}

TEST(Animation, OneVideoFramePerCameraFrame) {
  ScratchDir dir("anim");
  const auto seq = MakeSequence(12, 320, 240, 12);
  const AnimationSummary s = WriteVelocityAnimation(seq, dir / "velocity.mp4", SmallOptions());
  EXPECT_EQ(s.frames, 12u);
  EXPECT_EQ(s.frames_read_back, 12u);
  ASSERT_TRUE(std::filesystem::exists(s.path)) << s.path;
  // H.264 MP4 where the encoder exists, else MJPG AVI; the extension matches the codec.
  if (s.codec == "H.264") {
    EXPECT_EQ(std::filesystem::path(s.path).extension(), ".mp4");
    EXPECT_FALSE(s.fell_back);
  } else {
    EXPECT_EQ(s.codec, "MJPG");
    EXPECT_EQ(std::filesystem::path(s.path).extension(), ".avi");
    EXPECT_TRUE(s.fell_back);
    EXPECT_FALSE(s.fallback_reason.empty());
  }
  EXPECT_EQ(ReadAllFrames(s.path, s.size), 12u);
  EXPECT_EQ(CountVideoFrames(s.path), 12u);
  EXPECT_EQ(dir.Entries().size(), 1u);  // no temporary file left
  EXPECT_NE(s.BriefReport().find("12 frames"), std::string::npos) << s.BriefReport();
}

TEST(Animation, FallsBackToMjpgWhenH264DoesNotWork) {
  ScratchDir dir("anim");
  const auto seq = MakeSequence(12, 320, 240, 12);
  AnimationOptions o = SmallOptions();
  o.h264_fourccs = {"ZZZZ"};  // no such encoder: the writer does not open
  const AnimationSummary s = WriteVelocityAnimation(seq, dir / "velocity.mp4", o);
  EXPECT_TRUE(s.fell_back);
  EXPECT_NE(s.fallback_reason.find("ZZZZ"), std::string::npos) << s.fallback_reason;
  EXPECT_EQ(s.codec, "MJPG");
  EXPECT_EQ(s.path, dir / "velocity.avi");
  EXPECT_EQ(ReadAllFrames(s.path, s.size), 12u);
  EXPECT_FALSE(std::filesystem::exists(dir / "velocity.mp4"));
  EXPECT_NE(s.BriefReport().find("fell back to MJPG"), std::string::npos);
}

TEST(Animation, H264OnlyFailsCleanlyWithoutEncoder) {
  ScratchDir dir("anim");
  const auto seq = MakeSequence(3, 320, 240, 12);
  AnimationOptions o;
  o.codec = VideoCodec::kH264;
  o.h264_fourccs = {"ZZZZ"};
  EXPECT_THROW(WriteVelocityAnimation(seq, dir / "velocity.mp4", o), Error);
  EXPECT_TRUE(dir.Entries().empty());
}

TEST(Animation, MjpgAndPngFrames) {
  ScratchDir dir("anim");
  auto seq = MakeSequence(12, 320, 240, 12);
  // Extreme data in the middle of the sequence: all NaN in frame 5, all zero in frame 6.
  const std::size_t n = seq.num_subsets;
  for (std::size_t s = 0; s < n; ++s) {
    seq.vx_mm_s[5 * n + s] = std::numeric_limits<double>::quiet_NaN();
    seq.vx_mm_s[6 * n + s] = seq.vy_mm_s[6 * n + s] = 0.0;
  }
  AnimationOptions o = SmallOptions();
  o.codec = VideoCodec::kMjpg;
  o.png_frames_dir = dir / "frames";
  const AnimationSummary s = WriteVelocityAnimation(seq, dir / "velocity.mp4", o);
  EXPECT_EQ(s.path, dir / "velocity.avi");
  EXPECT_FALSE(s.fell_back);  // MJPG was asked for
  EXPECT_EQ(s.png_frames, 12u);
  EXPECT_EQ(ReadAllFrames(s.path, s.size), 12u);
  std::size_t pngs = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir / "frames")) {
    EXPECT_EQ(e.path().extension(), ".png");
    ++pngs;
  }
  EXPECT_EQ(pngs, 12u);
  EXPECT_TRUE(test::IsPngOfSize(dir / "frames/frame_00011.png", s.size.width, s.size.height));
}

TEST(Animation, UnwritableFolderIsAnIoError) {
  ScratchDir dir("anim");
  const auto seq = MakeSequence(2, 320, 240, 12);
  try {
    WriteVelocityAnimation(seq, dir / "missing/velocity.mp4");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kIo);
  }
  EXPECT_TRUE(dir.Entries().empty());
}

TEST(Animation, OptionsCheck) {
  AnimationOptions o;
  EXPECT_NO_THROW(o.Check());
  o.fps = 0;
  EXPECT_THROW(o.Check(), Error);
  o = {};
  o.h264_fourccs = {"toolong"};
  EXPECT_THROW(o.Check(), Error);
  EXPECT_EQ(VideoCodecFromString("mjpg"), VideoCodec::kMjpg);
  EXPECT_THROW(VideoCodecFromString("vp9"), Error);
}

}  // namespace
}  // namespace impactdic
