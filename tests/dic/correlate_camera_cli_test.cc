// `impactdic correlate --frames` on camera files: every Phantom .cine sample of DICe's tests
// (../shared/data/cine) and Photron .mraw recordings of 8, 10, 12 and 16 bits written from the
// published layout (.cih, .cihx, or the .mraw named), with --first/--last in the camera's frame
// numbers, the camera's frame numbers and time stamps in the .h5; and each refusal (colour,
// compressed, a frame number outside the recording, --first > --last, one frame).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../core/shared_data.h"
#include "../io/mraw_test_writer.h"
#include "../io/test_dir.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/camera_file.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/image_io.h"
#include "impactdic/synth/fields.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

// Frame k moves by (0.5 k, -0.25 k) px; values < 2^bits (CV_8U for 8 bits, else CV_16U).
std::vector<cv::Mat> ShiftedFrames(int count, int bits) {
  SpeckleOptions speckle;
  speckle.blob_radius_px = 2.5;
  SpecklePattern pattern(speckle, 96, 72);
  RenderOptions render;
  render.supersampling = 2;
  render.bits = bits == 8 ? 8 : 16;
  std::vector<cv::Mat> frames;
  frames.reserve(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k) {
    cv::Mat f = RenderImage(pattern, 96, 72, Translation(0.5 * k, -0.25 * k), render);
    if (bits != 8 && bits != 16) f.convertTo(f, CV_16U, ((1 << bits) - 1) / 65535.0);
    frames.push_back(f);
  }
  return frames;
}

std::string Quiet(const std::string& args) { return "correlate " + args + " --threads 1"; }

// A high-speed camera's low-contrast 12-bit recording (phantom_v7_raw_16bpp: grey levels 110..1731
// of 4095; a subset's standard deviation 30-60 counts, under 4 grey levels of an 8-bit image)
// correlates with the default options: its subsets' grey-level spread is judged against the range
// the frame uses, and subsets are refused by their predicted uncertainty (signal to noise). The
// left of the frame is static (the right has an object coming in), so every frame against the first
// (pairs) measures the noise floor, and the reported sigma must match the observed scatter of the
// displacements about zero.
TEST(CorrelateCameraCli, ALowContrastTwelveBitRecordingCorrelatesWithDefaultsAndAnHonestSigma) {
  IMPACTDIC_SHARED_DATA_OR_SKIP(cine, "cine");
  const TestDir dir;
  const std::string cine_file = (cine / "phantom_v7_raw_16bpp.cine").string();
  const std::string out = dir.File("v7.h5");
  const std::string args =
      fmt::format("--frames {} --subset 21 --step 20 --roi 0,0,110,128 --mode pairs", cine_file);
  const CliResult r = RunCli(Quiet(args + " -o " + out));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  H5Reader h5(out);
  const std::vector<std::int32_t> status = h5.ReadInt("/dic/status");
  const std::vector<double> u = h5.ReadDouble("/dic/u_px"), v = h5.ReadDouble("/dic/v_px");
  const std::vector<float> su = h5.ReadFloat("/dic/sigma_u_px"),
                           sv = h5.ReadFloat("/dic/sigma_v_px");
  const std::size_t subsets = h5.ReadDouble("/dic/x_px").size();
  ASSERT_EQ(subsets, 25u);
  ASSERT_EQ(status.size(), 6 * subsets);  // The reference row and five frames.
  int valid = 0, results = 0;
  double uu = 0, vv = 0;
  std::vector<double> sigma_u, sigma_v;
  for (std::size_t k = subsets; k < status.size(); ++k) {
    ++results;
    if (status[k] != static_cast<int>(SubsetStatus::kConverged)) continue;
    ++valid;
    uu += u[k] * u[k];
    vv += v[k] * v[k];
    sigma_u.push_back(su[k]);
    sigma_v.push_back(sv[k]);
  }
  EXPECT_GE(valid, 0.9 * results) << r.output;  // Measured 94.4 %: two spots change in the frames.
  const auto median = [](std::vector<double> x) {
    std::nth_element(x.begin(), x.begin() + x.size() / 2, x.end());
    return x[x.size() / 2];
  };
  ASSERT_GT(valid, 10);
  const double ratio_u = median(sigma_u) / std::sqrt(uu / valid);
  const double ratio_v = median(sigma_v) / std::sqrt(vv / valid);
  EXPECT_GE(ratio_u, 0.7);  // Measured 0.90 (sigma 0.043 px, RMS 0.048 px).
  EXPECT_LE(ratio_u, 1.3);
  EXPECT_GE(ratio_v, 0.7);  // Measured 0.90 (0.040 px, 0.045 px).
  EXPECT_LE(ratio_v, 1.3);
  // The subsets' contrast was judged on the container's scale before (4 levels of 255 = 64 counts
  // of 4095: every subset refused); on the frame's used range it passes, and the predicted
  // uncertainty decides: at a limit below what it predicts here (0.01 px) every subset is refused.
  const CliResult strict = RunCli(
      Quiet(args + " --dic.max_predicted_uncertainty_px 0.01 -o " + dir.File("v7_strict.h5")));
  EXPECT_NE(strict.exit_code, 0);
  EXPECT_NE(strict.output.find("low_contrast"), std::string::npos) << strict.output;
}

