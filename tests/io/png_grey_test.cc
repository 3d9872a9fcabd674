// DecodeGreyPng: exact pixels for every PNG filter type, 8 and 16 bit, identical to cv::imdecode
// on our own hand-built files and on OpenCV's, and a refusal (false, image untouched) for every
// file it does not handle, so that OpenCV decodes those as before.
#include "impactdic/io/png_grey.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/io/image_io.h"
#include "test_dir.h"

namespace impactdic {
namespace {

void Put32(std::string* out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out->push_back(static_cast<char>(v >> shift & 255));
}

void Chunk(std::string* png, const char* type, const std::string& body, bool bad_crc = false) {
  Put32(png, static_cast<std::uint32_t>(body.size()));
  const std::string typed = std::string(type, 4) + body;
  png->append(typed);
  std::uint32_t crc = static_cast<std::uint32_t>(
      crc32(0L, reinterpret_cast<const Bytef*>(typed.data()), static_cast<uInt>(typed.size())));
  Put32(png, bad_crc ? crc ^ 1u : crc);
}

int PaethPredictor(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

// How to build a test PNG: filter type per row (row % 5 by default), the IDAT split into pieces of
// `idat_piece` bytes (0 = one chunk), and changes that our decoder must refuse.
struct PngRecipe {
  int depth = 8;
  int colour_type = 0;
  int interlace = 0;
  int filter_offset = 0;          // row y uses filter (y + filter_offset) % 5
  int bad_filter_row = -1;        // this row gets filter type 5
  std::size_t idat_piece = 0;     // split the zlib stream
  bool empty_idat_after = false;  // an extra, empty IDAT chunk after the data
  bool ancillary = false;         // tEXt and gAMA chunks before the data
  bool trns = false;              // a tRNS chunk
  bool plte = false;              // a PLTE chunk
  bool bad_crc = false;           // the (first) IDAT's CRC is wrong
  bool extra_row = false;         // the zlib stream holds one row too many
  bool no_iend = false;
};

// A greyscale PNG of `pixels` (row-major, width x height, values < 2^depth), filtered as told.
std::string MakePng(const std::vector<std::uint16_t>& pixels, int width, int height,
                    const PngRecipe& r) {
  const int bpp = r.depth / 8;
  const std::size_t row_bytes = static_cast<std::size_t>(width) * bpp;
  std::string raw;
  std::vector<unsigned char> prev(row_bytes, 0), line(row_bytes);
  const int rows = height + (r.extra_row ? 1 : 0);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < width; ++x) {
      const std::uint16_t v = pixels[static_cast<std::size_t>(std::min(y, height - 1)) * width + x];
      if (bpp == 1) {
        line[x] = static_cast<unsigned char>(v);
      } else {
        line[2 * x] = static_cast<unsigned char>(v >> 8);
        line[2 * x + 1] = static_cast<unsigned char>(v & 255);
      }
    }
    const int filter = y == r.bad_filter_row ? 5 : (y + r.filter_offset) % 5;
    raw.push_back(static_cast<char>(filter));
    for (std::size_t i = 0; i < row_bytes; ++i) {
      const int a = i >= static_cast<std::size_t>(bpp) ? line[i - bpp] : 0;
      const int b = y > 0 ? prev[i] : 0;
      const int c = (y > 0 && i >= static_cast<std::size_t>(bpp)) ? prev[i - bpp] : 0;
      int predicted = 0;
      if (filter == 1) predicted = a;
      if (filter == 2) predicted = b;
      if (filter == 3) predicted = (a + b) / 2;
      if (filter == 4) predicted = PaethPredictor(a, b, c);
      raw.push_back(static_cast<char>((line[i] - predicted) & 255));
    }
    prev = line;
  }
  uLongf packed_size = compressBound(static_cast<uLong>(raw.size()));
  std::string packed(packed_size, '\0');
  EXPECT_EQ(
      compress2(reinterpret_cast<Bytef*>(packed.data()), &packed_size,
                reinterpret_cast<const Bytef*>(raw.data()), static_cast<uLong>(raw.size()), 6),
      Z_OK);
  packed.resize(packed_size);

