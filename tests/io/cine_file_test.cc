// Phantom .cine reader: the sample files of DICe's component tests (../shared/data/cine, six
// camera versions, 8-bit, 12 bits in 16, 10-bit packed, one colour file), and small files written
// here from the published layout for what the samples lack (12-bit packed, top-down rows, no time
// stamp block) and for broken files (truncated, bad magic).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "../core/expect_error.h"
#include "../core/shared_data.h"
#include "cine_test_writer.h"
#include "impactdic/io/camera_file.h"
#include "test_dir.h"

namespace impactdic {
namespace {

struct SampleFacts {
  const char* name;
  long long first_frame_number;
  double fps;
  int data_bits;
  int depth;  // CV_8U or CV_16U.
};

// Facts read from each sample's headers; DICe's DICe_TestCine.cpp asserts 256 x 128 pixels and
// 6 frames for every one, hypercine's test_read16bpp.cpp the v7's 80 fps and first frame 238292,
// and DICe's file names the v1610's first frame -85.
const SampleFacts kSamples[] = {
    {"packed_12bpp", 60, 100, 10, CV_16U},  // 10-bit packed despite its name (biCompression 256).
    {"packed_raw_12bpp", 60, 100, 10, CV_16U},
    {"phantom_v12_raw_16bpp", 237684, 100, 12, CV_16U},
    {"phantom_v1610", -85, 100, 8, CV_8U},
    {"phantom_v1610_16bpp", -85, 100, 12, CV_16U},
    {"phantom_v1610_raw", -85, 100, 8, CV_8U},
    {"phantom_v1610_raw_16bpp", -85, 100, 12, CV_16U},
    {"phantom_v2511_raw_16bpp", 209, 100, 12, CV_16U},
    {"phantom_v611_raw_16bpp", 151325, 2000, 12, CV_16U},
    {"phantom_v7_raw_16bpp", 238292, 80, 12, CV_16U},
    {"phantom_v9_raw_16bpp", 237439, 300, 8, CV_8U},  // 8-bit despite its name.
};

std::string Sample(const std::filesystem::path& folder, const std::string& name) {
  return (folder / (name + ".cine")).string();
}

TEST(CineFile, ReadsEverySampleWithDicesDimensionsAndFrameCount) {
  IMPACTDIC_SHARED_DATA_OR_SKIP(cine, "cine");
  for (const SampleFacts& s : kSamples) {
    SCOPED_TRACE(s.name);
    auto reader = OpenCameraFile(Sample(cine, s.name));
    const CameraFileInfo& info = reader->info();
    EXPECT_EQ(info.format, "Phantom cine");
    EXPECT_EQ(info.width_px, 256);
    EXPECT_EQ(info.height_px, 128);
    EXPECT_EQ(info.frame_count, 6);
    EXPECT_EQ(info.first_frame_number, s.first_frame_number);
    EXPECT_DOUBLE_EQ(info.fps, s.fps);
    EXPECT_EQ(info.data_bits, s.data_bits);
    ASSERT_EQ(info.time_s.size(), 6U);
    for (long long i = 0; i < info.frame_count; ++i) {
      const cv::Mat frame = reader->ReadFrame(i);
      EXPECT_EQ(frame.rows, 128);
      EXPECT_EQ(frame.cols, 256);
      EXPECT_EQ(frame.depth(), s.depth);
      EXPECT_EQ(frame.channels(), 1);
      double max_value = 0;
      cv::minMaxLoc(frame, nullptr, &max_value);
      EXPECT_LT(max_value, std::ldexp(1.0, s.data_bits)) << "frame " << i;
      EXPECT_GT(max_value, 0) << "frame " << i;
    }
  }
}

// Pixel values pinned from an independent decoding of the files (a few lines of Python over the
// published layout): output (x, y) with y down, so the stored bottom-up rows are flipped.
TEST(CineFile, PixelValuesMatchAnIndependentDecoding) {
  IMPACTDIC_SHARED_DATA_OR_SKIP(cine, "cine");
  struct Pinned {
    const char* name;
    long long index;
    int at_0_0, at_10_20, at_255_127, at_128_64;
  };
  const Pinned pinned[] = {
      {"packed_12bpp", 0, 424, 419, 89, 341},
      {"packed_12bpp", 5, 368, 346, 420, 422},
      {"phantom_v1610", 0, 124, 123, 120, 103},
      {"phantom_v1610", 5, 123, 121, 113, 72},
      {"phantom_v1610_16bpp", 0, 1988, 1975, 1931, 1663},
      {"phantom_v1610_16bpp", 5, 1981, 1947, 1812, 1154},
      {"phantom_v7_raw_16bpp", 0, 1176, 1188, 967, 1126},
      {"phantom_v7_raw_16bpp", 5, 1240, 1174, 1031, 1236},
      {"phantom_v9_raw_16bpp", 0, 12, 9, 70, 31},
      {"phantom_v12_raw_16bpp", 5, 1346, 1272, 1158, 622},
  };
  for (const Pinned& p : pinned) {
    SCOPED_TRACE(std::string(p.name) + " frame " + std::to_string(p.index));
    cv::Mat frame = OpenCineFile(Sample(cine, p.name))->ReadFrame(p.index);
    frame.convertTo(frame, CV_32S);
    EXPECT_EQ(frame.at<int>(0, 0), p.at_0_0);
    EXPECT_EQ(frame.at<int>(20, 10), p.at_10_20);
    EXPECT_EQ(frame.at<int>(127, 255), p.at_255_127);
    EXPECT_EQ(frame.at<int>(64, 128), p.at_128_64);
  }
}

// The v1610 recording saved at 8 bits and at 12 bits (same trigger time): the 8-bit frame is the
// 12-bit one divided by 16, up to Phantom's black/white level mapping (8-bit levels 4 .. 254):
// a wrong row order or byte order in either path would break this.
TEST(CineFile, EightAndTwelveBitSavesOfOneRecordingAgree) {
  IMPACTDIC_SHARED_DATA_OR_SKIP(cine, "cine");
  auto r8 = OpenCineFile(Sample(cine, "phantom_v1610"));
  auto r16 = OpenCineFile(Sample(cine, "phantom_v1610_16bpp"));
  for (long long i = 0; i < 6; ++i) {
    cv::Mat a, b;
    r8->ReadFrame(i).convertTo(a, CV_64F);
    r16->ReadFrame(i).convertTo(b, CV_64F, 1.0 / 16.0);
    EXPECT_LT(cv::mean(cv::abs(a - b))[0], 2.0) << "frame " << i;
  }
  // Identical files under two names read identically.
  auto packed = OpenCineFile(Sample(cine, "packed_12bpp"));
  auto packed_raw = OpenCineFile(Sample(cine, "packed_raw_12bpp"));
  EXPECT_EQ(cv::norm(packed->ReadFrame(3), packed_raw->ReadFrame(3), cv::NORM_INF), 0);
}

// Time stamps from the TIME64 block (tag 1002) relative to TriggerTime: the v1610 file's first
// frame (camera frame -85 at 100 fps) was taken 0.8447 s before the trigger, the frames 10 ms
// apart; the v611's 0.5 ms apart (2000 fps).
TEST(CineFile, TimeStampsComeFromTheFile) {
  IMPACTDIC_SHARED_DATA_OR_SKIP(cine, "cine");
  const CameraFileInfo v1610 = OpenCineFile(Sample(cine, "phantom_v1610"))->info();
  EXPECT_NEAR(v1610.time_s[0], -0.8447011, 1e-6);
  for (std::size_t i = 1; i < 6; ++i)
    EXPECT_NEAR(v1610.time_s[i] - v1610.time_s[i - 1], 0.01, 1e-6);
  const CameraFileInfo v611 = OpenCineFile(Sample(cine, "phantom_v611_raw_16bpp"))->info();
  for (std::size_t i = 1; i < 6; ++i) EXPECT_NEAR(v611.time_s[i] - v611.time_s[i - 1], 5e-4, 1e-6);
}

TEST(CineFile, RefusesColourRecording) {
  IMPACTDIC_SHARED_DATA_OR_SKIP(cine, "cine");
  const std::string path = Sample(cine, "invalid_color");
  const std::string message = ErrorText([&] { OpenCineFile(path); });
  EXPECT_NE(message.find("colour recording"), std::string::npos) << message;
  EXPECT_NE(message.find("greyscale (monochrome)"), std::string::npos) << message;
  EXPECT_NE(message.find(path), std::string::npos) << message;
}

TEST(CineFile, RefusesFrameIndexOutOfRange) {
  IMPACTDIC_SHARED_DATA_OR_SKIP(cine, "cine");
  auto reader = OpenCineFile(Sample(cine, "phantom_v1610"));
  ExpectErrorContaining([&] { reader->ReadFrame(6); }, "camera frames -85 .. -80");
  ExpectErrorContaining([&] { reader->ReadFrame(-1); }, "frame index -1");
}

std::vector<char> ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void WriteAll(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

TEST(CineFile, RefusesTruncatedCopyNamingTheFrame) {
  IMPACTDIC_SHARED_DATA_OR_SKIP(cine, "cine");
  const TestDir dir;
  std::vector<char> bytes = ReadAll(Sample(cine, "phantom_v1610_16bpp"));
  bytes.resize(bytes.size() - 1000);  // Ends inside the last frame (index 5, camera frame -80).
  const std::string path = dir.File("cut.cine");
  WriteAll(path, bytes);
  const std::string message = ErrorText([&] { OpenCineFile(path); });
  EXPECT_NE(message.find("ends inside frame 5 (camera frame -80)"), std::string::npos) << message;
  EXPECT_NE(message.find("truncated"), std::string::npos) << message;
  EXPECT_NE(message.find(path), std::string::npos) << message;
  // Cut inside the headers.
  bytes.resize(200);
  WriteAll(path, bytes);
  ExpectErrorContaining([&] { OpenCineFile(path); }, "past the end of the 200-byte file");
  bytes.resize(10);
  WriteAll(path, bytes);
  ExpectErrorContaining([&] { OpenCineFile(path); }, "44-byte header");
}

TEST(CineFile, RefusesBadMagic) {
  IMPACTDIC_SHARED_DATA_OR_SKIP(cine, "cine");
  const TestDir dir;
  std::vector<char> bytes = ReadAll(Sample(cine, "phantom_v1610"));
  bytes[0] = 'X';
  const std::string path = dir.File("bad.cine");
  WriteAll(path, bytes);
  ExpectErrorContaining([&] { OpenCineFile(path); }, "starts with \"CI\"");
}

TEST(CineFile, MissingFileIsNamed) {
  ExpectErrorContaining([] { OpenCineFile("/nonexistent/x.cine"); }, "/nonexistent/x.cine");
}

TEST(CineFile, ReadsTwelveBitPackedAndTopDownRows) {
  const TestDir dir;
  // 12-bit packed, 4 x 3: values v = 100 * k + 7 for pixel k, two pixels in three bytes, most
  // significant bits first.
  test::SyntheticCine c;
  c.bit_count = 16;
  c.bi_compression = 1024;
  std::vector<std::uint8_t> packed;
  for (int k = 0; k < 12; k += 2) {
    const int a = 100 * k + 7, b = 100 * (k + 1) + 7;
    packed.push_back(static_cast<std::uint8_t>(a >> 4));
    packed.push_back(static_cast<std::uint8_t>(((a & 0xF) << 4) | (b >> 8)));
    packed.push_back(static_cast<std::uint8_t>(b & 0xFF));
  }
  c.images = {packed, packed};
  const std::string path = dir.File("p12.cine");
  WriteAll(path, test::WriteCine(c));
  auto reader = OpenCineFile(path);
  EXPECT_EQ(reader->info().data_bits, 12);
  EXPECT_EQ(reader->info().first_frame_number, -2);
  EXPECT_DOUBLE_EQ(reader->info().fps, 1000);
  // No time stamp block: (first_frame_number + index) / fps.
  EXPECT_DOUBLE_EQ(reader->info().time_s[1], -1e-3);
  const cv::Mat frame = reader->ReadFrame(1);
  ASSERT_EQ(frame.type(), CV_16UC1);
  for (int k = 0; k < 12; ++k) EXPECT_EQ(frame.at<std::uint16_t>(k / 4, k % 4), 100 * k + 7) << k;

  // 16-bit plain with negative biHeight: rows stored top-down, read as they are.
  test::SyntheticCine t;
  t.bi_height = -3;
  std::vector<std::uint8_t> plain;
  for (int k = 0; k < 12; ++k) {
    plain.push_back(static_cast<std::uint8_t>((1000 + k) & 0xFF));
    plain.push_back(static_cast<std::uint8_t>((1000 + k) >> 8));
  }
  t.images = {plain};
  WriteAll(path, test::WriteCine(t));
  const cv::Mat top_down = OpenCineFile(path)->ReadFrame(0);
  for (int k = 0; k < 12; ++k) EXPECT_EQ(top_down.at<std::uint16_t>(k / 4, k % 4), 1000 + k) << k;
  // The same data with positive biHeight: bottom-up, so the first stored row is the last.
  t.bi_height = 3;
  WriteAll(path, test::WriteCine(t));
  const cv::Mat bottom_up = OpenCineFile(path)->ReadFrame(0);
  EXPECT_EQ(bottom_up.at<std::uint16_t>(2, 0), 1000);
  EXPECT_EQ(bottom_up.at<std::uint16_t>(0, 0), 1008);
}

TEST(CineFile, RefusesCompressedImages) {
  const TestDir dir;
  test::SyntheticCine c;
  c.images = {std::vector<std::uint8_t>(24, 0)};
  std::vector<char> bytes = test::WriteCine(c);
  test::Put(bytes, 4, 1, 2);  // Compression = CC_JPEG.
  const std::string path = dir.File("jpeg.cine");
  WriteAll(path, bytes);
  ExpectErrorContaining([&] { OpenCineFile(path); }, "JPEG-compressed");
  c.bi_compression = 3;  // Not a known pixel format.
  WriteAll(path, test::WriteCine(c));
  ExpectErrorContaining([&] { OpenCineFile(path); }, "biCompression 3");
}

}  // namespace
}  // namespace impactdic