TEST(CorrelateCameraCli, EveryPhantomSampleCorrelatesWithItsFrameNumbersAndTimes) {
  IMPACTDIC_SHARED_DATA_OR_SKIP(cine, "cine");
  const TestDir dir;
  int samples = 0;
  for (const auto& entry : fs::directory_iterator(cine)) {
    const std::string path = entry.path().string();
    if (entry.path().extension() != ".cine" || entry.path().stem() == "invalid_color") continue;
    ++samples;
    const auto reader = OpenCameraFile(path);
    const CameraFileInfo& info = reader->info();
    const std::string out = dir.File(entry.path().stem().string() + ".h5");
    // The camera's frames 1..3 of the file, by their numbers.
    const long long first = info.first_frame_number + 1, last = info.first_frame_number + 3;
    const CliResult r = RunCli(Quiet(
        fmt::format("--frames {} --subset 21 --step 32 --first {} --last {} --allow-partial -o {}",
                    path, first, last, out)));
    ASSERT_EQ(r.exit_code, 0) << path << "\n" << r.output;
    H5Reader h5(out);
    EXPECT_EQ(h5.ReadDouble("/dic/frame_number"),
              (std::vector<double>{double(first), double(first + 1), double(last)}))
        << path;
    const std::vector<double> t = h5.ReadDouble("/dic/time_s");
    ASSERT_EQ(t.size(), 3u) << path;
    for (std::size_t k = 0; k < 3; ++k) EXPECT_DOUBLE_EQ(t[k], info.time_s[k + 1]) << path;
  }
  EXPECT_EQ(samples, 11);
}

TEST(CorrelateCameraCli, PhotronRecordingsOfEveryBitDepthCorrelate) {
  const TestDir dir;
  int variant = 0;
  for (int bits : {8, 10, 12, 16}) {
    test::MrawWriteOptions o;
    o.color_bit = bits;
    o.start_frame = -2;
    o.fps = 1000;
    o.cihx = bits == 10;
    const std::string stem = dir.File("rec" + std::to_string(bits));
    const std::string description = test::WriteMraw(stem, ShiftedFrames(5, bits), o);
    // The description, or the .mraw beside it.
    const std::string named = variant++ == 2 ? stem + ".mraw" : description;
    const std::string csv = stem + ".csv", h5 = stem + ".h5";
    const std::string args = "--frames " + named + " --subset 21 --step 16 --first -1 --last 2 -o ";
    const CliResult r = RunCli(Quiet(args + csv));
    ASSERT_EQ(r.exit_code, 0) << bits << " bits\n" << r.output;
    const CsvTable t = ReadCsv(csv, {.allow_non_finite = true, .text_columns = {"status"}});
    const auto& frame = t.Column("frame");
    const auto& u = t.Column("u_px");
    const auto& v = t.Column("v_px");
    const auto& status = t.TextColumn("status");
    int converged = 0;
    for (std::size_t i = 0; i < t.rows(); ++i) {
      EXPECT_GE(frame[i], 0);  // Deformed frames 0..2; the reference is camera frame -1.
      EXPECT_LE(frame[i], 2);
      if (status[i] != "converged") continue;
      ++converged;
      const double steps = frame[i] + 1;  // Frames after the reference.
      EXPECT_NEAR(u[i], 0.5 * steps, 0.05) << bits << " bits, row " << i;
      EXPECT_NEAR(v[i], -0.25 * steps, 0.05) << bits << " bits, row " << i;
    }
    EXPECT_GT(converged, static_cast<int>(t.rows() * 9 / 10)) << bits << " bits";
    ASSERT_EQ(RunCli(Quiet(args + h5)).exit_code, 0) << bits << " bits";
    H5Reader in(h5);
    EXPECT_EQ(in.ReadDouble("/dic/frame_number"), (std::vector<double>{-1, 0, 1, 2}));
    EXPECT_EQ(in.ReadDouble("/dic/time_s"), (std::vector<double>{-1e-3, 0, 1e-3, 2e-3}));
  }
}