  std::string png = "\x89PNG\r\n\x1a\n";
  std::string ihdr;
  Put32(&ihdr, static_cast<std::uint32_t>(width));
  Put32(&ihdr, static_cast<std::uint32_t>(height));
  ihdr += {static_cast<char>(r.depth), static_cast<char>(r.colour_type), 0, 0,
           static_cast<char>(r.interlace)};
  Chunk(&png, "IHDR", ihdr);
  if (r.ancillary) {
    Chunk(&png, "gAMA", std::string("\0\0\xb1\x8f", 4));
    Chunk(&png, "tEXt", std::string("Comment\0test", 12));
  }
  if (r.plte) Chunk(&png, "PLTE", std::string("\0\0\0\xff\xff\xff", 6));
  if (r.trns) Chunk(&png, "tRNS", std::string("\0\0", 2));
  const std::size_t piece = r.idat_piece > 0 ? r.idat_piece : packed.size();
  for (std::size_t at = 0; at < packed.size(); at += piece)
    Chunk(&png, "IDAT", packed.substr(at, piece), r.bad_crc && at == 0);
  if (r.empty_idat_after) Chunk(&png, "IDAT", "");
  if (!r.no_iend) Chunk(&png, "IEND", "");
  return png;
}

std::vector<std::uint16_t> RandomPixels(int width, int height, int depth, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> value(0, (1 << depth) - 1);
  std::vector<std::uint16_t> pixels(static_cast<std::size_t>(width) * height);
  // Smooth ramps with noise, so that every filter has something to predict.
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int ramp = (x * 7 + y * 3) % (1 << depth);
      pixels[static_cast<std::size_t>(y) * width + x] =
          static_cast<std::uint16_t>(((x + y) % 3 == 0) ? value(rng) : ramp);
    }
  }
  return pixels;
}

cv::Mat ToMat(const std::vector<std::uint16_t>& pixels, int width, int height, int depth) {
  cv::Mat m(height, width, depth == 8 ? CV_8UC1 : CV_16UC1);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const std::uint16_t v = pixels[static_cast<std::size_t>(y) * width + x];
      if (depth == 8)
        m.at<unsigned char>(y, x) = static_cast<unsigned char>(v);
      else
        m.at<std::uint16_t>(y, x) = v;
    }
  }
  return m;
}

::testing::AssertionResult SameImage(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) {
    return ::testing::AssertionFailure()
           << a.cols << "x" << a.rows << " type " << a.type() << " vs " << b.cols << "x" << b.rows
           << " type " << b.type();
  }
  const double diff = cv::norm(a, b, cv::NORM_INF);
  if (diff != 0) return ::testing::AssertionFailure() << "max difference " << diff;
  return ::testing::AssertionSuccess();
}

