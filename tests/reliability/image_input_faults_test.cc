// Frames, images and videos that are truncated, empty,
// corrupt or not regular files fail with one message of ours naming the file and what is wrong,
// and no line of libpng, libjpeg, OpenCV, FFmpeg or GStreamer reaches the terminal. The bad files
// are made here: a JPEG cut short, a PNG whose CRCs are right but whose rows are not, a folder, a
// symbolic link to nowhere and a FIFO among the frames, zero-byte files.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <zlib.h>

#include <cstdint>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "fault_util.h"
#include "impactdic/core/error.h"
#include "impactdic/io/image_io.h"
#include "impactdic/io/png_grey.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

// The lines of `output` that are not ours ("impactdic: error: ..."), e.g. "libpng error: ...",
// "Premature end of JPEG file", "[ WARN:0@0.1] ... GStreamer warning".
std::string ForeignLines(const std::string& output) {
  std::string foreign;
  std::size_t at = 0;
  while (at < output.size()) {
    std::size_t end = output.find('\n', at);
    if (end == std::string::npos) end = output.size();
    const std::string line = output.substr(at, end - at);
    if (!line.empty() && line.rfind("impactdic: error: ", 0) != 0) foreign += line + "\n";
    at = end + 1;
  }
  return foreign;
}

// `impactdic -q <arguments>` fails with exit 1, prints `parts`, and nothing else than its one
// error line.
void ExpectOnlyOurError(const std::string& arguments, std::initializer_list<std::string> parts) {
  const std::string output = ExpectCliFailure("-q " + arguments, parts);
  EXPECT_EQ(ForeignLines(output), "") << "impactdic -q " << arguments << ":\n" << output;
}

