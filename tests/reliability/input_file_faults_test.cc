// Fault injection: input files of the wrong kind, encoding, separator or size (the one CSV reader
// in io/csv.cc, the one image reader in io/image_io.cc, io/input_file.h for every reader).
#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "../core/expect_error.h"
#include "../io/test_dir.h"
#include "fault_util.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/image_io.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

// A short accelerometer record in our format.
constexpr const char* kRecord =
    "time_s,accel_g,exposure\n0,1.25,0\n0.00004,1.5,1\n0.00008,-0.75,0\n";

TEST(InputFileFaults, Utf8BomCsvIsReadLikeThePlainFile) {
  TestDir dir;
  const std::string plain = dir.Write("plain.csv", kRecord);
  const std::string bom = dir.Write("bom.csv", std::string("\xEF\xBB\xBF") + kRecord);
  const CsvTable a = ReadCsv(plain), b = ReadCsv(bom);
  ASSERT_EQ(b.names, a.names);  // "time_s", not "\xEF\xBB\xBFtime_s".
  for (std::size_t c = 0; c < a.names.size(); ++c) EXPECT_EQ(b.columns[c], a.columns[c]);
  EXPECT_EQ(b.Column("time_s")[1], 0.00004);
}

TEST(InputFileFaults, SemicolonAndTabSeparatedCsvSayCommasAreExpected) {
  TestDir dir;
  const std::string semicolon =
      dir.Write("semicolon.csv", "time_s;accel_g;exposure\n0;1,25;0\n0,00004;1,5;1\n");
  ExpectCliFailure("analyze --sensor " + semicolon + " --from-release",
                   {semicolon + ":1", "'time_s;accel_g;exposure'", "separated by semicolons",
                    "expected comma-separated columns with '.' as decimal point"});
  const std::string tab = dir.Write("tab.csv", "time_s\taccel_g\texposure\n0\t1.25\t0\n");
  ExpectCliFailure("analyze --sensor " + tab + " --from-release",
                   {tab + ":1", "separated by tabs", "expected comma-separated columns"});
  // UTF-16 (Excel's "Unicode text") is named as such.
  const std::string utf16 = dir.Write("utf16.csv", std::string("\xFF\xFEt\0i\0", 6));
  ExpectErrorContaining([&] { ReadCsv(utf16); }, "UTF-16");
}

TEST(InputFileFaults, DeviceOrFolderAsSensorIsRefusedBeforeReading) {
  TestDir dir;
  // /dev/zero was read for minutes (16.8 GB) before "empty file"; now refused at once.
  ExpectCliFailure("analyze --sensor /dev/zero --from-release",
                   {"/dev/zero", "is a character device, not a regular file", "a CSV file"});
  const std::string folder = dir.path().string();
  ExpectCliFailure("analyze --sensor " + folder + " --from-release",
                   {folder, "is a folder, not a regular file", "a CSV file"});
  // The same through a scene's inputs.sensor.
  WriteFrames(dir, "frames", "f_", 0, 4);
  const std::string scene =
      dir.Write("scene.yaml",
                "inputs: {frames: frames/*.png, mm_per_px: 0.5, sensor: /dev/zero}\n"
                "momentum: {pounder_center_x_px: 10, surface_y_px: 5}\n");
  ExpectCliFailure("run " + scene + " -o " + dir.File("out"), {"/dev/zero", "character device"});
}

TEST(InputFileFaults, CsvLargerThanTheLimitIsRefusedBySize) {
  TestDir dir;
  // A sparse file: no disk space used, but 3 GiB by its size.
  const std::string big = dir.Write("big.csv", "time_s,accel_g\n");
  fs::resize_file(big, std::uintmax_t{3} << 30);
  ExpectCliFailure("analyze --sensor " + big + " --from-release",
                   {big, "is 3.2 GB, more than the 2.1 GB allowed for a CSV file"});
}

TEST(InputFileFaults, BinaryFileAsCsvIsNamedByItsKind) {
  TestDir dir;
  WriteImage(dir.File("image.png"), Speckle(16, 16, 1));
  const std::string png = dir.File("image.png");
  ExpectErrorContaining([&] { ReadCsv(png); }, "got a PNG image); expected a CSV file");
}

// A valid PNG signature and IHDR chunk claiming width x height, then nothing else.
std::string PngHeader(std::uint32_t width, std::uint32_t height) {
  std::string bytes = "\x89PNG\r\n\x1a\n";
  bytes += std::string("\0\0\0\x0d", 4) + "IHDR";
  for (std::uint32_t v : {width, height})
    for (int shift = 24; shift >= 0; shift -= 8) bytes += static_cast<char>((v >> shift) & 0xFF);
  bytes += std::string("\x08\0\0\0\0", 5) + std::string(4, '\0');  // 8-bit grey; CRC not checked
  return bytes;
}

TEST(InputFileFaults, HugePngHeaderIsRefusedWithItsSize) {
  TestDir dir;
  const std::string huge = dir.File("huge.png");
  WriteBytes(huge, PngHeader(100000, 100000));
  WriteImage(dir.File("ok.png"), Speckle(96, 80, 1));
  // Was a raw OpenCV assertion ("pixels <= CV_IO_MAX_IMAGE_PIXELS").
  const std::string output =
      ExpectCliFailure("correlate --reference " + huge + " --deformed " + dir.File("ok.png") +
                           " -o " + dir.File("out.csv"),
                       {huge, "100000x100000 px in its header", "at most 32768 px a side"});
  EXPECT_EQ(output.find("OpenCV"), std::string::npos) << output;
  // Also one side beyond the limit with few pixels in all.
  WriteBytes(huge, PngHeader(40000, 2));
  ExpectErrorContaining([&] { ReadGreyImage(huge); }, "40000x2 px");
}

TEST(InputFileFaults, TruncatedPngGivesOneMessageWithoutLibpngNoise) {
  TestDir dir;
  WriteImage(dir.File("ok.png"), Speckle(96, 80, 1));
  const std::string bytes = ReadBytes(dir.File("ok.png"));
  const std::string truncated = dir.File("truncated.png");
  WriteBytes(truncated, bytes.substr(0, bytes.size() / 2));
  const std::string output = ExpectCliFailure(
      "correlate --reference " + dir.File("ok.png") + " --deformed " + truncated + " -o " +
          dir.File("out.csv"),
      {truncated, "a truncated PNG: the file ends at byte", "expected a complete PNG file"});
  // Before: "libpng error: Read Error" on a line of its own, before our message.
  EXPECT_EQ(output.find("libpng"), std::string::npos) << output;
  // A flipped byte inside the image data: the chunk's CRC names it, again without libpng.
  std::string corrupt = bytes;
  corrupt[bytes.find("IDAT") + 20] ^= 0x55;
  WriteBytes(dir.File("corrupt.png"), corrupt);
  const std::string corrupt_output =
      ExpectCliFailure("correlate --reference " + dir.File("ok.png") + " --deformed " +
                           dir.File("corrupt.png") + " -o " + dir.File("out.csv"),
                       {"corrupt.png", "CRC error in its 'IDAT' chunk"});
  EXPECT_EQ(corrupt_output.find("libpng"), std::string::npos) << corrupt_output;
  // The intact file still reads (the structure check accepts what libpng writes).
  EXPECT_EQ(ReadGreyImage(dir.File("ok.png")).cols, 96);
}

}  // namespace
}  // namespace impactdic
