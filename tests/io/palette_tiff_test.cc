// Camera formats beyond plain grey images: palette (indexed colour) TIFFs and 12-bit data in
// 16-bit containers.
#include <gtest/gtest.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/io/image_io.h"
#include "test_dir.h"

namespace impactdic {
namespace {

// A minimal baseline TIFF 6.0 (little-endian, uncompressed, one strip) of 8-bit palette colour:
// PhotometricInterpretation 3 with a ColorMap of 256 red, then 256 green, then 256 blue 16-bit
// values. OpenCV writes no palette TIFFs, so the test writes its own.
void WritePaletteTiff(const std::string& path, const std::vector<std::uint8_t>& indices, int width,
                      int height, const std::array<std::uint16_t, 768>& colour_map) {
  std::string b = "II*";
  b.push_back('\0');
  auto put16 = [&b](std::uint32_t v) {
    b.push_back(static_cast<char>(v & 0xFF));
    b.push_back(static_cast<char>((v >> 8) & 0xFF));
  };
  auto put32 = [&](std::uint32_t v) {
    put16(v & 0xFFFF);
    put16(v >> 16);
  };
  constexpr std::uint32_t kEntries = 10, kIfd = 8;
  constexpr std::uint32_t kMapAt = kIfd + 2 + 12 * kEntries + 4;
  constexpr std::uint32_t kPixelsAt = kMapAt + 2 * 768;
  put32(kIfd);
  put16(kEntries);
  auto entry = [&](std::uint32_t tag, std::uint32_t type, std::uint32_t count,
                   std::uint32_t value) {
    put16(tag);
    put16(type);
    put32(count);
    put32(value);  // A SHORT value sits in the first two bytes (little-endian).
  };
  const auto w = static_cast<std::uint32_t>(width), h = static_cast<std::uint32_t>(height);
  entry(256, 3, 1, w);          // ImageWidth
  entry(257, 3, 1, h);          // ImageLength
  entry(258, 3, 1, 8);          // BitsPerSample
  entry(259, 3, 1, 1);          // Compression: none
  entry(262, 3, 1, 3);          // PhotometricInterpretation: palette colour
  entry(273, 4, 1, kPixelsAt);  // StripOffsets
  entry(277, 3, 1, 1);          // SamplesPerPixel
  entry(278, 3, 1, h);          // RowsPerStrip
  entry(279, 4, 1, w * h);      // StripByteCounts
  entry(320, 3, 768, kMapAt);   // ColorMap
  put32(0);                     // No further image file directory.
  for (std::uint16_t v : colour_map) put16(v);
  b.append(indices.begin(), indices.end());
  std::ofstream(path, std::ios::binary) << b;
}

constexpr int kWidth = 16, kHeight = 8;

std::vector<std::uint8_t> Indices() {
  std::vector<std::uint8_t> indices(kWidth * kHeight);
  for (std::size_t i = 0; i < indices.size(); ++i) indices[i] = static_cast<std::uint8_t>(2 * i);
  return indices;
}

TEST(PaletteTiff, GreyPaletteReadsAsItsGreyValuesAndAsAGreyscaleImage) {
  TestDir dir;
  // A grey palette that is not the identity: index i shows grey 255 - i (16-bit map entries).
  std::array<std::uint16_t, 768> map{};
  for (int i = 0; i < 256; ++i)
    map[i] = map[256 + i] = map[512 + i] = static_cast<std::uint16_t>((255 - i) * 257);
  const std::string path = dir.File("palette.tif");
  WritePaletteTiff(path, Indices(), kWidth, kHeight, map);
  int channels = 0;
  const cv::Mat image = ReadGreyImage(path, &channels);
  ASSERT_EQ(image.type(), CV_8UC1);
  ASSERT_EQ(image.size(), cv::Size(kWidth, kHeight));
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      ASSERT_EQ(image.at<std::uint8_t>(y, x), 255 - 2 * (y * kWidth + x)) << x << "," << y;
  EXPECT_EQ(channels, 1);  // A greyscale image, not a colour frame.
  // In a sequence of plain greyscale frames it raises no colour-layout warning.
  WriteImage(dir.File("grey.png"), image);
  int grey_channels = 0;
  ReadGreyImage(dir.File("grey.png"), &grey_channels);
  SequenceColourCheck check;
  EXPECT_EQ(check.Check(path, channels), "");
  EXPECT_EQ(check.Check(dir.File("grey.png"), grey_channels), "");
}

TEST(PaletteTiff, ColourPaletteIsConvertedLikeAColourFrame) {
  TestDir dir;
  // Index i shows red i, green 255 - i, blue 0: grey = 0.299 R + 0.587 G + 0.114 B.
  std::array<std::uint16_t, 768> map{};
  for (int i = 0; i < 256; ++i) {
    map[i] = static_cast<std::uint16_t>(i * 257);
    map[256 + i] = static_cast<std::uint16_t>((255 - i) * 257);
  }
  const std::string path = dir.File("colour.tif");
  WritePaletteTiff(path, Indices(), kWidth, kHeight, map);
  int channels = 0;
  const cv::Mat image = ReadGreyImage(path, &channels);
  ASSERT_EQ(image.type(), CV_8UC1);
  EXPECT_EQ(channels, 3);
  for (int k = 0; k < kWidth * kHeight; ++k) {
    const int i = 2 * k;
    const double grey = 0.299 * i + 0.587 * (255 - i);
    EXPECT_NEAR(image.at<std::uint8_t>(k / kWidth, k % kWidth), grey, 0.51) << "index " << i;
  }
}

TEST(DataBits, TellsTwelveBitDataInSixteenBitImages) {
  EXPECT_EQ(DataBits(cv::Mat(4, 4, CV_8U, cv::Scalar(255))), 8);
  cv::Mat twelve(4, 4, CV_16U, cv::Scalar(100));
  twelve.at<std::uint16_t>(2, 3) = 4095;
  EXPECT_EQ(DataBits(twelve), 12);
  twelve.at<std::uint16_t>(1, 1) = 4096;
  EXPECT_EQ(DataBits(twelve), 16);
  EXPECT_EQ(DataBits(cv::Mat(4, 4, CV_32F, cv::Scalar(1))), 0);
}

}  // namespace
}  // namespace impactdic
