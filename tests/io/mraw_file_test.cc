#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/io/camera_file.h"
#include "mraw_test_writer.h"
#include "test_dir.h"

namespace impactdic {
namespace {

// Frames of `bits`-bit values: a gradient through the whole range, then seeded random values.
std::vector<cv::Mat> MakeFrames(int bits, int count, int width = 13, int height = 8) {
  const int type = bits == 8 ? CV_8UC1 : CV_16UC1;
  const double max_value = (1 << bits) - 1;
  std::vector<cv::Mat> frames;
  cv::Mat gradient(height, width, type);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      const double v = max_value * (r * width + c) / (width * height - 1);
      if (bits == 8) {
        gradient.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(v);
      } else {
        gradient.at<std::uint16_t>(r, c) = static_cast<std::uint16_t>(v);
      }
    }
  }
  frames.push_back(gradient);
  cv::RNG rng(/*state=*/20261127 + bits);
  for (int i = 1; i < count; ++i) {
    cv::Mat random(height, width, type);
    rng.fill(random, cv::RNG::UNIFORM, 0, max_value + 1);
    frames.push_back(random);
  }
  return frames;
}

bool SameFrame(const cv::Mat& a, const cv::Mat& b) {
  return a.type() == b.type() && a.size() == b.size() && cv::norm(a, b, cv::NORM_INF) == 0;
}

