#include "impactdic/io/image_io.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "impactdic/core/error.h"
#include "test_dir.h"

namespace impactdic {
namespace {

TEST(ImageIo, Reads8And16BitAndListsFramesSorted) {
  TestDir dir;
  cv::Mat a(20, 30, CV_8U, cv::Scalar(7));
  cv::Mat b(20, 30, CV_16U, cv::Scalar(4000));
  WriteImage(dir.File("f_002.png"), a);
  WriteImage(dir.File("f_001.png"), a);
  WriteImage(dir.File("g.tif"), b);
  EXPECT_EQ(ReadGreyImage(dir.File("f_001.png")).at<uchar>(3, 4), 7);
  const cv::Mat c = ReadGreyImage(dir.File("g.tif"));
  EXPECT_EQ(c.depth(), CV_16U);
  EXPECT_EQ(c.at<std::uint16_t>(1, 1), 4000);
  const auto glob = ListFrames(dir.File("f_*.png"));
  ASSERT_EQ(glob.size(), 2u);
  EXPECT_NE(glob[0].find("f_001"), std::string::npos);
  EXPECT_EQ(ListFrames(dir.path().string()).size(), 3u);
}

TEST(ImageIo, FramesSortNaturallyAndGapsInTheNumberingAreNamed) {
  TestDir dir;
  const cv::Mat a(8, 8, CV_8U, cv::Scalar(1));
  for (const char* name : {"f_10.png", "f_9.png", "f_8.png", "f_100.png"})
    WriteImage(dir.File(name), a);
  const auto files = ListFrames(dir.File("f_*.png"));
  ASSERT_EQ(files.size(), 4u);
  EXPECT_NE(files[0].find("f_8.png"), std::string::npos);
  EXPECT_NE(files[1].find("f_9.png"), std::string::npos);
  EXPECT_NE(files[2].find("f_10.png"), std::string::npos);
  EXPECT_NE(files[3].find("f_100.png"), std::string::npos);
  // f_8, 9, 10, 100: a gap of 89 frames after f_10.
  try {
    CheckFrameNumbering(files);
    FAIL() << "expected a numbering gap";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("f_100.png"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("89 frame(s) missing"), std::string::npos) << e.what();
  }
  try {
    CheckFrameNumbering({"d/frame_0001.png", "d/frame_0002.png", "d/frame_0004.png"});
    FAIL() << "expected a numbering gap";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("frame_0002.png to frame_0004.png"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("1 frame(s) missing"), std::string::npos);
  }
  // The gap is blamed where it is, also when it comes first.
  try {
    CheckFrameNumbering({"f_1.png", "f_3.png", "f_4.png", "f_5.png", "f_6.png"});
    FAIL() << "expected a numbering gap";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("f_1.png to f_3.png (1 frame(s) missing)"),
              std::string::npos)
        << e.what();
  }
  // Timestamps (more than 9 digits) are not frame counters: not checked.
  EXPECT_NO_THROW(
      CheckFrameNumbering({"t_1700000000001.png", "t_1700000000003.png", "t_1700000000006.png"}));
  // A constant step, names that are not one numbered series, or too few names: no error.
  EXPECT_NO_THROW(CheckFrameNumbering({"img_10.tif", "img_12.tif", "img_14.tif"}));
  EXPECT_NO_THROW(CheckFrameNumbering({"a.png", "b.png", "c.png"}));
  EXPECT_NO_THROW(CheckFrameNumbering({"a1.png", "b5.png", "c9.png"}));
  EXPECT_NO_THROW(CheckFrameNumbering({"f_1.png", "f_7.png"}));
}

TEST(ImageIo, ClearErrorsForMissingCorruptAndMixedSizes) {
  TestDir dir;
  try {
    ReadGreyImage(dir.File("missing.png"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kFileNotFound);
    EXPECT_NE(std::string(e.what()).find("missing.png"), std::string::npos);
  }
  // A truncated PNG.
  WriteImage(dir.File("ok.png"), cv::Mat(40, 40, CV_8U, cv::Scalar(1)));
  std::ifstream in(dir.File("ok.png"), std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  dir.Write("trunc.png", bytes.substr(0, bytes.size() / 3));
  try {
    ReadGreyImage(dir.File("trunc.png"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kFileFormat);
    EXPECT_NE(std::string(e.what()).find("trunc.png"), std::string::npos);
  }
  EXPECT_THROW(ListFrames(dir.File("nothing_*.png")), Error);
  std::vector<cv::Mat> images = {cv::Mat(10, 10, CV_8U), cv::Mat(10, 12, CV_8U)};
  try {
    CheckSameSize(images, {"a.png", "b.png"});
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("b.png"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("12x10"), std::string::npos);
  }
}

}  // namespace
}  // namespace impactdic
