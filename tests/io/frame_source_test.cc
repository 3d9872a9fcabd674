// FrameSource: image files (numbered and not), a camera file (.mraw written from the published
// layout, the shared Phantom .cine samples), frames in memory: count, size, bits, names, frame
// numbers, time stamps, sequential and random reads, warnings, FrameIndexOf's errors.
#include "impactdic/io/frame_source.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "../core/expect_error.h"
#include "../core/shared_data.h"
#include "impactdic/io/camera_file.h"
#include "impactdic/io/image_io.h"
#include "mraw_test_writer.h"
#include "test_dir.h"

namespace impactdic {
namespace {

// Frame k of a tiny sequence: every pixel k + 10 * row.
cv::Mat Frame(int k, int type = CV_8U, int rows = 6, int cols = 8) {
  cv::Mat f(rows, cols, type);
  for (int r = 0; r < rows; ++r) f.row(r).setTo(k + 10 * r);
  return f;
}

bool Same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

TEST(FrameSource, NumberedImageSequenceIsNumberedByItsFileNames) {
  const TestDir dir;
  std::filesystem::create_directories(dir.path() / "frames");
  for (int n : {12, 13, 14})
    WriteImage(dir.File("frames/frame_00" + std::to_string(n) + ".png"), Frame(n));
  const auto source = OpenFrameSource(dir.File("frames"));
  ASSERT_EQ(source->frame_count(), 3);
  EXPECT_EQ(source->FrameNumber(0), 12);
  EXPECT_EQ(source->FrameNumber(2), 14);
  EXPECT_EQ(source->Name(1), dir.File("frames/frame_0013.png"));
  EXPECT_TRUE(std::isnan(source->TimeS(0)));
  EXPECT_EQ(source->fps(), 0);
  EXPECT_EQ(source->frame_size(), cv::Size(8, 6));
  EXPECT_EQ(source->data_bits(), 8);
  // Random access, then sequential.
  for (int i : {2, 0, 1, 2}) EXPECT_TRUE(Same(source->Read(i), Frame(12 + i))) << i;
  EXPECT_EQ(FrameIndexOf(*source, 13, "--first"), 1);
  ExpectErrorContaining([&] { FrameIndexOf(*source, 15, "--last"); }, "frames 12..14");
  EXPECT_TRUE(source->warnings().empty());
}

TEST(FrameSource, ListedImagesAreNumberedByIndexAndAColourImageIsWarnedOnce) {
  const TestDir dir;
  const std::string a = dir.File("ref.png"), b = dir.File("def.png");
  WriteImage(a, Frame(0));
  cv::Mat colour;
  cv::cvtColor(Frame(1), colour, cv::COLOR_GRAY2BGR);
  WriteImage(b, colour);
  const auto source = MakeImageFileSource({a, b});
  EXPECT_EQ(source->FrameNumber(1), 1);
  EXPECT_EQ(source->Name(0), a);
  source->Read(0);
  source->Read(1);
  source->Read(1);
  ASSERT_EQ(source->warnings().size(), 1u);
  EXPECT_NE(source->warnings()[0].find(b), std::string::npos) << source->warnings()[0];
  // A missing file is named before anything is decoded.
  ExpectErrorContaining([&] { MakeImageFileSource({a, dir.File("missing.png")}); }, "missing.png");
}

// A frame decoded ahead (on another thread) reads as one decoded on demand, with the colour
// warning in file order; a file that fails to decode is reported by the Read of that frame; a
// frame read ahead but never read is dropped.
TEST(FrameSource, ImageDecodedAheadReadsAsDecodedOnDemand) {
  const TestDir dir;
  const std::string a = dir.File("ref.png"), b = dir.File("def.png"), bad = dir.File("bad.png");
  WriteImage(a, Frame(0));
  cv::Mat colour;
  cv::cvtColor(Frame(1), colour, cv::COLOR_GRAY2BGR);
  WriteImage(b, colour);
  { std::ofstream(bad) << "not a png"; }
  const auto source = MakeImageFileSource({a, b, bad});
  source->ReadAhead(1);
  EXPECT_TRUE(Same(source->Read(0), Frame(0)));
  EXPECT_TRUE(source->warnings().empty());
  EXPECT_TRUE(Same(source->Read(1), Frame(1)));
  ASSERT_EQ(source->warnings().size(), 1u);
  EXPECT_NE(source->warnings()[0].find(b), std::string::npos) << source->warnings()[0];
  source->ReadAhead(2);
  ExpectErrorContaining([&] { source->Read(2); }, "bad.png");
  source->ReadAhead(0);  // Never read: the source still closes.
}

TEST(FrameSource, CameraFileHasFrameNumbersTimeStampsAndBits) {
  const TestDir dir;
  std::vector<cv::Mat> frames;
  frames.reserve(4);
  for (int k = 0; k < 4; ++k) frames.push_back(Frame(100 * k, CV_16U));
  test::MrawWriteOptions o;
  o.color_bit = 12;
  o.start_frame = -2;
  o.fps = 5000;
  const std::string cih = test::WriteMraw(dir.File("rec"), frames, o);
  const auto source = OpenFrameSource(cih);
  ASSERT_EQ(source->frame_count(), 4);
  EXPECT_EQ(source->FrameNumber(0), -2);
  EXPECT_EQ(source->FrameNumber(3), 1);
  EXPECT_EQ(source->data_bits(), 12);
  EXPECT_EQ(source->frame_size(), cv::Size(8, 6));
  EXPECT_DOUBLE_EQ(source->fps(), 5000);
  EXPECT_DOUBLE_EQ(source->TimeS(0), -2 / 5000.0);
  EXPECT_DOUBLE_EQ(source->TimeS(3), 1 / 5000.0);
  EXPECT_NE(source->Name(0).find("frame -2"), std::string::npos) << source->Name(0);
  for (int i : {3, 1, 0, 1, 2, 3}) EXPECT_TRUE(Same(source->Read(i), frames[i])) << i;
  EXPECT_EQ(FrameIndexOf(*source, -1, "--first"), 1);
  const std::string error = ErrorText([&] { FrameIndexOf(*source, 2, "--last"); });
  EXPECT_NE(error.find("--last"), std::string::npos) << error;
  EXPECT_NE(error.find("frames -2..1"), std::string::npos) << error;
}

// The files a source reads, the ones campaign resume hashes: a Photron recording is its
// description and its .mraw whichever of them is named (the reader's own companion lookup), a
// .cine is itself, an image sequence its images; a missing companion is the reader's error.
TEST(FrameSource, FilesAreEveryFileTheSourceReads) {
  const TestDir dir;
  const std::vector<cv::Mat> frames{Frame(0), Frame(1)};
  test::MrawWriteOptions o;
  o.color_bit = 8;
  const std::string cih = test::WriteMraw(dir.File("rec"), frames, o);
  const std::string mraw = dir.File("rec.mraw");
  const std::vector<std::string> parts{cih, mraw};
  EXPECT_EQ(FrameSourceFiles(cih), parts);
  EXPECT_EQ(FrameSourceFiles(mraw), parts);
  EXPECT_EQ(CameraFileParts(mraw), parts);
  // A .cihx is found before a .cih; the extension in upper case too.
  o.cihx = true;
  const std::string cihx = test::WriteMraw(dir.File("x"), frames, o);
  std::filesystem::rename(dir.File("x.mraw"), dir.File("x.MRAW"));
  EXPECT_EQ(FrameSourceFiles(cihx), (std::vector<std::string>{cihx, dir.File("x.MRAW")}));
  std::filesystem::copy_file(cih, dir.File("x.cih"));
  EXPECT_EQ(FrameSourceFiles(dir.File("x.MRAW")),
            (std::vector<std::string>{cihx, dir.File("x.MRAW")}));
  // A .cine alone, whether it exists or not (its reader names a missing one).
  EXPECT_EQ(FrameSourceFiles(dir.File("shot.cine")),
            std::vector<std::string>{dir.File("shot.cine")});
  // A missing companion: the reader's error, naming the file given.
  std::filesystem::remove(mraw);
  ExpectErrorContaining([&] { FrameSourceFiles(cih); }, "no .mraw file of the same name");
  ExpectErrorContaining([&] { OpenFrameSource(cih); }, "no .mraw file of the same name");
  ExpectErrorContaining([&] { CameraFileParts(dir.File("rec.png")); }, "a camera file");
  // Images: the sequence's files in order.
  std::filesystem::create_directories(dir.path() / "frames");
  for (int n : {1, 2}) WriteImage(dir.File("frames/f_" + std::to_string(n) + ".png"), Frame(n));
  EXPECT_EQ(FrameSourceFiles(dir.File("frames/f_*.png")),
            (std::vector<std::string>{dir.File("frames/f_1.png"), dir.File("frames/f_2.png")}));
}

TEST(FrameSource, PhantomSamplesOpenWithTheirCameraNumbering) {
  IMPACTDIC_SHARED_DATA_OR_SKIP(cine, "cine");
  const std::string path = (cine / "phantom_v1610.cine").string();
  const auto source = OpenFrameSource(path);
  const auto reader = OpenCameraFile(path);
  ASSERT_EQ(source->frame_count(), reader->info().frame_count);
  EXPECT_EQ(source->FrameNumber(0), -85);
  EXPECT_EQ(source->Name(1), path + " frame -84");
  EXPECT_DOUBLE_EQ(source->TimeS(2), reader->info().time_s[2]);
  EXPECT_TRUE(Same(source->Read(2), reader->ReadFrame(2)));
  ExpectErrorContaining([&] { OpenFrameSource((cine / "invalid_color.cine").string()); },
                        "invalid_color.cine");
}

TEST(FrameSource, FramesInMemoryAreNumberedFromZero) {
  const auto source = MakeMemoryFrameSource({Frame(0), Frame(1), Frame(2)}, {0.0, 0.5, 1.0}, 2);
  EXPECT_EQ(source->frame_count(), 3);
  EXPECT_EQ(source->FrameNumber(2), 2);
  EXPECT_EQ(source->Name(2), "frame 2");
  EXPECT_DOUBLE_EQ(source->TimeS(1), 0.5);
  EXPECT_DOUBLE_EQ(source->fps(), 2);
  EXPECT_TRUE(Same(source->Read(1), Frame(1)));
  EXPECT_TRUE(std::isnan(MakeMemoryFrameSource({Frame(0)})->TimeS(0)));
  ExpectErrorContaining([] { MakeMemoryFrameSource({Frame(0)}, {0.0, 1.0}); }, "time stamps");
}

}  // namespace
}  // namespace impactdic
