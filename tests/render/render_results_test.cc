// Re-rendering from a results file (library and `impactdic render`): every output from a complete
// file, skipping of absent data, and clear errors with exit codes for bad input.
#include "impactdic/render/render_results.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "../cli/cli_runner.h"
#include "impactdic/core/error.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/kinematics/kinematics_results.h"
#include "impactdic/model/model_results.h"
#include "impactdic/momentum/momentum_results.h"
#include "impactdic/sensor/sensor_results.h"
#include "test_util.h"

namespace impactdic {
namespace {

namespace L = results_layout;
using test::IsPngOfSize;
using test::ScratchDir;

struct Parts {
  bool momentum = true, sensor = true, model = true, field = true, frames = true;
  int frame_count = 12;
};

// A small results file: 12 (or parts.frame_count) frames of 160 x 120 px, a subset grid every
// 12 px, synthetic series.
void WriteResults(const std::string& path, const Parts& parts) {
  const int kFrames = parts.frame_count;
  constexpr int kRows = 120, kCols = 160;
  H5Writer out(path);
  if (parts.field) {
    const auto seq = test::MakeSequence(kFrames, kCols, kRows, 12);
    const std::size_t n = seq.num_subsets;
    out.Write(L::kTimeMs, seq.time_ms, "ms", "time since impact");
    out.Write(L::kDicX, seq.x_px, "px", "subset centre x");
    out.Write(L::kDicY, seq.y_px, "px", "subset centre y");
    std::vector<double> u(kFrames * n), v(kFrames * n);
    for (int i = 0; i < kFrames; ++i) {
      for (std::size_t s = 0; s < n; ++s) v[i * n + s] = 0.3 * i;  // moving down
    }
    out.Write(L::kDicU, u, {std::size_t(kFrames), n}, "px", "displacement x");
    out.Write(L::kDicV, v, {std::size_t(kFrames), n}, "px", "displacement y");
    out.Write(L::kVx, seq.vx_mm_s, {std::size_t(kFrames), n}, "mm/s", "velocity x");
    out.Write(L::kVy, seq.vy_mm_s, {std::size_t(kFrames), n}, "mm/s", "velocity y");
    out.SetAttribute(L::kKinematicsGroup, L::kMmPerPxAttr, 0.25);
    if (parts.frames) test::WriteFrames(seq, out);
  }
  std::vector<double> t, pp, pg, pt, madd;
  for (int i = 0; i < 30; ++i) {
    const double ti = i / 1600.0 * 0.5;
    t.push_back(ti);
    pp.push_back(39.0 * std::exp(-ti / 3e-3));
    pg.push_back(39.0 - pp.back());
    pt.push_back(39.0);
    madd.push_back(10.0 / (1.0 + std::exp(-2500.0 * (ti - 2e-3))));
  }
  if (parts.momentum) {
    out.Write(L::kMomentumT, t, "s", "time since impact");
    out.Write(L::kPPounder, pp, "N s", "pounder momentum");
    out.Write(L::kPGran, pg, "N s", "granular momentum");
    out.Write(L::kPTotal, pt, "N s", "total momentum");
    out.Write(L::kMAdd, madd, "kg", "added mass");
    out.SetAttribute(L::kMomentumGroup, L::kPMaxAttr, 39.0);
    out.SetAttribute(L::kMomentumGroup, L::kTeAttr, 4e-3);
    out.SetAttribute(L::kMomentumGroup, L::kSigmoidMAttr, 10.0);
    out.SetAttribute(L::kMomentumGroup, L::kSigmoidBAttr, 2500.0);
    out.SetAttribute(L::kMomentumGroup, L::kSigmoidTAttr, 2e-3);
  }
  std::vector<double> decel(t.size());
  for (std::size_t i = 0; i < t.size(); ++i)
    decel[i] = 60.0 * std::exp(-std::pow((t[i] - 2e-3) / 1e-3, 2));
  if (parts.sensor) {
    out.Write(L::kSensorT, t, "s", "time");
    out.Write(L::kSensorDecel, decel, "g", "measured deceleration");
  }
  if (parts.model) {
    out.Write(L::kModelT, t, "s", "time");
    out.Write(L::kModelDecel, decel, "g", "model deceleration");
  }
  if (!parts.momentum && !parts.sensor && !parts.model && !parts.field) {
    out.Write("/other/thing", std::vector<double>{1.0}, "-", "unrelated");
  }
  out.Commit();
}

RenderResultsOptions FastOptions(const std::string& out_dir) {
  RenderResultsOptions o;
  o.output_dir = out_dir;
  o.animation_options.overlay.min_width_px = 320;
  return o;
}

TEST(RenderResults, CompleteFileGivesEveryOutput) {
  ScratchDir dir("res");
  WriteResults(dir / "results.h5", {});
  const auto s = RenderResults(dir / "results.h5", FastOptions(dir / "out"));
  EXPECT_TRUE(s.skipped.empty()) << s.FullReport();
  for (const char* png :
       {L::kMomentumPng, L::kDecelerationPng, L::kAddedMassPng, L::kVelocitySnapshotPng}) {
    EXPECT_TRUE(IsPngOfSize(dir / (std::string("out/") + png), 640, 480)) << png;
  }
  ASSERT_TRUE(s.has_animation);
  EXPECT_EQ(s.animation.frames_read_back, 12u);
  EXPECT_EQ(CountVideoFrames(s.animation.path), 12u);
  EXPECT_EQ(s.written.size(), 5u);
}

TEST(RenderResults, SkipsWhatIsAbsent) {
  ScratchDir dir("res");
  Parts parts;
  parts.momentum = parts.field = false;
  WriteResults(dir / "results.h5", parts);
  const auto s = RenderResults(dir / "results.h5", FastOptions(dir / "out"));
  EXPECT_EQ(s.written.size(), 1u) << s.FullReport();
  EXPECT_TRUE(IsPngOfSize(dir / "out/deceleration.png", 640, 480));
  EXPECT_EQ(s.skipped.size(), 4u) << s.FullReport();  // momentum, m_add, snapshot, animation
  EXPECT_FALSE(s.has_animation);
  EXPECT_FALSE(std::filesystem::exists(dir / "out/momentum.png"));
}

TEST(RenderResults, FieldWithoutFramesSkipsTheImages) {
  ScratchDir dir("res");
  Parts parts;
  parts.frames = false;
  parts.sensor = parts.model = parts.momentum = false;
  WriteResults(dir / "results.h5", parts);
  RenderResultsOptions o = FastOptions(dir / "out");
  const auto s = RenderResults(dir / "results.h5", o);
  EXPECT_TRUE(s.written.empty());
  ASSERT_EQ(s.skipped.size(), 5u) << s.FullReport();
  EXPECT_NE(s.FullReport().find("/frames/images"), std::string::npos) << s.FullReport();
}

TEST(RenderResults, FileWithoutAnyRenderDataIsAFormatError) {
  ScratchDir dir("res");
  Parts none;
  none.momentum = none.sensor = none.model = none.field = false;
  WriteResults(dir / "results.h5", none);
  try {
    RenderResults(dir / "results.h5", FastOptions(dir / "out"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kFileFormat);
    EXPECT_NE(std::string(e.what()).find("/kinematics/vx_mm_s"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("results.h5"), std::string::npos) << e.what();
  }
}

TEST(RenderResults, InconsistentShapesNameTheDataset) {
  ScratchDir dir("res");
  {
    H5Writer out(dir / "results.h5");
    out.Write(L::kTimeMs, std::vector<double>{0, 1, 2}, "ms", "");
    out.Write(L::kDicX, std::vector<double>{1, 2}, "px", "");
    out.Write(L::kDicY, std::vector<double>{1, 2}, "px", "");
    out.Write(L::kVx, std::vector<double>(4, 1.0), {2, 2}, "mm/s", "");  // 2 frames, not 3
    out.Write(L::kVy, std::vector<double>(4, 1.0), {2, 2}, "mm/s", "");
    out.Commit();
  }
  try {
    RenderResults(dir / "results.h5", FastOptions(dir / "out"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kFileFormat);
    EXPECT_NE(std::string(e.what()).find("/kinematics/vx_mm_s"), std::string::npos) << e.what();
  }
}

TEST(RenderResults, ReadsLagrangianPositionsAndScale) {
  ScratchDir dir("res");
  WriteResults(dir / "results.h5", {});
  const H5Reader r(dir / "results.h5");
  const VelocityFieldSequence seq = ReadVelocityFieldSequence(r);
  EXPECT_EQ(seq.num_frames(), 12u);
  EXPECT_TRUE(seq.lagrangian());
  EXPECT_NEAR(seq.y(11, 0) - seq.y(0, 0), 0.3 * 11, 1e-12);  // y_px + v_px, to rounding
  EXPECT_DOUBLE_EQ(seq.mm_per_px, 0.25);
  EXPECT_EQ(seq.frames[0].type(), CV_8UC1);
}

// The CLI.
TEST(RenderCli, RendersEverythingWithPngFrames) {
  ScratchDir dir("cli");
  Parts few;
  few.frame_count = 4;  // the CLI draws at full display size: keep it short
  WriteResults(dir / "results.h5", few);
  const CliResult r = RunCli("render " + (dir / "results.h5") + " -o " + (dir / "out") +
                             " --png-frames --codec mjpg");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(IsPngOfSize(dir / "out/momentum.png", 640, 480)) << r.output;
  EXPECT_TRUE(IsPngOfSize(dir / "out/velocity_field_te.png", 640, 480));
  EXPECT_EQ(CountVideoFrames(dir / "out/velocity.avi"), 4u) << r.output;
  EXPECT_TRUE(IsPngOfSize(dir / "out/velocity_frames/frame_00003.png", 640, 480));
  EXPECT_NE(r.output.find("velocity.avi"), std::string::npos) << r.output;
}

// The drawing is the scene's outputs.* keys, as flags: the figure and the display size follow them.
TEST(RenderCli, SceneDrawingKeysAsFlags) {
  ScratchDir dir("cli");
  Parts few;
  few.frame_count = 4;
  WriteResults(dir / "results.h5", few);
  const CliResult r = RunCli("render " + (dir / "results.h5") + " -o " + (dir / "out") +
                             " --no-animation --outputs.plot.width_px 500 --outputs.plot.height_px "
                             "300 --outputs.velocity_map.min_width_px 320 "
                             "--outputs.velocity_map.max_width_px 320");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(IsPngOfSize(dir / "out/momentum.png", 500, 300)) << r.output;
  EXPECT_TRUE(IsPngOfSize(dir / "out/velocity_field_te.png", 320, 240)) << r.output;
  const CliResult bad = RunCli("render " + (dir / "results.h5") + " -o " + (dir / "bad") +
                               " --outputs.plot.width_px 100");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("--outputs.plot.width_px"), std::string::npos) << bad.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad"));
}

TEST(RenderCli, MissingFileFails) {
  ScratchDir dir("cli");
  const CliResult r = RunCli("render " + (dir / "nope.h5"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("nope.h5"), std::string::npos) << r.output;
}

TEST(RenderCli, NotAnHdf5FileFails) {
  ScratchDir dir("cli");
  std::ofstream(dir / "fake.h5") << "this is not HDF5";
  const CliResult r = RunCli("render " + (dir / "fake.h5"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("fake.h5"), std::string::npos) << r.output;
}

TEST(RenderCli, FileWithoutDatasetsFails) {
  ScratchDir dir("cli");
  Parts none;
  none.momentum = none.sensor = none.model = none.field = false;
  WriteResults(dir / "results.h5", none);
  const CliResult r = RunCli("render " + (dir / "results.h5") + " -o " + (dir / "out"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("none of the datasets"), std::string::npos) << r.output;
}

TEST(RenderCli, UnwritableOutputFolderFails) {
  ScratchDir dir("cli");
  Parts few;
  few.frame_count = 4;  // the CLI draws at full display size: keep it short
  WriteResults(dir / "results.h5", few);
  std::ofstream(dir / "a_file") << "x";  // a file where the folder should be
  const CliResult r = RunCli("render " + (dir / "results.h5") + " -o " + (dir / "a_file/out"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("output folder"), std::string::npos) << r.output;
}

TEST(RenderCli, BadOptionsFailBeforeWork) {
  ScratchDir dir("cli");
  Parts few;
  few.frame_count = 4;  // the CLI draws at full display size: keep it short
  WriteResults(dir / "results.h5", few);
  CliResult r = RunCli("render " + (dir / "results.h5") + " --codec vp9 -o " + (dir / "out"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("--codec"), std::string::npos) << r.output;
  r = RunCli("render " + (dir / "results.h5") + " --fps 0 -o " + (dir / "out"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("--fps"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}

TEST(RenderCli, MissingGnuplotIsAClearErrorWithoutOutput) {
  ScratchDir dir("cli");
  Parts few;
  few.frame_count = 4;  // the CLI draws at full display size: keep it short
  WriteResults(dir / "results.h5", few);
  const CliResult r =
      RunCli("render " + (dir / "results.h5") + " -o " + (dir / "out") + " --no-animation");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::filesystem::remove_all(dir / "out");
  setenv("IMPACTDIC_GNUPLOT", "/nonexistent/gnuplot", 1);
  const CliResult bad = RunCli("render " + (dir / "results.h5") + " -o " + (dir / "out"));
  unsetenv("IMPACTDIC_GNUPLOT");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("IMPACTDIC_GNUPLOT"), std::string::npos) << bad.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out/momentum.png"));
}

}  // namespace
}  // namespace impactdic
