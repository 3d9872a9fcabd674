// Camera files (Photron .cih/.cihx + .mraw, Phantom .cine) that say something unusual or absurd:
// a Photron save step (every n-th recorded frame kept: numbers, times, rate and selection by frame
// number), rates outside a camera's range, contradicting or unreadable descriptions, a cine header
// whose image size or frame rate contradicts the file. Each is read right or refused with a
// message naming the file, the field and what is expected. The files are written here
// (tests/io/mraw_test_writer.h, tests/io/cine_test_writer.h).
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "../io/cine_test_writer.h"
#include "../io/mraw_test_writer.h"
#include "fault_util.h"
#include "impactdic/core/error.h"
#include "impactdic/io/camera_file.h"
#include "impactdic/io/frame_source.h"
#include "impactdic/io/hdf5_store.h"

namespace impactdic {
namespace {

// The message of the Error `open` throws, or "" when it throws none.
template <typename F>
std::string ErrorOf(F open) {
  try {
    open();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// Every part appears in `message`.
void ExpectMessage(const std::string& message, std::initializer_list<std::string> parts) {
  EXPECT_FALSE(message.empty()) << "no error";
  for (const std::string& part : parts) {
    EXPECT_NE(message.find(part), std::string::npos)
        << "'" << part << "' missing from: " << message;
  }
}

// `count` 8-bit speckle frames (identical: they correlate at zero displacement).
std::vector<cv::Mat> SpeckleFrames(int count) {
  return std::vector<cv::Mat>(static_cast<std::size_t>(count), Speckle(96, 80, 3));
}

// A recording at 3200 fps of which every 2nd frame was saved, from camera frame -10: ten frames
// numbered -10, -8, ..., 8.
test::MrawWriteOptions SaveStepTwo() {
  test::MrawWriteOptions o;
  o.color_bit = 8;
  o.fps = 3200;
  o.save_step = 2;
  o.start_frame = -10;
  return o;
}

TEST(CameraFileFaults, PhotronSaveStepNumbersTimesAndRatesTheSavedFrames) {
  const TestDir dir;
  for (const bool cihx : {false, true}) {
    SCOPED_TRACE(cihx ? ".cihx (frameInfo/skipFrame)" : ".cih (Save Step)");
    test::MrawWriteOptions o = SaveStepTwo();
    o.cihx = cihx;
    const std::string path =
        test::WriteMraw(dir.File(cihx ? "stepx" : "step"), SpeckleFrames(10), o);
    const std::unique_ptr<FrameSource> source = OpenFrameSource(path);
    ASSERT_EQ(source->frame_count(), 10);
    // Before: numbers -10, -9, ..., -1 (the row labelled 0 was camera frame +10).
    for (int i = 0; i < 10; ++i) {
      const long long number = -10 + 2 * i;
      EXPECT_EQ(source->FrameNumber(i), number) << i;
      EXPECT_DOUBLE_EQ(source->TimeS(i), static_cast<double>(number) / 3200) << i;
    }
    EXPECT_DOUBLE_EQ(source->fps(), 1600);
    EXPECT_EQ(source->Name(5), path + " frame 0");
    // Selection by camera frame number.
    EXPECT_EQ(FrameIndexOf(*source, -8, "--first"), 1);
    EXPECT_EQ(FrameIndexOf(*source, 0, "--last"), 5);
    EXPECT_EQ(FrameIndexOf(*source, 8, "--last"), 9);
    // Frame -9 was never saved (before: accepted, index 1, camera frame -8).
    ExpectMessage(ErrorOf([&] { FrameIndexOf(*source, -9, "--first"); }),
                  {"--first", "got -9", "frames -10..8 in steps of 2"});
    ExpectMessage(ErrorOf([&] { FrameIndexOf(*source, 10, "--last"); }),
                  {"--last", "got 10", "frames -10..8 in steps of 2"});

    const CameraFileInfo info = OpenCameraFile(path)->info();
    EXPECT_EQ(info.frame_step, 2);
    EXPECT_EQ(info.FrameNumber(3), -4);
  }
}

TEST(CameraFileFaults, CorrelateSelectsSavedFramesByTheirCameraNumbers) {
  const TestDir dir;
  const std::string path = test::WriteMraw(dir.File("rec"), SpeckleFrames(10), SaveStepTwo());
  const std::string out = dir.File("out.h5");
  // Before: --last 0 selected 11 frames up to camera frame +10, labelled -10..0.
  const CliResult r = RunCli("-q correlate --frames " + path +
                             " --subset 21 --step 32 --first -8 --last 0 --threads 1 -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  H5Reader h5(out);
  EXPECT_EQ(h5.ReadDouble("/dic/frame_number"), (std::vector<double>{-8, -6, -4, -2, 0}));
  const std::vector<double> t = h5.ReadDouble("/dic/time_s");
  ASSERT_EQ(t.size(), 5u);
  for (std::size_t k = 0; k < t.size(); ++k) EXPECT_DOUBLE_EQ(t[k], (-8.0 + 2.0 * k) / 3200) << k;
  // A frame the camera did not save.
  ExpectCliFailure("-q correlate --frames " + path + " --first -9 --last 0 -o " + dir.File("x.h5"),
                   {"--first", "-9", "in steps of 2"});
}

TEST(CameraFileFaults, PhotronRatesOutsideACamerasRangeAreRefused) {
  const TestDir dir;
  for (const std::string rate : {"1e300", "1e-300", "0", "-3200", "inf", "nan", "2e7", "0.5"}) {
    SCOPED_TRACE(rate);
    test::MrawWriteOptions o;
    o.color_bit = 8;
    o.record_rate = rate;
    const std::string path = test::WriteMraw(dir.File("rate"), SpeckleFrames(2), o);
    // Before: 1e300 and 1e-300 (and 2e7, 0.5) were read, giving absurd velocities.
    ExpectMessage(ErrorOf([&] { OpenMrawFile(path); }),
                  {path, "Record Rate(fps)", "'" + rate + "'", "[1, 1e+07] 1/s"});
  }
  // The .cihx names its element.
  test::MrawWriteOptions x;
  x.color_bit = 8;
  x.cihx = true;
  x.record_rate = "1e300";
  const std::string cihx = test::WriteMraw(dir.File("ratex"), SpeckleFrames(2), x);
  ExpectMessage(ErrorOf([&] { OpenMrawFile(cihx); }), {cihx, "recordInfo/recordRate"});
  // The CLI refuses it too.
  test::MrawWriteOptions big;
  big.color_bit = 8;
  big.record_rate = "1e300";
  const std::string cih = test::WriteMraw(dir.File("big"), SpeckleFrames(2), big);
  ExpectCliFailure("-q correlate --frames " + cih + " -o " + dir.File("big.h5"),
                   {"Record Rate(fps)", "1e300"});
}

TEST(CameraFileFaults, PhotronSaveStepsBelowOneOrGivingAbsurdRatesAreRefused) {
  const TestDir dir;
  for (const std::string step : {"0", "-1", "2000000", "1.5"}) {
    SCOPED_TRACE(step);
    const std::string path = test::WriteMraw(dir.File("s"), SpeckleFrames(2), SaveStepTwo());
    std::string text = ReadBytes(path);
    text.replace(text.find("Save Step : 2"), 13, "Save Step : " + step);
    WriteBytes(path, text);
    ExpectMessage(ErrorOf([&] { OpenMrawFile(path); }),
                  {path, "Save Step", "'" + step + "'", "an integer in [1, 1048576]"});
  }
  // Each rate is a camera's, but the saved frames are 0.1 per second apart.
  test::MrawWriteOptions slow;
  slow.color_bit = 8;
  slow.fps = 100;
  slow.save_step = 1000;
  const std::string slow_path = test::WriteMraw(dir.File("slow"), SpeckleFrames(2), slow);
  ExpectMessage(ErrorOf([&] { OpenMrawFile(slow_path); }),
                {slow_path, "Save Step", "1000", "0.1 frames/s",
                 "Record Rate(fps) / Save Step) in [1, 1e+07] 1/s"});
}

TEST(CameraFileFaults, CineFrameRatesOutsideACamerasRangeAreRefused) {
  const TestDir dir;
  for (const std::uint32_t rate : {0U, 20000000U}) {
    test::SyntheticCine c;
    c.frame_rate = rate;
    c.images = {std::vector<std::uint8_t>(24, 1)};
    const std::string path = dir.File("rate.cine");
    test::WriteCineFile(path, c);
    // Before: 2e7 fps was read.
    ExpectMessage(ErrorOf([&] { OpenCineFile(path); }),
                  {path, rate == 0 ? "FrameRate16" : "FrameRate", "[1, 1e+07] 1/s"});
  }
}

TEST(CameraFileFaults, ColourBitsWithAMonoColourTypeNameTheContradiction) {
  const TestDir dir;
  test::MrawWriteOptions o;
  o.color_bit = 24;
  const std::string path = test::WriteMraw(dir.File("rgb"), SpeckleFrames(1), o);
  const std::string message = ErrorOf([&] { OpenMrawFile(path); });
  // Before: "Color Type: ... (got 'Mono')", blaming the field that is right.
  ExpectMessage(message,
                {path, "Color Bit", "24 bits", "colour", "Color Type says 'Mono'", "contradict"});
  // Without a Color Type line, the bits alone.
  o.omit_keys = {"Color Type"};
  const std::string bare = test::WriteMraw(dir.File("rgb2"), SpeckleFrames(1), o);
  ExpectMessage(ErrorOf([&] { OpenMrawFile(bare); }), {"Color Bit", "24 bits", "colour"});
}

// The .cih at `path` rewritten as UTF-16 (little-endian with a byte-order mark unless
// `big_endian_no_bom`).
void ToUtf16(const std::string& path, bool big_endian_no_bom) {
  const std::string text = ReadBytes(path);
  std::string utf16 = big_endian_no_bom ? "" : "\xFF\xFE";
  for (const char c : text) {
    if (big_endian_no_bom) utf16.push_back('\0');
    utf16.push_back(c);
    if (!big_endian_no_bom) utf16.push_back('\0');
  }
  WriteBytes(path, utf16);
}

TEST(CameraFileFaults, Utf16DescriptionsAreDecodedAndBinaryOnesNamed) {
  const TestDir dir;
  for (const bool big_endian_no_bom : {false, true}) {
    const std::string path = test::WriteMraw(dir.File("u16"), SpeckleFrames(3), SaveStepTwo());
    ToUtf16(path, big_endian_no_bom);
    // Before: "Color Bit: ... (got nothing)".
    std::unique_ptr<CameraFileReader> reader;
    ASSERT_NO_THROW(reader = OpenMrawFile(path));
    EXPECT_EQ(reader->info().frame_count, 3);
    EXPECT_EQ(reader->info().FrameNumber(2), -6);
    EXPECT_DOUBLE_EQ(reader->info().fps, 1600);
  }
  // Not text at all.
  const std::string path = test::WriteMraw(dir.File("bin"), SpeckleFrames(1), SaveStepTwo());
  WriteBytes(path, std::string("\x01\x00\x7f\x10garbage\x00\x00", 13));
  ExpectMessage(ErrorOf([&] { OpenMrawFile(path); }),
                {path, "NUL byte at byte 1", "ASCII or UTF-8 text"});
}

TEST(CineFaults, ImageSizeBeyondTheFileNamesTheHeaderFields) {
  const TestDir dir;
  test::SyntheticCine c;
  c.width = 65536;
  c.bi_height = 65536;
  const std::string path = dir.File("huge.cine");
  // One image: larger than the file; two: larger than their spacing in it.
  for (const int images : {1, 2}) {
    SCOPED_TRACE(images);
    c.images.assign(static_cast<std::size_t>(images), std::vector<std::uint8_t>(24, 1));
    test::WriteCineFile(path, c);
    const std::string message = ErrorOf([&] { OpenCineFile(path); });
    // Before: "the file ... ends inside frame 0", as if the file were truncated.
    ExpectMessage(message, {path, "biWidth x biHeight 65536 x 65536", "corrupt image header",
                            images == 1 ? "more than the whole" : "images are 32 bytes apart"});
    EXPECT_EQ(message.find("truncated"), std::string::npos) << message;
  }
}

TEST(CineFaults, FrameRateContradictingTheTimeStampsNamesBothRates) {
  const TestDir dir;
  test::SyntheticCine c;
  c.frame_rate = 1;
  c.images.assign(5, std::vector<std::uint8_t>(24, 1));
  c.time_s = {0.00, 0.01, 0.02, 0.03, 0.04};  // 100 frames/s.
  const std::string path = dir.File("rate.cine");
  test::WriteCineFile(path, c);
  // Before: read, and a run then blamed a dropped frame between the first two frames.
  ExpectMessage(ErrorOf([&] { OpenCineFile(path); }),
                {path, "FrameRate", "got 1 frames/s", "time stamps say 100 frames/s"});
  // A single dropped frame (one long interval) does not move the median: read.
  c.frame_rate = 100;
  c.time_s = {0.00, 0.01, 0.03, 0.04, 0.05};
  test::WriteCineFile(path, c);
  EXPECT_DOUBLE_EQ(OpenCineFile(path)->info().fps, 100);
}

}  // namespace
}  // namespace impactdic