cv::Mat OpenCvDecode(const std::string& png) {
  const cv::Mat buffer(1, static_cast<int>(png.size()), CV_8U, const_cast<char*>(png.data()));
  return cv::imdecode(buffer, cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
}

TEST(PngGrey, EveryFilterTypeGivesTheExactPixels) {
  for (int depth : {8, 16}) {
    for (int offset = 0; offset < 5; ++offset) {  // each filter on the first row too
      SCOPED_TRACE("depth " + std::to_string(depth) + ", filter offset " + std::to_string(offset));
      const int w = 37, h = 23;
      const auto pixels = RandomPixels(w, h, depth, 11u + offset);
      const std::string png = MakePng(pixels, w, h, {.depth = depth, .filter_offset = offset});
      cv::Mat ours;
      ASSERT_TRUE(DecodeGreyPng(png, &ours));
      EXPECT_TRUE(SameImage(ours, ToMat(pixels, w, h, depth)));
      EXPECT_TRUE(SameImage(ours, OpenCvDecode(png)));
    }
  }
}

TEST(PngGrey, OneByOnePixel) {
  for (int depth : {8, 16}) {
    const std::vector<std::uint16_t> pixel = {static_cast<std::uint16_t>(depth == 8 ? 200 : 51234)};
    cv::Mat ours;
    ASSERT_TRUE(DecodeGreyPng(MakePng(pixel, 1, 1, {.depth = depth}), &ours));
    EXPECT_TRUE(SameImage(ours, ToMat(pixel, 1, 1, depth)));
  }
}

TEST(PngGrey, SplitDataAndAncillaryChunks) {
  const int w = 64, h = 40;
  const auto pixels = RandomPixels(w, h, 16, 3);
  const std::string png = MakePng(
      pixels, w, h, {.depth = 16, .idat_piece = 7, .empty_idat_after = true, .ancillary = true});
  cv::Mat ours;
  ASSERT_TRUE(DecodeGreyPng(png, &ours));
  EXPECT_TRUE(SameImage(ours, ToMat(pixels, w, h, 16)));
  EXPECT_TRUE(SameImage(ours, OpenCvDecode(png)));
}

TEST(PngGrey, ZlibHeaderSplitOverDataChunksAndAWrongHeaderRefused) {
  // One byte per IDAT chunk: the zlib stream's 2-byte header straddles two chunks (the decoder
  // inflates the raw deflate data after it and checks the header itself).
  const int w = 37, h = 9;
  const auto pixels = RandomPixels(w, h, 8, 21);
  const std::string png = MakePng(pixels, w, h, {.idat_piece = 1});
  cv::Mat ours;
  ASSERT_TRUE(DecodeGreyPng(png, &ours));
  EXPECT_TRUE(SameImage(ours, ToMat(pixels, w, h, 8)));
  EXPECT_TRUE(SameImage(ours, OpenCvDecode(png)));
  // A preset dictionary flagged in the header (FDICT, with the check bits kept right): refused
  // when the CRCs are left to the caller too.
  std::string bad = MakePng(pixels, w, h, {});
  const std::size_t idat = bad.find("IDAT");
  ASSERT_NE(idat, std::string::npos);
  auto& flg = reinterpret_cast<unsigned char&>(bad[idat + 5]);
  const unsigned cmf = static_cast<unsigned char>(bad[idat + 4]);
  flg = static_cast<unsigned char>(0x20);
  flg = static_cast<unsigned char>(flg + (31 - (cmf * 256 + flg) % 31) % 31);
  cv::Mat image;
  EXPECT_FALSE(DecodeGreyPng(bad, &image, PngChunkCrcs::kCheckedByCaller));
  EXPECT_TRUE(image.empty());
}

TEST(PngGrey, FilesWrittenByOpenCvDecodeIdentically) {
  // libpng's adaptive filter choice, several zlib strategies and levels, 8 and 16 bit.
  cv::Mat noise8(97, 131, CV_8UC1), noise16(97, 131, CV_16UC1);
  cv::RNG rng(5);
  rng.fill(noise8, cv::RNG::UNIFORM, 0, 256);
  rng.fill(noise16, cv::RNG::UNIFORM, 0, 65536);
  cv::GaussianBlur(noise8, noise8, cv::Size(5, 5), 1.5);
  cv::GaussianBlur(noise16, noise16, cv::Size(5, 5), 1.5);
  for (const cv::Mat& image : {noise8, noise16}) {
    for (int strategy : {cv::IMWRITE_PNG_STRATEGY_DEFAULT, cv::IMWRITE_PNG_STRATEGY_FILTERED,
                         cv::IMWRITE_PNG_STRATEGY_HUFFMAN_ONLY, cv::IMWRITE_PNG_STRATEGY_RLE,
                         cv::IMWRITE_PNG_STRATEGY_FIXED}) {
      for (int level : {0, 1, 9}) {
        std::vector<uchar> bytes;
        ASSERT_TRUE(
            cv::imencode(".png", image, bytes,
                         {cv::IMWRITE_PNG_COMPRESSION, level, cv::IMWRITE_PNG_STRATEGY, strategy}));
        const std::string png(bytes.begin(), bytes.end());
        cv::Mat ours;
        ASSERT_TRUE(DecodeGreyPng(png, &ours)) << "strategy " << strategy << " level " << level;
        EXPECT_TRUE(SameImage(ours, image));
        EXPECT_TRUE(SameImage(ours, OpenCvDecode(png)));
      }
    }
  }
}

TEST(PngGrey, RefusesWhatItDoesNotHandleAndLeavesTheImageAlone) {
  const int w = 16, h = 8;
  const auto pixels = RandomPixels(w, h, 8, 9);
  const std::vector<std::pair<std::string, PngRecipe>> cases = {
      {"colour type 2 (RGB)", {.colour_type = 2}},
      {"colour type 3 (palette) with PLTE", {.colour_type = 3, .plte = true}},
      {"PLTE in a grey file", {.plte = true}},
      {"tRNS", {.trns = true}},
      {"interlaced", {.interlace = 1}},
      {"bit depth 4", {.depth = 4}},
      {"bad CRC", {.bad_crc = true}},
      {"filter type 5", {.bad_filter_row = 3}},
      {"more data than the image holds", {.extra_row = true}},
      {"no IEND", {.no_iend = true}},
  };
  for (const auto& [name, recipe] : cases) {
    // Bit depth 4 packs two pixels per byte; build it as 8-bit data and relabel the header.
    PngRecipe build = recipe;
    if (build.depth == 4) build.depth = 8;
    std::string png = MakePng(pixels, w, h, build);
    if (recipe.depth == 4) png[8 + 8 + 8] = 4;  // IHDR bit depth (the CRC no longer matches)
    cv::Mat image(2, 3, CV_8UC1, cv::Scalar(7));
    EXPECT_FALSE(DecodeGreyPng(png, &image)) << name;
    EXPECT_EQ(image.rows, 2) << name;
    EXPECT_EQ(image.at<unsigned char>(0, 0), 7) << name;
  }
  const std::string good = MakePng(pixels, w, h, {});
  cv::Mat image;
  EXPECT_FALSE(DecodeGreyPng(good.substr(0, good.size() - 20), &image)) << "truncated";
  EXPECT_FALSE(DecodeGreyPng("not a png at all, just some text of some length", &image));
  EXPECT_TRUE(image.empty());
}

TEST(PngGrey, ReadGreyImageReadsGreyAndColourPngsAsBefore) {
  // Through the library's reader: the grey file by our decoder, the colour one by OpenCV (the
  // plugin), both converted to grey exactly as cv::imread + cvtColor would.
  TestDir dir;
  cv::Mat grey(30, 40, CV_16UC1), colour(30, 40, CV_8UC3);
  cv::RNG rng(8);
  rng.fill(grey, cv::RNG::UNIFORM, 0, 4096);
  rng.fill(colour, cv::RNG::UNIFORM, 0, 256);
  ASSERT_TRUE(cv::imwrite(dir.File("grey.png"), grey));
  ASSERT_TRUE(cv::imwrite(dir.File("colour.png"), colour));
  int channels = 0;
  EXPECT_TRUE(SameImage(ReadGreyImage(dir.File("grey.png"), &channels), grey));
  EXPECT_EQ(channels, 1);
  cv::Mat expected;
  cv::cvtColor(colour, expected, cv::COLOR_BGR2GRAY);
  EXPECT_TRUE(SameImage(ReadGreyImage(dir.File("colour.png"), &channels), expected));
  EXPECT_EQ(channels, 3);
}

}  // namespace
}  // namespace impactdic