std::string ErrorOf(const std::string& path) {
  try {
    OpenMrawFile(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

void ExpectRoundTrip(bool cihx) {
  TestDir dir;
  for (const int bits : {8, 10, 12, 16}) {
    SCOPED_TRACE(bits);
    const std::vector<cv::Mat> frames = MakeFrames(bits, /*count=*/4);
    test::MrawWriteOptions options;
    options.color_bit = bits;
    options.cihx = cihx;
    options.fps = 20000;
    const std::string description =
        test::WriteMraw(dir.File("rec" + std::to_string(bits)), frames, options);
    auto reader = OpenMrawFile(description);
    const CameraFileInfo& info = reader->info();
    EXPECT_EQ(info.format, "Photron mraw");
    EXPECT_EQ(info.path, dir.File("rec" + std::to_string(bits) + ".mraw"));
    EXPECT_EQ(info.width_px, 13);
    EXPECT_EQ(info.height_px, 8);
    EXPECT_EQ(info.data_bits, bits);
    EXPECT_EQ(info.frame_count, 4);
    EXPECT_EQ(info.fps, 20000);
    ASSERT_EQ(info.time_s.size(), 4u);
    EXPECT_DOUBLE_EQ(info.time_s[3], 3.0 / 20000);
    // Frames in any order: each read seeks to its own offset.
    for (const long long i : {3, 0, 2, 1}) {
      EXPECT_TRUE(SameFrame(reader->ReadFrame(i), frames[static_cast<size_t>(i)])) << i;
    }
  }
}

TEST(MrawFile, RoundTripsEveryBitDepthFromCih) { ExpectRoundTrip(/*cihx=*/false); }

TEST(MrawFile, RoundTripsEveryBitDepthFromCihxAfterBinaryPreamble) {
  ExpectRoundTrip(/*cihx=*/true);
}

TEST(MrawFile, OpensFromTheMrawOrTheDescriptionAndThroughDispatch) {
  TestDir dir;
  const std::vector<cv::Mat> frames = MakeFrames(/*bits=*/12, /*count=*/2);
  test::MrawWriteOptions options;
  test::WriteMraw(dir.File("shot"), frames, options);
  for (const std::string& path : {dir.File("shot.mraw"), dir.File("shot.cih")}) {
    ASSERT_TRUE(IsCameraFile(path));
    auto reader = OpenCameraFile(path);
    EXPECT_EQ(reader->info().path, dir.File("shot.mraw"));
    EXPECT_TRUE(SameFrame(reader->ReadFrame(1), frames[1]));
  }
}

TEST(MrawFile, FindsAPartnerWithAnUpperCaseExtension) {
  TestDir dir;
  const std::vector<cv::Mat> frames = MakeFrames(/*bits=*/10, /*count=*/2);
  test::MrawWriteOptions options;
  options.color_bit = 10;
  test::WriteMraw(dir.File("up"), frames, options);
  std::filesystem::rename(dir.File("up.mraw"), dir.File("up.MRAW"));
  auto reader = OpenMrawFile(dir.File("up.cih"));
  EXPECT_EQ(reader->info().path, dir.File("up.MRAW"));
  EXPECT_TRUE(SameFrame(reader->ReadFrame(1), frames[1]));
}

// Offsets past 4 GiB: a sparse 4.3 GB file of 257 frames of 4096 x 4096 8-bit pixels, the last
// one written (it starts at 4 GiB).
TEST(MrawFile, ReadsFramesBeyondFourGibibytes) {
  TestDir dir;
  constexpr long long kFrameBytes = 4096LL * 4096;
  constexpr long long kFrames = 257;
  dir.Write("big.cih",
            "Record Rate(fps) : 1000\nTotal Frame : 257\nStart Frame : -100\n"
            "Image Width : 4096\nImage Height : 4096\nColor Type : Mono\nColor Bit : 8\n");
  cv::Mat last(4096, 4096, CV_8UC1);
  cv::RNG(/*state=*/7).fill(last, cv::RNG::UNIFORM, 0, 256);
  {
    std::ofstream out(dir.File("big.mraw"), std::ios::binary);
    out.seekp(static_cast<std::streamoff>((kFrames - 1) * kFrameBytes));
    out.write(reinterpret_cast<const char*>(last.data), static_cast<std::streamsize>(kFrameBytes));
  }
  ASSERT_EQ(std::filesystem::file_size(dir.File("big.mraw")),
            static_cast<std::uintmax_t>(kFrames * kFrameBytes));
  auto reader = OpenMrawFile(dir.File("big.mraw"));
  EXPECT_TRUE(SameFrame(reader->ReadFrame(kFrames - 1), last));
  EXPECT_EQ(cv::countNonZero(reader->ReadFrame(128)), 0);
  EXPECT_DOUBLE_EQ(reader->info().time_s.back(), 0.156);
}

TEST(MrawFile, NegativeStartFrameGivesTimesBeforeTheTrigger) {
  TestDir dir;
  test::MrawWriteOptions options;
  options.color_bit = 8;
  options.fps = 1000;
  options.start_frame = -2;
  for (const bool cihx : {false, true}) {
    options.cihx = cihx;
    const std::string description =
        test::WriteMraw(dir.File(cihx ? "x" : "t"), MakeFrames(8, /*count=*/5), options);
    auto reader = OpenMrawFile(description);
    EXPECT_EQ(reader->info().first_frame_number, -2);
    const std::vector<double> expected = {-0.002, -0.001, 0, 0.001, 0.002};
    ASSERT_EQ(reader->info().time_s.size(), expected.size());
    for (size_t i = 0; i < expected.size(); ++i) {
      EXPECT_DOUBLE_EQ(reader->info().time_s[i], expected[i]) << i;
    }
  }
}

TEST(MrawFile, SaveStepSpacesTheTimes) {
  TestDir dir;
  test::MrawWriteOptions options;
  options.color_bit = 8;
  options.fps = 1000;
  options.start_frame = 10;
  options.save_step = 4;
  auto reader = OpenMrawFile(test::WriteMraw(dir.File("s"), MakeFrames(8, 3), options));
  EXPECT_EQ(reader->info().fps, 250);
  EXPECT_DOUBLE_EQ(reader->info().time_s[2], (10 + 2 * 4) / 1000.0);
}

TEST(MrawFile, EffectiveBitDepthInSixteenBitWords) {
  TestDir dir;
  const std::vector<cv::Mat> frames = MakeFrames(/*bits=*/12, /*count=*/2);
  test::MrawWriteOptions options;
  options.color_bit = 16;
  options.effective_bit = 12;
  auto lower = OpenMrawFile(test::WriteMraw(dir.File("lower"), frames, options));
  EXPECT_EQ(lower->info().data_bits, 12);
  EXPECT_TRUE(SameFrame(lower->ReadFrame(1), frames[1]));

  // "Higher": the 12 bits fill the top of the words; read back as 0 .. 4095.
  std::vector<cv::Mat> shifted;
  for (const cv::Mat& f : frames) shifted.push_back(f * 16);
  options.effective_side = "Higher";
  auto higher = OpenMrawFile(test::WriteMraw(dir.File("higher"), shifted, options));
  EXPECT_EQ(higher->info().data_bits, 12);
  EXPECT_TRUE(SameFrame(higher->ReadFrame(1), frames[1]));
}

TEST(MrawFile, RefusesColourRecordings) {
  TestDir dir;
  test::MrawWriteOptions options;
  options.color_bit = 8;
  options.color_type = "Color";
  std::string message = ErrorOf(test::WriteMraw(dir.File("c"), MakeFrames(8, 2), options));
  EXPECT_NE(message.find("c.cih"), std::string::npos) << message;
  EXPECT_NE(message.find("Color Type"), std::string::npos) << message;
  EXPECT_NE(message.find("monochrome"), std::string::npos) << message;

  options.cihx = true;
  message = ErrorOf(test::WriteMraw(dir.File("x"), MakeFrames(8, 2), options));
  EXPECT_NE(message.find("x.cihx"), std::string::npos) << message;
  EXPECT_NE(message.find("imageDataInfo/colorInfo/type"), std::string::npos) << message;
}

TEST(MrawFile, RefusesASizeMismatchNamingBothSizes) {
  TestDir dir;
  test::MrawWriteOptions options;
  options.color_bit = 12;  // 13 x 8 pixels: 156 bytes a frame.
  options.total_frame = 3;
  const std::string description = test::WriteMraw(dir.File("m"), MakeFrames(12, 2), options);
  const std::string message = ErrorOf(description);
  EXPECT_NE(message.find("m.mraw"), std::string::npos) << message;
  EXPECT_NE(message.find("312 bytes"), std::string::npos) << message;
  EXPECT_NE(message.find("468 bytes"), std::string::npos) << message;
}

TEST(MrawFile, RefusesATruncatedMraw) {
  TestDir dir;
  test::MrawWriteOptions options;
  const std::string description = test::WriteMraw(dir.File("t"), MakeFrames(12, 3), options);
  std::filesystem::resize_file(dir.File("t.mraw"), 3 * 156 - 7);
  EXPECT_NE(ErrorOf(description).find("461 bytes"), std::string::npos) << ErrorOf(description);
}

TEST(MrawFile, FileCutAfterOpeningFailsTheFrameRead) {
  TestDir dir;
  test::MrawWriteOptions options;
  auto reader = OpenMrawFile(test::WriteMraw(dir.File("t"), MakeFrames(12, 3), options));
  std::filesystem::resize_file(dir.File("t.mraw"), 2 * 156 + 10);
  EXPECT_NO_THROW(reader->ReadFrame(1));
  try {
    reader->ReadFrame(2);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("frame 2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("t.mraw"), std::string::npos) << e.what();
  }
}

TEST(MrawFile, RefusesFrameIndexOutOfRange) {
  TestDir dir;
  test::MrawWriteOptions options;
  auto reader = OpenMrawFile(test::WriteMraw(dir.File("r"), MakeFrames(12, 2), options));
  EXPECT_THROW(reader->ReadFrame(2), Error);
  EXPECT_THROW(reader->ReadFrame(-1), Error);
}

TEST(MrawFile, RefusesAMissingPartner) {
  TestDir dir;
  test::MrawWriteOptions options;
  test::WriteMraw(dir.File("p"), MakeFrames(8, 1), options);
  std::filesystem::remove(dir.File("p.cih"));
  std::string message = ErrorOf(dir.File("p.mraw"));
  EXPECT_NE(message.find(".cih"), std::string::npos) << message;
  EXPECT_NE(message.find("p.mraw"), std::string::npos) << message;

  test::WriteMraw(dir.File("q"), MakeFrames(8, 1), options);
  std::filesystem::remove(dir.File("q.mraw"));
  message = ErrorOf(dir.File("q.cih"));
  EXPECT_NE(message.find("no .mraw"), std::string::npos) << message;
  EXPECT_NE(ErrorOf(dir.File("none.mraw")).find("file not found"), std::string::npos);
}

TEST(MrawFile, RefusesMissingKeys) {
  TestDir dir;
  for (const std::string key : {"Image Width", "Image Height", "Total Frame", "Start Frame",
                                "Record Rate(fps)", "Color Bit"}) {
    test::MrawWriteOptions options;
    options.omit_keys = {key};
    const std::string message = ErrorOf(test::WriteMraw(dir.File("k"), MakeFrames(12, 1), options));
    EXPECT_NE(message.find(key), std::string::npos) << key << ": " << message;
    EXPECT_NE(message.find("k.cih"), std::string::npos) << message;
  }
}

TEST(MrawFile, RefusesUnknownBitDepthsAndBadValues) {
  TestDir dir;
  test::MrawWriteOptions options;
  options.color_bit = 14;
  std::string message = ErrorOf(test::WriteMraw(dir.File("b"), MakeFrames(8, 1), options));
  EXPECT_NE(message.find("Color Bit"), std::string::npos) << message;
  EXPECT_NE(message.find("14 bits"), std::string::npos) << message;

  options.color_bit = 12;
  options.fps = 0;
  message = ErrorOf(test::WriteMraw(dir.File("f"), MakeFrames(12, 1), options));
  EXPECT_NE(message.find("Record Rate(fps)"), std::string::npos) << message;

  // 13 x 7 pixels of 12 bits: 1092 bits, not whole bytes.
  options.fps = 1000;
  message = ErrorOf(test::WriteMraw(dir.File("o"), MakeFrames(12, 1, 13, 7), options));
  EXPECT_NE(message.find("not whole bytes"), std::string::npos) << message;

  // A width beyond any sensor is refused before anything is allocated.
  dir.Write("w.mraw", "");
  dir.Write("w.cih",
            "Record Rate(fps) : 1000\nTotal Frame : 2000000000\nStart Frame : 0\n"
            "Image Width : 99999999999\nImage Height : 1\nColor Type : Mono\nColor Bit : 8\n");
  message = ErrorOf(dir.File("w.cih"));
  EXPECT_NE(message.find("Image Width"), std::string::npos) << message;

  // Huge but valid-looking counts fail on the file size, not on an allocation.
  dir.Write("h.cih",
            "Record Rate(fps) : 1000\nTotal Frame : 2000000000\nStart Frame : 0\n"
            "Image Width : 65536\nImage Height : 65536\nColor Type : Mono\nColor Bit : 16\n");
  dir.Write("h.mraw", "");
  message = ErrorOf(dir.File("h.cih"));
  EXPECT_NE(message.find("0 bytes"), std::string::npos) << message;
}

TEST(MrawFile, RefusesACihxWithoutTheXml) {
  TestDir dir;
  dir.Write("x.mraw", "");
  dir.Write("x.cihx", "not xml at all");
  EXPECT_NE(ErrorOf(dir.File("x.cihx")).find("<cih>"), std::string::npos);
}

}  // namespace
}  // namespace impactdic
