// Campaign resume and camera files: a test is resumed only when every byte its scene reads is
// unchanged, the companion of the camera file the scene names included (a Photron recording is
// its .cih/.cihx description and its .mraw; the scene names either). Driven through the library's
// RunCampaign on a tiny synthesised scene whose frames are written as a .mraw recording.
#include <gtest/gtest.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <regex>
#include <string>
#include <vector>

#include "../io/mraw_test_writer.h"
#include "../io/test_dir.h"
#include "fault_util.h"
#include "impactdic/io/image_io.h"
#include "impactdic/pipeline/campaign.h"
#include "impactdic/synth/impact_scene.h"

namespace impactdic {
namespace {
namespace fs = std::filesystem;

// A tiny synthesised scene (8 frames, 160 x 120 px) in dir/s whose frames are the Photron
// recording s/rec.mraw with its description s/rec.cih (or s/rec.cihx), 8-bit at the scene's
// rate; inputs.frames names `named` ("rec.cih", "rec.mraw", ...), the rate comes from the file,
// no figures or video. Returns the scene file.
std::string CameraScene(const TestDir& dir, bool cihx, const std::string& named) {
  const ImpactSceneSpec spec = ImpactScenePreset("tiny");
  const std::string scene = WriteImpactScene(ImpactScene(spec), dir.File("s")).scene_yaml;
  std::vector<cv::Mat> frames;
  for (const std::string& f : ListFrameSequence(dir.File("s/frames/frame_*.png")))
    frames.push_back(ReadGreyImage(f));
  EXPECT_EQ(frames.size(), 8u);
  test::MrawWriteOptions o;
  o.color_bit = 8;
  o.fps = spec.fps;
  o.cihx = cihx;
  test::WriteMraw(dir.File("s/rec"), frames, o);
  std::string text = ReadBytes(scene);
  text = std::regex_replace(text, std::regex(R"(\n  frames: [^\n]*\n)"),
                            "\n  frames: \"" + named + "\"\n");
  text = std::regex_replace(text, std::regex(R"(\n  fps: [^\n]*\n)"), "\n");
  for (const std::string key : {"figures", "animation"}) {
    text =
        std::regex_replace(text, std::regex("\n  " + key + ": true\n"), "\n  " + key + ": false\n");
  }
  EXPECT_NE(text.find("frames: \"" + named + "\""), std::string::npos) << text;
  WriteBytes(scene, text);
  return scene;
}

// One campaign of the scene into dir/out: its summary.
CampaignSummary Campaign(const TestDir& dir, const std::string& scene) {
  CampaignOptions o;
  o.output_folder = dir.File("out");
  o.figures = false;
  o.threads = 1;
  return RunCampaign({scene}, o);
}

// Runs the campaign and returns whether its one test was resumed; a test that ran must not fail.
bool Resumed(const TestDir& dir, const std::string& scene) {
  const CampaignSummary s = Campaign(dir, scene);
  EXPECT_EQ(s.rows.size(), 1u);
  EXPECT_EQ(s.failed, 0) << (s.rows.empty() ? "" : s.rows[0].error);
  return s.resumed == 1;
}

// Bytes of `path` with the one at its middle inverted: the same size, other content.
void FlipMiddleByte(const std::string& path) {
  std::string bytes = ReadBytes(path);
  ASSERT_FALSE(bytes.empty()) << path;
  bytes[bytes.size() / 2] = static_cast<char>(~bytes[bytes.size() / 2]);
  WriteBytes(path, bytes);
}

// `from` replaced by `to` in the file (once; it must be there).
void Replace(const std::string& path, const std::string& from, const std::string& to) {
  std::string text = ReadBytes(path);
  const std::size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << path;
  text.replace(at, from.size(), to);
  WriteBytes(path, text);
}

// Frames named by the .cih: only the .cih was hashed, so new pixels in the .mraw beside it kept
// the old results ("1 resumed").
TEST(CampaignResume, NewPixelsInTheMrawOfANamedCihRerunTheTest) {
  const TestDir dir;
  const std::string scene = CameraScene(dir, /*cihx=*/false, "rec.cih");
  ASSERT_FALSE(Resumed(dir, scene));
  EXPECT_TRUE(Resumed(dir, scene));
  // The same bytes, newer mtime: still complete.
  const std::string mraw = dir.File("s/rec.mraw");
  fs::last_write_time(mraw, fs::last_write_time(mraw) + std::chrono::hours(1));
  EXPECT_TRUE(Resumed(dir, scene));
  FlipMiddleByte(mraw);
  EXPECT_FALSE(Resumed(dir, scene));
  EXPECT_TRUE(Resumed(dir, scene));
}

// Frames named by the .mraw: a changed byte of its description (.cih or .cihx, even one the
// reader does not use) re-runs the test.
TEST(CampaignResume, AChangedDescriptionOfANamedMrawRerunsTheTest) {
  for (const bool cihx : {false, true}) {
    SCOPED_TRACE(cihx ? ".cihx" : ".cih");
    const TestDir dir(std::string("CampaignResumeDescription") + (cihx ? "X" : ""));
    const std::string scene = CameraScene(dir, cihx, "rec.mraw");
    ASSERT_FALSE(Resumed(dir, scene));
    EXPECT_TRUE(Resumed(dir, scene));
    if (cihx) {
      Replace(dir.File("s/rec.cihx"), "<date>2026/11/27</date>", "<date>2026/11/28</date>");
    } else {
      Replace(dir.File("s/rec.cih"), "Date : 2026/11/27", "Date : 2026/11/28");
    }
    EXPECT_FALSE(Resumed(dir, scene));
    EXPECT_TRUE(Resumed(dir, scene));
  }
}

// A companion that is gone: the test runs again and fails naming it (not resumed from the results
// of the recording that was there). Back in place, the results of those same bytes, which the
// failed run left in place, are resumed.
TEST(CampaignResume, AMissingCompanionRerunsTheTestWhichFails) {
  const TestDir dir;
  const std::string scene = CameraScene(dir, /*cihx=*/false, "rec.cih");
  ASSERT_FALSE(Resumed(dir, scene));
  const std::string mraw = dir.File("s/rec.mraw");
  fs::rename(mraw, dir.File("rec.mraw.away"));
  const CampaignSummary gone = Campaign(dir, scene);
  EXPECT_EQ(gone.resumed, 0);
  EXPECT_EQ(gone.failed, 1);
  ASSERT_EQ(gone.rows.size(), 1u);
  EXPECT_NE(gone.rows[0].error.find("no .mraw file"), std::string::npos) << gone.rows[0].error;
  fs::rename(dir.File("rec.mraw.away"), mraw);
  EXPECT_TRUE(Resumed(dir, scene));
}

}  // namespace
}  // namespace impactdic
