// Sequences: reference updating, accumulation, occlusion and determinism.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>

#include "dic_test_util.h"
#include "impactdic/dic/correlator.h"

namespace impactdic {
namespace {

using testing::Errors;
using testing::ErrorStats;
using testing::Scene;

std::vector<cv::Mat> RenderSequence(Scene& scene, const FieldSequence& seq) {
  std::vector<cv::Mat> images;
  for (int k = 0; k < seq.frames; ++k) images.push_back(scene.Render(seq.at(k), 1000 + k));
  return images;
}

TEST(Sequence, RigidMotionAutoKeepsTheReferenceIncrementalRandomWalks) {
  // 100 frames (99 increments of 0.2 px), 20 px in total at 30 degrees, noise sigma 2.
  Scene scene(160, 160, /*noise_sigma=*/2, /*seed=*/3, /*supersampling=*/2);
  const double total = 0.2 * 99;
  const FieldSequence seq =
      LinearSequence(Translation(total * std::cos(M_PI / 6), total * std::sin(M_PI / 6)), 100);
  const std::vector<cv::Mat> images = RenderSequence(scene, seq);
  DicOptions options;
  options.grid.step = 12;
  double rms[2] = {0, 0};
  int updates[2] = {0, 0};
  int k = 0;
  for (ReferenceUpdate mode : {ReferenceUpdate::kAuto, ReferenceUpdate::kIncremental}) {
    options.update.mode = mode;
    const DicResult r = CorrelateSequence(images, options);
    const ErrorStats e = Errors(r.positions, r.frames.back(), seq.at(99));
    // The subsets that are still inside the image after 20 px are tracked.
    EXPECT_GT(e.valid, 0.5 * r.positions.size());
    rms[k] = e.rms;
    updates[k] = r.summary.reference_updates;
    ++k;
  }
  EXPECT_EQ(updates[0], 0);   // Nothing decorrelates: auto keeps the first reference.
  EXPECT_EQ(updates[1], 99);  // Incremental updates at every frame.
  EXPECT_LE(rms[0], 0.02);
  // Random walk: 99 independent increments, each with the noise of one correlation.
  EXPECT_GT(rms[1], 2 * rms[0]);
}

TEST(Sequence, DarkBlockEnteringTheViewFailsOnlyTheSubsetsItCovers) {
  // The soil translates slowly; a dark rigid block (the pounder) slides in from the top, 8 px per
  // frame, in front of it.
  Scene scene(200, 200, /*noise_sigma=*/2, /*seed=*/9, /*supersampling=*/2);
  const int frames = 12;
  const FieldSequence seq = LinearSequence(Translation(0.9, 0.6), frames);
  std::vector<cv::Mat> images = RenderSequence(scene, seq);
  cv::RNG rng(5);
  for (int k = 1; k < frames; ++k) {
    const cv::Rect block(60, 0, 80, 8 * k);
    cv::Mat dark(block.size(), CV_8U);
    rng.fill(dark, cv::RNG::NORMAL, 20, 2);
    dark.copyTo(images[k](block));
  }
  DicOptions options;
  options.grid.step = 10;
  options.update.mode = ReferenceUpdate::kFixed;
  const DicResult r = CorrelateSequence(images, options);
  const int h = options.grid.subset_size / 2;
  for (int k = 1; k < frames; ++k) {
    const FrameResult& f = r.frames[k - 1];
    const cv::Rect block(60, 0, 80, 8 * k);
    const DisplacementField truth = seq.at(k);
    for (std::size_t i = 0; i < r.positions.size(); ++i) {
      const cv::Vec2d u = truth.u(r.positions[i].x, r.positions[i].y);
      const cv::Rect box(static_cast<int>(std::lround(r.positions[i].x + u[0])) - h,
                         static_cast<int>(std::lround(r.positions[i].y + u[1])) - h, 2 * h + 1,
                         2 * h + 1);
      const double covered = double((box & block).area()) / box.area();
      const bool valid = f.status[i] == SubsetStatus::kConverged;
      if (covered >= 0.25) {
        EXPECT_FALSE(valid) << "frame " << k << " subset " << i;
      }
      if (covered == 0) {
        EXPECT_TRUE(valid) << "frame " << k << " subset " << i;
      }
      if (valid) {
        EXPECT_NEAR(f.u_px[i], u[0], 0.05) << "frame " << k << " covered " << covered;
        EXPECT_NEAR(f.v_px[i], u[1], 0.05) << "frame " << k << " covered " << covered;
      }
    }
  }
}

TEST(Sequence, ResultsDoNotDependOnTheThreadCount) {
  Scene scene(200, 160, /*noise_sigma=*/2, /*seed=*/11, /*supersampling=*/2);
  const FieldSequence seq = LinearSequence(Sum({Rotation(0.02, 100, 80), Translation(3, -2)}), 5);
  const std::vector<cv::Mat> images = RenderSequence(scene, seq);
  DicOptions options;
  options.grid.step = 7;
  options.update.mode = ReferenceUpdate::kEveryN;
  options.update.every_n = 2;
  DicResult one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = CorrelateSequence(images, options);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = CorrelateSequence(images, options);
  }
  ASSERT_EQ(one.frames.size(), two.frames.size());
  EXPECT_GT(one.summary.valid_fraction, 0.8);
  for (std::size_t k = 0; k < one.frames.size(); ++k) {
    const FrameResult& a = one.frames[k];
    const FrameResult& b = two.frames[k];
    const std::size_t n = a.u_px.size();
    // Bitwise equality (NaNs included).
    EXPECT_EQ(std::memcmp(a.u_px.data(), b.u_px.data(), n * sizeof(double)), 0) << k;
    EXPECT_EQ(std::memcmp(a.v_px.data(), b.v_px.data(), n * sizeof(double)), 0) << k;
    EXPECT_EQ(std::memcmp(a.zncc.data(), b.zncc.data(), n * sizeof(float)), 0) << k;
    EXPECT_EQ(a.iterations, b.iterations) << k;
    EXPECT_EQ(a.status, b.status) << k;
  }
}

}  // namespace
}  // namespace impactdic
