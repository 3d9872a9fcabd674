// The correlation path stays light: `impactdic correlate` of greyscale PNGs
// must not load OpenCV's image codecs or video I/O (with them the dynamic loader maps ~250
// libraries, ~0.1-0.17 s per process), and of TIFFs only the image codecs (the images plugin),
// never the video I/O with FFmpeg and GStreamer. Checked on the real binary through the dynamic
// loader's own trace (LD_DEBUG=files), with a TIFF pair and a video as the positive controls (they
// must load the images or the video plugin, so the trace is known to work), and with each plugin
// made unavailable. Speed itself is measured in bench/startup_benchmark.py, not here.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <string>

#include "cli_runner.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

class Startup : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("impactdic_startup_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // A speckle pattern and a copy shifted by one pixel.
    cv::Mat noise(122, 161, CV_8UC1);
    cv::RNG rng(4);
    rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
    cv::GaussianBlur(noise, noise, cv::Size(0, 0), 1.5);
    cv::normalize(noise, noise, 20, 235, cv::NORM_MINMAX);
    for (const char* ext : {".png", ".tif"}) {
      ASSERT_TRUE(cv::imwrite(File(std::string("ref") + ext), noise(cv::Rect(0, 0, 160, 120))));
      ASSERT_TRUE(cv::imwrite(File(std::string("def") + ext), noise(cv::Rect(1, 1, 160, 120))));
    }
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string File(const std::string& name) const { return (dir_ / name).string(); }
  std::string Correlate(const std::string& ext) const {
    return "correlate --reference " + File("ref" + ext) + " --deformed " + File("def" + ext) +
           " --subset 21 --step 20 --threads 1 -o " + File("out" + ext + ".csv");
  }

  fs::path dir_;
};

// Runs the binary with one environment variable set (only for it, not for the shell).
CliResult RunWith(const std::string& variable, const std::string& arguments) {
  return RunCli(arguments, variable);
}

// The libraries whose loading the trace shows ("file=NAME [0];  needed by ..." or "dlopen").
bool Loads(const std::string& trace, const std::string& library) {
  return trace.find("file=" + library) != std::string::npos ||
         trace.find("/" + library) != std::string::npos;
}

TEST_F(Startup, CorrelatingGreyPngsLoadsNoImageCodecsOrVideo) {
  const CliResult r = RunWith("LD_DEBUG=files", "-q " + Correlate(".png"));
  ASSERT_EQ(r.exit_code, 0) << r.output.substr(0, 4000);
  // The trace works: the core library is listed.
  ASSERT_TRUE(Loads(r.output, "libopencv_core.so")) << r.output.substr(0, 2000);
  for (const char* heavy :
       {"libopencv_imgcodecs.so", "libopencv_videoio.so", "libopencv_highgui.so",
        "libimpactdic_opencv_codecs.so", "libgdal.so", "libavcodec.so", "libgstreamer-1.0.so"}) {
    EXPECT_FALSE(Loads(r.output, heavy)) << heavy << " is loaded by `impactdic correlate` of PNGs";
  }
}

TEST_F(Startup, VersionLoadsNoImageCodecsOrVideo) {
  const CliResult r = RunWith("LD_DEBUG=files", "version");
  ASSERT_EQ(r.exit_code, 0) << r.output.substr(0, 4000);
  ASSERT_TRUE(Loads(r.output, "libopencv_core.so")) << r.output.substr(0, 2000);
  EXPECT_FALSE(Loads(r.output, "libopencv_imgcodecs.so"));
  EXPECT_FALSE(Loads(r.output, "libopencv_videoio.so"));
}

