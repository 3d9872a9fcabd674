// The strain maps and animation drawn from a results file: written when the file
// has /strain and nothing extra when it has not, eps_v coloured with compression at the positive
// (red) end, and one colour scale for every frame of the animation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/kinematics/kinematics_results.h"
#include "impactdic/momentum/momentum_results.h"
#include "impactdic/render/render_results.h"
#include "impactdic/render/strain_field.h"
#include "test_util.h"

namespace impactdic {
namespace {

namespace L = results_layout;
using test::IsPngOfSize;
using test::ScratchDir;

constexpr int kFrames = 5, kRows = 120, kCols = 160, kStep = 12;

struct StrainParts {
  bool strain = true, frames = true, t_e = true, shear_band = true;
};

// A small results file: the velocity field of test::MakeSequence and, with parts.strain, a strain
// field growing with the frame: eps_v = +2 % k in the left half of the grid (compaction) and
// -2 % k in the right half (dilation), gamma_max = 1 % k y / rows, k = (frame + 1) / frames; a
// shear band along the grid column nearest the middle.
void WriteStrainResults(const std::string& path, const StrainParts& parts) {
  const auto seq = test::MakeSequence(kFrames, kCols, kRows, kStep);
  const std::size_t n = seq.num_subsets, f = kFrames;
  H5Writer out(path);
  out.Write(L::kTimeMs, seq.time_ms, "ms", "time since impact");
  out.Write(L::kDicX, seq.x_px, "px", "subset centre x");
  out.Write(L::kDicY, seq.y_px, "px", "subset centre y");
  out.Write(L::kVx, seq.vx_mm_s, {f, n}, "mm/s", "velocity x");
  out.Write(L::kVy, seq.vy_mm_s, {f, n}, "mm/s", "velocity y");
  out.SetAttribute(L::kKinematicsGroup, L::kMmPerPxAttr, 0.25);
  if (parts.frames) test::WriteFrames(seq, out);
  if (parts.t_e) {
    out.Write(L::kMomentumT, std::vector<double>{0.0, 1e-3, 2e-3}, "s", "time since impact");
    out.Write(L::kPTotal, std::vector<double>{39.0, 39.0, 39.0}, "N s", "total momentum");
    out.SetAttribute(L::kMomentumGroup, L::kTeAttr, 1.3e-3);
  }
  if (parts.strain) {
    std::vector<double> eps_v(f * n), gamma_max(f * n), band(f * n, 0.0);
    for (std::size_t i = 0; i < f; ++i) {
      const double k = (i + 1.0) / kFrames;
      for (std::size_t s = 0; s < n; ++s) {
        eps_v[i * n + s] = (seq.x_px[s] < kCols / 2.0 ? 0.02 : -0.02) * k;
        gamma_max[i * n + s] = 0.01 * k * seq.y_px[s] / kRows;
        band[i * n + s] = std::abs(seq.x_px[s] - kCols / 2.0) < kStep / 2.0 ? 1.0 : 0.0;
      }
    }
    out.Write(L::kStrainEpsV, eps_v, {f, n}, "1", "volumetric strain, compression positive");
    out.Write(L::kStrainGammaMax, gamma_max, {f, n}, "1", "maximum shear strain");
    if (parts.shear_band) out.Write(L::kStrainShearBand, band, {f, n}, "1", "shear band ridge");
  }
  out.Commit();
}

RenderResultsOptions FastOptions(const std::string& out_dir) {
  RenderResultsOptions o;
  o.output_dir = out_dir;
  o.figures = false;  // the gnuplot figures are not the subject here
  o.animation_options.overlay.min_width_px = 320;
  o.strain_overlay.min_width_px = 160;
  return o;
}

bool HasStrainEntry(const ScratchDir& dir, const std::string& folder) {
  for (const auto& e : std::filesystem::directory_iterator(dir / folder)) {
    if (e.path().filename().string().rfind("strain", 0) == 0) return true;
  }
  return false;
}

TEST(StrainFigures, MapsAndAnimationWhenTheFileHasStrain) {
  ScratchDir dir("strain");
  WriteStrainResults(dir / "results.h5", {});
  const auto s = RenderResults(dir / "results.h5", FastOptions(dir / "out"));
  EXPECT_TRUE(s.skipped.empty()) << s.FullReport();
  EXPECT_TRUE(IsPngOfSize(dir / (std::string("out/") + L::kStrainTePng), 320, 120));
  EXPECT_TRUE(IsPngOfSize(dir / (std::string("out/") + L::kStrainEndPng), 320, 120));
  ASSERT_TRUE(s.has_strain_animation) << s.FullReport();
  EXPECT_EQ(std::filesystem::path(s.strain_animation.path).stem(), "strain");
  EXPECT_EQ(s.strain_animation.frames_read_back, std::size_t(kFrames));
  EXPECT_EQ(CountVideoFrames(s.strain_animation.path), std::size_t(kFrames));
  // The velocity outputs are still there.
  EXPECT_TRUE(std::filesystem::exists(dir / (std::string("out/") + L::kVelocitySnapshotPng)));
  EXPECT_TRUE(s.has_animation);
}

TEST(StrainFigures, NothingExtraWithoutStrain) {
  ScratchDir dir("strain");
  StrainParts parts;
  parts.strain = false;
  WriteStrainResults(dir / "results.h5", parts);
  const auto s = RenderResults(dir / "results.h5", FastOptions(dir / "out"));
  EXPECT_FALSE(s.has_strain_animation);
  EXPECT_FALSE(HasStrainEntry(dir, "out")) << s.FullReport();
  for (const auto& w : s.written) {
    EXPECT_NE(std::filesystem::path(w).filename().string().rfind("strain", 0), 0u) << w;
  }
  for (const auto& k : s.skipped) EXPECT_NE(k.rfind("strain", 0), 0u) << k;
}

TEST(StrainFigures, NoSnapshotsOrAnimationWhenNotAsked) {
  ScratchDir dir("strain");
  WriteStrainResults(dir / "results.h5", {});
  RenderResultsOptions o = FastOptions(dir / "out");
  o.snapshot = o.animation = false;  // as `run` with outputs.figures and outputs.animation false
  o.figures = true;
  RenderResults(dir / "results.h5", o);
  EXPECT_FALSE(HasStrainEntry(dir, "out"));
}

// Compression (eps_v > 0) is drawn in the red end of the map: at a subset of the left half, in the
// last frame (eps_v = +2 %, the colour limit), on the plain background, the pixel is the blend of
// the map's last entry; with the sign flipped it would be the blue first entry.
TEST(StrainFigures, CompressionIsThePositiveEndOfTheMap) {
  ScratchDir dir("strain");
  StrainParts parts;
  parts.frames = false;  // a plain background: the expected colour is exact
  WriteStrainResults(dir / "results.h5", parts);
  RenderResultsOptions o = FastOptions(dir / "out");
  o.animation = false;
  RenderResults(dir / "results.h5", o);
  const cv::Mat png = cv::imread(dir / (std::string("out/") + L::kStrainEndPng));
  ASSERT_FALSE(png.empty());

  const StrainFieldSequence seq = ReadStrainFieldSequence(H5Reader(dir / "results.h5"));
  EXPECT_FALSE(seq.has_images());
  const StrainFieldRenderer renderer(seq, o.strain_overlay);
  EXPECT_NEAR(renderer.eps_v_limit(), 0.02, 1e-12);
  const int band = png.rows - renderer.canvas_size().height;  // the title band on top
  ASSERT_GT(band, 0);
  // A subset well inside the left half, away from the time stamp and the scale bar.
  std::size_t pick = seq.num_subsets;
  for (std::size_t s = 0; s < seq.num_subsets; ++s) {
    if (seq.x_px[s] > 2.5 * kStep && seq.x_px[s] < kCols / 2.0 - 2 * kStep && seq.y_px[s] > 60 &&
        seq.y_px[s] < 80) {
      pick = s;
      break;
    }
  }
  ASSERT_LT(pick, seq.num_subsets);
  const std::size_t last = kFrames - 1;
  ASSERT_GT(seq.eps_v[last * seq.num_subsets + pick], 0.019);
  const cv::Point2d p = renderer.CanvasPoint(0, last, pick);
  const cv::Vec3b got = png.at<cv::Vec3b>(int(std::lround(p.y)) + band, int(std::lround(p.x)));
  const double a = o.strain_overlay.opacity;
  auto blend = [&](int entry) {
    const cv::Vec3b c = CoolWarmLut().at<cv::Vec3b>(entry);
    cv::Vec3d v;
    for (int k = 0; k < 3; ++k) v[k] = a * c[k] + (1 - a) * 128.0;
    return v;
  };
  const cv::Vec3d positive = blend(255), negative = blend(0);
  EXPECT_LT(cv::norm(cv::Vec3d(got) - positive), 12.0)
      << "pixel " << cv::Vec3d(got) << ", positive end " << positive;
  EXPECT_GT(cv::norm(cv::Vec3d(got) - negative), 100.0);
  EXPECT_GT(got[2], got[0] + 80);  // red, not blue (BGR)
}

// One colour scale for the run: the colour bars (ticks and limits included) are the same pixels in
// every frame of the animation, although the field grows fivefold from the first frame to the last.
TEST(StrainFigures, ColourLimitsAreTheSameInEveryFrame) {
  ScratchDir dir("strain");
  WriteStrainResults(dir / "results.h5", {});
  RenderResultsOptions o = FastOptions(dir / "out");
  o.snapshot = false;
  o.png_frames = true;
  o.animation_options.codec = VideoCodec::kMjpg;
  const auto s = RenderResults(dir / "results.h5", o);
  ASSERT_TRUE(s.has_strain_animation) << s.FullReport();
  EXPECT_EQ(s.strain_animation.png_frames, std::size_t(kFrames));
  const StrainFieldRenderer renderer(ReadStrainFieldSequence(H5Reader(dir / "results.h5")),
                                     o.strain_overlay);
  std::vector<cv::Mat> frames;
  for (int i = 0; i < kFrames; ++i) {
    char name[64];
    std::snprintf(name, sizeof name, "out/%s/frame_%05d.png", L::kStrainPngFramesDir, i);
    frames.push_back(cv::imread(dir / name));
    ASSERT_FALSE(frames.back().empty()) << name;
    ASSERT_EQ(frames.back().size(), renderer.canvas_size());
  }
  for (int panel = 0; panel < 2; ++panel) {
    const cv::Rect bar = renderer.ColourBarRect(panel);
    for (int i = 1; i < kFrames; ++i) {
      EXPECT_EQ(cv::norm(frames[0](bar), frames[i](bar), cv::NORM_INF), 0.0)
          << "panel " << panel << " frame " << i;
    }
  }
  // The fields themselves differ (the comparison above is not of identical frames).
  const cv::Rect field(0, 0, renderer.ColourBarRect(0).x, renderer.canvas_size().height);
  EXPECT_GT(cv::norm(frames[0](field), frames[kFrames - 1](field), cv::NORM_INF), 0.0);
}

TEST(StrainFigures, WithoutTeOnlyTheLastFrameIsDrawn) {
  ScratchDir dir("strain");
  StrainParts parts;
  parts.t_e = false;
  WriteStrainResults(dir / "results.h5", parts);
  RenderResultsOptions o = FastOptions(dir / "out");
  o.animation = false;
  const auto s = RenderResults(dir / "results.h5", o);
  EXPECT_TRUE(IsPngOfSize(dir / (std::string("out/") + L::kStrainEndPng), 320, 120));
  EXPECT_FALSE(std::filesystem::exists(dir / (std::string("out/") + L::kStrainTePng)));
  EXPECT_NE(s.FullReport().find(std::string(L::kStrainTePng) + ": no t_e"), std::string::npos)
      << s.FullReport();
}

// `impactdic render` of an existing run folder draws them too.
TEST(StrainFiguresCli, RenderDrawsTheStrain) {
  ScratchDir dir("strain_cli");
  WriteStrainResults(dir / "results.h5", {});
  const CliResult r = RunCli("render " + (dir / "results.h5") + " --no-figures --codec mjpg");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(IsPngOfSize(dir / L::kStrainTePng, 320, 120)) << r.output;
  EXPECT_TRUE(IsPngOfSize(dir / L::kStrainEndPng, 320, 120)) << r.output;
  EXPECT_EQ(CountVideoFrames(dir / L::kStrainAnimationAviName), std::size_t(kFrames)) << r.output;
}

}  // namespace
}  // namespace impactdic