// 10-bit data fits 0..4095 like 12-bit data, so the pixels alone would put its saturation at 4095;
// the recording states 10 bits, and glare clipped at 1023 is flagged `saturated`.
TEST(CorrelateCameraCli, TenBitRecordingsSaturateAtTheirOwnLimit) {
  const TestDir dir;
  std::vector<cv::Mat> frames = ShiftedFrames(3, 10);
  for (cv::Mat& f : frames) f(cv::Rect(0, 0, f.cols / 2, f.rows)).setTo(1023);  // Clipped glare.
  test::MrawWriteOptions o;
  o.color_bit = 10;
  const std::string cih = test::WriteMraw(dir.File("glare"), frames, o);
  const CliResult r =
      RunCli(Quiet("--frames " + cih + " --subset 21 --step 16 -o " + dir.File("glare.h5")));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("10-bit data in 16-bit images"), std::string::npos) << r.output;
  const std::vector<double> status = H5Reader(dir.File("glare.h5")).ReadDouble("/dic/status");
  const auto saturated =
      std::count(status.begin(), status.end(), static_cast<double>(SubsetStatus::kSaturated));
  EXPECT_GT(saturated, 0) << r.output;
}

TEST(CorrelateCameraCli, FrameRangeOutsideTheRecordingIsRefusedNamingItsSpan) {
  const TestDir dir;
  test::MrawWriteOptions o;
  o.start_frame = -2;
  const std::string cih = test::WriteMraw(dir.File("rec"), ShiftedFrames(4, 12), o);
  const std::string out = dir.File("out.csv");
  const auto refused = [&](const std::string& range, const std::vector<std::string>& texts) {
    const CliResult r = RunCli(Quiet("--frames " + cih + " " + range + " -o " + out));
    EXPECT_NE(r.exit_code, 0) << range << "\n" << r.output;
    for (const std::string& text : texts)
      EXPECT_NE(r.output.find(text), std::string::npos) << range << ": " << text << "\n"
                                                        << r.output;
    EXPECT_FALSE(fs::exists(out)) << range;
  };
  refused("--first -3", {"--first", "-3", "frames -2..1", cih});
  refused("--last 2", {"--last", "frames -2..1"});
  refused("--first 1 --last 0", {"--first/--last", "1 > 0"});
  refused("--first 1", {"at least two frames"});
  // Not a camera file: the numbers are those of the file names.
  fs::create_directories(dir.path() / "frames");
  const std::vector<cv::Mat> frames = ShiftedFrames(3, 8);
  for (int k = 0; k < 3; ++k)
    WriteImage(dir.File("frames/f_" + std::to_string(k + 7) + ".png"), frames[k]);
  const CliResult r = RunCli(Quiet("--frames " + dir.File("frames") + " --first 3 -o " + out));
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("frames 7..9"), std::string::npos) << r.output;
}

TEST(CorrelateCameraCli, ColourAndCompressedCineFilesAreRefused) {
  IMPACTDIC_SHARED_DATA_OR_SKIP(cine, "cine");
  const TestDir dir;
  const std::string out = dir.File("out.csv");
  const std::string colour = (cine / "invalid_color.cine").string();
  CliResult r = RunCli(Quiet("--frames " + colour + " -o " + out));
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("invalid_color.cine"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("colour recording"), std::string::npos) << r.output;
  // A grey sample whose header says JPEG-compressed (Compression = 1 at byte 4).
  std::string bytes;
  {
    std::ifstream in((cine / "phantom_v1610.cine").string(), std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  bytes[4] = 1;
  bytes[5] = 0;
  const std::string jpeg = dir.File("jpeg.cine");
  std::ofstream(jpeg, std::ios::binary) << bytes;
  r = RunCli(Quiet("--frames " + jpeg + " -o " + out));
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("jpeg.cine"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("JPEG-compressed"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace impactdic