TEST_F(Startup, ATiffPairLoadsTheImagesPluginButNoVideoAndGivesTheSameResult) {
  {
    const CliResult r = RunWith("LD_DEBUG=files", "-q " + Correlate(".tif"));
    ASSERT_EQ(r.exit_code, 0) << r.output.substr(0, 4000);
    EXPECT_TRUE(Loads(r.output, "libimpactdic_opencv_codecs.so")) << r.output.substr(0, 2000);
    EXPECT_TRUE(Loads(r.output, "libopencv_imgcodecs.so"));
    for (const char* video : {"libimpactdic_opencv_video.so", "libopencv_videoio.so",
                              "libavcodec.so", "libavformat.so", "libgstreamer-1.0.so"}) {
      EXPECT_FALSE(Loads(r.output, video)) << video << " is loaded to decode a TIFF";
    }
  }
  ASSERT_EQ(RunCli("-q " + Correlate(".png")).exit_code, 0);
  // Same pixels through either decoder: the same numbers.
  auto read = [](const std::string& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string png = read(File("out.png.csv")), tif = read(File("out.tif.csv"));
  EXPECT_FALSE(png.empty());
  EXPECT_EQ(png, tif);
}

TEST_F(Startup, WithoutThePluginPngsStillCorrelateAndTiffsSayWhatIsMissing) {
  const std::string missing = File("no_such_plugin.so");
  const std::string no_plugin = "IMPACTDIC_OPENCV_CODECS=" + missing;
  const CliResult png = RunWith(no_plugin, "-q " + Correlate(".png"));
  EXPECT_EQ(png.exit_code, 0) << png.output;
  const CliResult tif = RunWith(no_plugin, "-q " + Correlate(".tif"));
  EXPECT_EQ(tif.exit_code, 1) << tif.output;
  EXPECT_NE(tif.output.find("libimpactdic_opencv_codecs.so"), std::string::npos) << tif.output;
  EXPECT_NE(tif.output.find("IMPACTDIC_OPENCV_CODECS"), std::string::npos) << tif.output;
  EXPECT_NE(tif.output.find(missing), std::string::npos) << tif.output;
}

TEST_F(Startup, AVideoLoadsTheVideoPluginAndWithoutItSaysWhatIsMissing) {
  // Three frames, each shifted by one pixel; OpenCV's own MJPG writer (no FFmpeg needed here).
  const std::string video = File("clip.avi");
  {
    cv::Mat noise(130, 170, CV_8UC1);
    cv::RNG rng(5);
    rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
    cv::GaussianBlur(noise, noise, cv::Size(0, 0), 1.5);
    cv::VideoWriter writer(video, cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'),
                           25, cv::Size(160, 120), /*isColor=*/false);
    ASSERT_TRUE(writer.isOpened());
    for (int k = 0; k < 3; ++k) writer.write(noise(cv::Rect(k, k, 160, 120)).clone());
  }
  const std::string correlate =
      "-q correlate --frames " + video + " --subset 21 --step 20 --threads 1 -o " + File("v.csv");
  const CliResult r = RunWith("LD_DEBUG=files", correlate);
  ASSERT_EQ(r.exit_code, 0) << r.output.substr(0, 4000);
  EXPECT_TRUE(Loads(r.output, "libimpactdic_opencv_video.so")) << r.output.substr(0, 2000);
  EXPECT_TRUE(Loads(r.output, "libopencv_videoio.so"));

  const std::string missing = File("no_such_video_plugin.so");
  const CliResult without = RunWith("IMPACTDIC_OPENCV_VIDEO=" + missing, correlate);
  EXPECT_EQ(without.exit_code, 1) << without.output;
  EXPECT_NE(without.output.find("libimpactdic_opencv_video.so"), std::string::npos)
      << without.output;
  EXPECT_NE(without.output.find("IMPACTDIC_OPENCV_VIDEO"), std::string::npos) << without.output;
  EXPECT_NE(without.output.find(missing), std::string::npos) << without.output;
  // Images need only the images plugin.
  EXPECT_EQ(RunWith("IMPACTDIC_OPENCV_VIDEO=" + missing, "-q " + Correlate(".tif")).exit_code, 0);
}

}  // namespace
}  // namespace impactdic
