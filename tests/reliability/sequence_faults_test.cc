// Fault injection: image sequences and videos that are incomplete or inconsistent. `run` and
// `correlate` read them through the same functions (io ListFrameSequence, ReadGreyImage with
// SequenceColourCheck, ReadVideoFrames) and so agree.
#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <set>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../io/test_dir.h"
#include "fault_util.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/image_io.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

TEST(SequenceFaults, CorrelateRejectsAGapInTheNumberingAsRunDoes) {
  TestDir dir;
  WriteFrames(dir, "frames", "frame_", 10, 5, /*skip=*/12);  // 10, 11, 13, 14
  const std::string expected_text = "frame_0011.png to frame_0013.png (1 frame(s) missing)";
  ExpectCliFailure(
      "correlate --frames " + Quoted(dir.File("frames/frame_*.png")) +
          " --subset 21 --step 20 -o " + dir.File("out.csv"),
      {dir.File("frames/frame_0013.png"), expected_text, "consecutively numbered frames"});
  EXPECT_FALSE(fs::exists(dir.File("out.csv")));
  const std::string scene =
      dir.Write("scene.yaml", "inputs: {frames: frames/frame_*.png, mm_per_px: 0.5}\n");
  ExpectCliFailure("run " + scene + " -o " + dir.File("out"), {expected_text});
}

TEST(SequenceFaults, CorrelateCsvFrameColumnIsTheFileNumber) {
  TestDir dir;
  WriteFrames(dir, "frames", "frame_", 10, 3);  // frame_0010 (reference), 0011, 0012
  const CliResult r = RunCli("correlate --frames " + Quoted(dir.File("frames/frame_*.png")) +
                             " --subset 21 --step 20 -o " + dir.File("out.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  CsvReadOptions read;
  read.text_columns = {"status"};
  const CsvTable table = ReadCsv(dir.File("out.csv"), read);
  const std::set<double> frames(table.Column("frame").begin(), table.Column("frame").end());
  // Was 1 and 2 (the position in the list).
  EXPECT_EQ(frames, (std::set<double>{11, 12}));
}

TEST(SequenceFaults, ColourFrameInAGreySequenceIsNamedInAWarning) {
  TestDir dir;
  WriteFrames(dir, "frames", "f_", 0, 4);
  cv::Mat colour;
  cv::cvtColor(ReadGreyImage(dir.File("frames/f_0002.png")), colour, cv::COLOR_GRAY2BGR);
  WriteImage(dir.File("frames/f_0002.png"), colour);
  const CliResult r = RunCli("correlate --frames " + Quoted(dir.File("frames/f_*.png")) +
                             " --subset 21 --step 20 -o " + dir.File("out.csv"));
  EXPECT_EQ(r.exit_code, 0) << r.output;  // Converted, as before, but no longer silently.
  const std::string warning = dir.File("frames/f_0002.png") +
                              " is a 3-channel colour image in a sequence whose first image " +
                              dir.File("frames/f_0000.png") + " is greyscale: converted to grey";
  EXPECT_NE(r.output.find(warning), std::string::npos) << r.output;
  // `run` says the same and keeps it in the summary's warnings (PipelineSummary::warnings).
  const std::string scene = dir.Write("scene.yaml",
                                      "inputs: {frames: frames/f_*.png, mm_per_px: 0.5}\n"
                                      "stages: [frames, correlate, kinematics, outputs]\n"
                                      "dic: {subset_size: 21, step: 20}\n"
                                      "outputs: {hdf5: false, figures: false, animation: false}\n");
  const CliResult run = RunCli("run " + scene + " -o " + dir.File("out"));
  EXPECT_EQ(run.exit_code, 0) << run.output;
  // Logged when read, and listed among the run's warnings in its report.
  EXPECT_NE(run.output.find("warning: frames: " + warning), std::string::npos) << run.output;
}

// An MJPG AVI of `count` frames written by OpenCV (FFmpeg, else its built-in writer); false if
// this OpenCV cannot write one.
bool WriteVideo(const std::string& path, int count) {
  cv::VideoWriter writer;
  for (int backend : {cv::CAP_FFMPEG, cv::CAP_OPENCV_MJPEG}) {
    if (writer.open(path, backend, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25,
                    cv::Size(96, 80), /*isColor=*/false))
      break;
  }
  if (!writer.isOpened()) return false;
  for (int k = 0; k < count; ++k) writer.write(Speckle(96, 80, k + 1));
  writer.release();
  return fs::file_size(path) > 0;
}

TEST(SequenceFaults, TruncatedVideoWarnsWithBothCounts) {
  TestDir dir;
  const std::string video = dir.File("clip.avi");
  ASSERT_TRUE(WriteVideo(video, 20)) << "OpenCV cannot write an MJPG AVI";
  std::string warning;
  ASSERT_EQ(ReadVideoFrames(video, 0, &warning).size(), 20u);
  EXPECT_EQ(warning, "");  // A complete video: no warning.
  const std::string bytes = ReadBytes(video);
  WriteBytes(video, bytes.substr(0, bytes.size() / 2));
  const std::size_t decoded = ReadVideoFrames(video, 0, &warning).size();
  ASSERT_GT(decoded, 0u);
  ASSERT_LT(decoded, 20u);
  EXPECT_NE(warning.find(video + ": decoded " + std::to_string(decoded) +
                         " frames but the container declares 20"),
            std::string::npos)
      << warning;
  EXPECT_NE(warning.find("truncated or damaged"), std::string::npos) << warning;
}

}  // namespace
}  // namespace impactdic