std::string ReadError(const std::string& path) {
  try {
    ReadGreyImage(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// Four frames f_0000.<ext> .. f_0003.<ext> of one speckle image in `folder`.
std::vector<std::string> WriteSequence(const TestDir& dir, const std::string& folder,
                                       const std::string& ext,
                                       const std::vector<int>& params = {}) {
  fs::create_directories(dir.path() / folder);
  std::vector<std::string> files;
  for (int k = 0; k < 4; ++k) {
    std::string name = folder;
    name += "/f_000" + std::to_string(k);
    name += ext;
    files.push_back(dir.File(name));
    WriteImage(files.back(), Speckle(96, 80, 3), params);
  }
  return files;
}

TEST(ImageInputFaults, TruncatedJpegInASequenceIsNamed) {
  TestDir dir;
  const std::vector<std::string> files = WriteSequence(dir, "seq", ".jpg");
  const std::string whole = ReadBytes(files[2]);
  WriteBytes(files[2], whole.substr(0, whole.size() / 2));
  // Before: exit 0, the lower half of frame 2 flat grey, and only libjpeg's "Premature end of
  // JPEG file" on stderr.
  ExpectOnlyOurError(
      "correlate --frames " + dir.File("seq") + " -o " + dir.File("out.csv"),
      {files[2],
       "a truncated JPEG: the file ends at byte " + std::to_string(whole.size() / 2) +
           ", inside the compressed image data of its scan 1",
       "end-of-image marker (FF D9)"});
  EXPECT_FALSE(fs::exists(dir.File("out.csv")));
}

TEST(ImageInputFaults, JpegCutAnywhereIsTruncatedAndTrailingCameraDataIsIgnored) {
  TestDir dir;
  const std::string image = dir.File("a.jpg");
  // Baseline, progressive (several scans) and with restart markers (FF D0..D7 inside the data).
  const std::vector<std::vector<int>> kinds = {
      {}, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}, {cv::IMWRITE_JPEG_RST_INTERVAL, 2}};
  for (const auto& params : kinds) {
    WriteImage(image, Speckle(96, 80, 5), params);
    const std::string whole = ReadBytes(image);
    const cv::Mat original = ReadGreyImage(image);
    // Data a camera appends after the end-of-image marker: read as before.
    WriteBytes(image, whole + std::string("\xFF\xE1 camera record \xFF\xD8\x00", 20));
    EXPECT_EQ(cv::norm(ReadGreyImage(image), original, cv::NORM_INF), 0);
    // Cut inside the headers, the tables, the scans, and just before FF D9.
    for (const std::size_t cut : {std::size_t{3}, std::size_t{30}, whole.size() / 4,
                                  whole.size() / 2, whole.size() - 40, whole.size() - 2}) {
      WriteBytes(image, whole.substr(0, cut));
      EXPECT_NE(
          ReadError(image).find("a truncated JPEG: the file ends at byte " + std::to_string(cut)),
          std::string::npos)
          << "cut at " << cut << " of " << whole.size() << ": " << ReadError(image);
    }
  }
}

TEST(ImageInputFaults, FramesThatAreNotRegularFilesAreNamed) {
  TestDir dir;
  const std::vector<std::string> files = WriteSequence(dir, "seq", ".png");
  const std::string& frame = files[2];
  const std::string out = " -o " + dir.File("out.csv");
  // Before, each was left out of the list and reported as "1 frame(s) missing".
  fs::remove(frame);
  fs::create_directory(frame);
  ExpectOnlyOurError("correlate --frames " + dir.File("seq") + out,
                     {frame + ": is a folder, not a regular file"});
  fs::remove(frame);
  fs::create_symlink("f_0009.png", frame);
  ExpectOnlyOurError("correlate --frames " + dir.File("seq") + out,
                     {frame + ": is a dangling symbolic link to f_0009.png, which does not exist"});
  ExpectOnlyOurError("correlate --frames " + Quoted(dir.File("seq/f_*.png")) + out,
                     {frame + ": is a dangling symbolic link to f_0009.png"});
  ExpectOnlyOurError("correlate --reference " + files[0] + " --deformed " + frame + out,
                     {frame + ": is a dangling symbolic link to f_0009.png"});
  // A FIFO is judged by stat(): never opened, so nothing blocks waiting for a writer.
  fs::remove(frame);
  ASSERT_EQ(mkfifo(frame.c_str(), 0600), 0);
  ExpectOnlyOurError("correlate --frames " + dir.File("seq") + out,
                     {frame + ": is a pipe (FIFO), not a regular file"});
  ExpectOnlyOurError("correlate --frames " + Quoted(dir.File("seq/f_*.png")) + out,
                     {frame + ": is a pipe (FIFO), not a regular file"});
  EXPECT_FALSE(fs::exists(dir.File("out.csv")));
}

TEST(ImageInputFaults, SameFileTwiceInASequenceIsRefused) {
  TestDir dir;
  const std::vector<std::string> files = WriteSequence(dir, "seq", ".png");
  const std::string out = " -o " + dir.File("out.csv");
  // A link made to fill a gap in the numbering: the repeated image would read as no motion.
  fs::remove(files[2]);
  fs::create_symlink("f_0001.png", files[2]);
  ExpectOnlyOurError("correlate --frames " + dir.File("seq") + out,
                     {files[2], "the same file as " + files[1]});
  fs::remove(files[2]);
  fs::create_hard_link(files[1], files[2]);
  ExpectOnlyOurError("correlate --frames " + dir.File("seq") + out,
                     {files[2], "the same file as " + files[1]});
  EXPECT_FALSE(fs::exists(dir.File("out.csv")));
}

// A PNG chunk: length, type, body, CRC.
std::string PngChunk(const std::string& type, const std::string& body) {
  std::string chunk;
  for (int shift = 24; shift >= 0; shift -= 8)
    chunk += static_cast<char>((body.size() >> shift) & 0xFF);
  const std::string typed = type + body;
  chunk += typed;
  const auto crc = static_cast<std::uint32_t>(
      crc32(0, reinterpret_cast<const Bytef*>(typed.data()), static_cast<uInt>(typed.size())));
  for (int shift = 24; shift >= 0; shift -= 8) chunk += static_cast<char>((crc >> shift) & 0xFF);
  return chunk;
}

// An 8-bit PNG of `channels` samples (colour type 0 or 2) made here, every chunk with a correct
// CRC. Row `bad_row` (of the whole image, or of the last Adam7 pass when interlaced) gets the
// filter type 7, which does not exist; -1 for none.
std::string MakePng(int width, int height, int colour, bool interlaced, int bad_row) {
  const int channels = colour == 2 ? 3 : 1;
  std::string header;
  for (const int v : {width, height})
    for (int shift = 24; shift >= 0; shift -= 8) header += static_cast<char>((v >> shift) & 0xFF);
  header += std::string{8, static_cast<char>(colour), 0, 0, static_cast<char>(interlaced)};
  // Adam7 (PNG specification section 8.2): each pass's columns x0 + k dx and rows y0 + k dy.
  const std::vector<std::vector<int>> passes =
      interlaced
          ? std::vector<std::vector<int>>{{0, 0, 8, 8}, {4, 0, 8, 8}, {0, 4, 4, 8}, {2, 0, 4, 4},
                                          {0, 2, 2, 4}, {1, 0, 2, 2}, {0, 1, 1, 2}}
          : std::vector<std::vector<int>>{{0, 0, 1, 1}};
  std::string raw;
  for (std::size_t p = 0; p < passes.size(); ++p) {
    const int w = (width - passes[p][0] + passes[p][2] - 1) / passes[p][2];
    const int h = (height - passes[p][1] + passes[p][3] - 1) / passes[p][3];
    if (w <= 0 || h <= 0) continue;
    for (int y = 0; y < h; ++y) {
      raw += static_cast<char>(p + 1 == passes.size() && y == bad_row ? 7 : 0);
      for (int x = 0; x < w * channels; ++x) raw += static_cast<char>((x * 37 + y * 11) & 0xFF);
    }
  }
  std::string packed(compressBound(static_cast<uLong>(raw.size())), '\0');
  uLongf packed_size = packed.size();
  EXPECT_EQ(compress(reinterpret_cast<Bytef*>(packed.data()), &packed_size,
                     reinterpret_cast<const Bytef*>(raw.data()), static_cast<uLong>(raw.size())),
            Z_OK);
  packed.resize(packed_size);
  return std::string("\x89PNG\r\n\x1a\n", 8) + PngChunk("IHDR", header) + PngChunk("IDAT", packed) +
         PngChunk("IEND", "");
}

TEST(ImageInputFaults, PngWithBadRowsGivesOurMessageWithoutLibpng) {
  TestDir dir;
  const std::string good = dir.File("good.png");
  WriteImage(good, Speckle(96, 80, 1));
  for (const int colour : {0, 2}) {  // grey (our decoder, then OpenCV's) and RGB (OpenCV's)
    const std::string bad = dir.File("bad" + std::to_string(colour) + ".png");
    WriteBytes(bad, MakePng(96, 80, colour, /*interlaced=*/false, /*bad_row=*/40));
    // Before: "libpng error: bad adaptive filter value" on a line of its own, then ours.
    ExpectOnlyOurError(
        fmt::format("correlate --reference {} --deformed {} -o {}", good, bad, dir.File("out.csv")),
        {bad, "a corrupt PNG: row 40 has filter type 7; the PNG filter types are 0-4"});
  }
  // Sound PNGs of every layout still read, interlaced ones too; a bad row in the last pass of an
  // interlaced one is found there.
  for (const int colour : {0, 2}) {
    for (const bool interlaced : {false, true}) {
      const std::string bytes = MakePng(13, 11, colour, interlaced, -1);
      EXPECT_EQ(PngImageDataProblem(bytes), "") << colour << " " << interlaced;
      WriteBytes(dir.File("ok.png"), bytes);
      EXPECT_EQ(ReadGreyImage(dir.File("ok.png")).size(), cv::Size(13, 11));
    }
  }
  EXPECT_EQ(PngImageDataProblem(MakePng(13, 11, 2, /*interlaced=*/true, /*bad_row=*/2)),
            "a corrupt PNG: row 2 of interlace pass 7 has filter type 7; the PNG filter types "
            "are 0-4");
  // The image data of a PNG cut inside its compressed data, with every CRC made right again.
  const std::string whole = MakePng(96, 80, 0, false, -1);
  const std::size_t idat = whole.find("IDAT");
  const std::size_t length = whole.size() - idat - 4 - 4 - 12;
  std::string cut_data = whole.substr(idat + 4, length / 2);
  const std::string cut = std::string("\x89PNG\r\n\x1a\n", 8) + whole.substr(8, idat - 4 - 8) +
                          PngChunk("IDAT", cut_data) + PngChunk("IEND", "");
  EXPECT_NE(PngImageDataProblem(cut).find("a corrupt PNG: its image data end in row "),
            std::string::npos)
      << PngImageDataProblem(cut);
}

TEST(ImageInputFaults, EmptyFilesAndBrokenVideosGiveOnlyOurMessage) {
  TestDir dir;
  const std::string good = dir.File("good.png");
  WriteImage(good, Speckle(96, 80, 1));
  const std::string out = " -o " + dir.File("out.csv");
  // Before: "a file OpenCV cannot decode: !buf.empty()".
  WriteBytes(dir.File("empty.png"), "");
  ExpectOnlyOurError("correlate --reference " + good + " --deformed " + dir.File("empty.png") + out,
                     {dir.File("empty.png") + ": is empty (0 bytes); expected an 8- or 16-bit"});
  // A BMP cut short: OpenCV's decoder printed "imdecode_(''): can't read data: OpenCV(4.6.0)
  // ... Unexpected end of input stream" to std::cerr; now that is our message's reason.
  WriteImage(dir.File("cut.bmp"), Speckle(96, 80, 1));
  const std::string bmp = ReadBytes(dir.File("cut.bmp"));
  WriteBytes(dir.File("cut.bmp"), bmp.substr(0, bmp.size() / 2));
  ExpectOnlyOurError(
      "correlate --reference " + good + " --deformed " + dir.File("cut.bmp") + out,
      {dir.File("cut.bmp") + ": image: bad file format (got a file OpenCV cannot decode"});
  // Before: FFmpeg's "moov atom not found" and OpenCV's GStreamer warning and assertion
  // ("uridecodebin") before ours.
  WriteBytes(dir.File("empty.mp4"), "");
  ExpectOnlyOurError("correlate --frames " + dir.File("empty.mp4") + out,
                     {dir.File("empty.mp4") + ": is empty (0 bytes); expected a video file"});
  // An MP4 whose recording stopped before its index (only the 'ftyp' box): the same, once
  // FFmpeg and GStreamer have both tried it.
  WriteBytes(dir.File("cut.mp4"), std::string("\0\0\0\x18"
                                              "ftypisom\0\0\x02\0isomiso2",
                                              24) +
                                      std::string(64, '\0'));
  ExpectOnlyOurError("correlate --frames " + dir.File("cut.mp4") + out,
                     {dir.File("cut.mp4") + ": video: bad file format"});
  EXPECT_FALSE(fs::exists(dir.File("out.csv")));
}

}  // namespace
}  // namespace impactdic
