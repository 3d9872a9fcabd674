// Realistic synthetic footage (synth/realistic.h): the spec, the exactness of the rendering, the
// kinematics and the truth flags.
#include "impactdic/synth/realistic.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "impactdic/core/error.h"
#include "impactdic/io/hdf5_store.h"

namespace impactdic {
namespace {

RealisticSceneSpec Small() {
  RealisticSceneSpec spec;
  spec.width = 160;
  spec.height = 120;
  spec.supersampling = 2;
  spec.blur_samples = 2;
  return spec;
}

TEST(RealisticScene, RigidTranslationOfTheTextureIsExact) {
  // With no motion the sand at a reference pixel is the texture at that material point; a frame
  // is therefore an exact function of the field: frame 0 rendered twice is identical, and the
  // noise-free sand pixel equals the integrated texture times the light.
  RealisticSceneSpec spec = Small();
  spec.penetration_px_per_frame = 0;
  spec.glare_level = 0;
  spec.light_falloff = 0;
  spec.light_drift_per_frame = 0;
  spec.supersampling = 1;
  spec.blur_samples = 1;
  const RealisticScene scene(spec);
  const cv::Mat a = scene.RenderFrame(0, /*with_noise=*/false);
  const cv::Mat b = scene.RenderFrame(1, /*with_noise=*/false);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0);
  for (int r = 60; r < 120; r += 7) {
    for (int c = 3; c < 40; c += 5) {
      EXPECT_EQ(a.at<std::uint8_t>(r, c), std::round(255 * scene.SandIntensity(c, r)))
          << r << "," << c;
    }
  }
}

TEST(RealisticScene, TextureIsGrainyWithVariedBrightness) {
  const RealisticScene scene(Small());
  cv::Mat t(80, 80, CV_64F);
  for (int r = 0; r < 80; ++r)
    for (int c = 0; c < 80; ++c) t.at<double>(r, c) = scene.SandIntensity(c + 40, r + 60);
  double lo, hi;
  cv::minMaxLoc(t, &lo, &hi);
  cv::Scalar mean, sd;
  cv::meanStdDev(t, mean, sd);
  EXPECT_LT(lo, 0.3);  // Dark minerals and matrix.
  EXPECT_GT(hi, 0.9);  // Lit side of light grains.
  EXPECT_GT(sd[0], 0.1);
}

TEST(RealisticScene, KinematicsHaveCoreShearBandAndHeave) {
  const RealisticScene scene(Small());
  const double t = 1 / scene.spec().fps;  // Penetration V = 2 px.
  ASSERT_NEAR(scene.Penetration(t), 2, 1e-12);
  const double x0 = scene.axis_px(), y0 = scene.surface_px(), b = scene.half_width_px();
  // Under the pounder the surface moves with it.
  EXPECT_NEAR(scene.SoilDisplacement(x0, y0 + 0.1, t)[1], 2, 1e-3);
  // Across the shear band (w = 0.5 px) the vertical displacement changes by > 2 px within 4 px,
  // the horizontal one stays small (a slip, no opening).
  const cv::Vec2d in = scene.SoilDisplacement(x0 + b - 2, y0 + 5, t);
  const cv::Vec2d out = scene.SoilDisplacement(x0 + b + 2, y0 + 5, t);
  EXPECT_GT(in[1] - out[1], 2.0);
  EXPECT_LT(std::abs(in[0] - out[0]), 0.1);
  // Heave beside the pounder: the surface rises.
  EXPECT_LT(scene.SoilDisplacement(x0 + b + 3, y0, t)[1], -0.3);
  // Far away nothing moves.
  EXPECT_LT(cv::norm(scene.SoilDisplacement(5, 115, t)), 0.05);
}

TEST(RealisticScene, TruthFlagsStraddlingSubsets) {
  const RealisticScene scene(Small());
  const double x0 = scene.axis_px(), y0 = scene.surface_px(), b = scene.half_width_px();
  const std::vector<cv::Point2d> points = {{x0 + b, y0 + 20},       // On the band.
                                           {x0 + b + 25, y0 + 25},  // Beside it, in the sand.
                                           {x0, y0},                // On the pounder bottom.
                                           {x0 - b - 25, y0 + 40}};
  const RealisticTruth t = scene.Truth(points, 1, 10);
  EXPECT_TRUE(t.straddles_shear_band[0]);
  EXPECT_FALSE(t.straddles_shear_band[1]);
  EXPECT_FALSE(t.straddles_edge[1]);
  EXPECT_TRUE(t.straddles_edge[2]);
  EXPECT_FALSE(t.Flagged()[3]);
  // Truth is the displacement since frame 0 (a material point under the moving field).
  EXPECT_LT(t.v_px[1], 0);  // Heave.
}

TEST(RealisticScene, SpecKeysAreCheckedWithTheirPath) {
  const RealisticSceneSpec spec =
      ParseRealisticSceneSpec("realistic: {width: 200, jpeg_quality: 75}\n", "spec.yaml");
  EXPECT_EQ(spec.width, 200);
  EXPECT_EQ(spec.jpeg_quality, 75);
  try {
    ParseRealisticSceneSpec("realistic: {jpeg_quality: 101}\n", "spec.yaml");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("realistic.jpeg_quality"), std::string::npos) << e.what();
  }
  try {
    ParseRealisticSceneSpec("realistic: {jpg_quality: 50}\n", "spec.yaml");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("jpeg_quality"), std::string::npos) << e.what();
  }
  // The written spec reads back to the same values.
  RealisticSceneSpec other;
  other.glare_x = 0.25;
  other.seed = 9;
  const RealisticSceneSpec back =
      ParseRealisticSceneSpec(RealisticSceneSpecToYaml(other), "written.yaml");
  EXPECT_EQ(back.glare_x, 0.25);
  EXPECT_EQ(back.seed, 9u);
}

TEST(RealisticScene, WritesJpegFramesAndTruth) {
  RealisticSceneSpec spec = Small();
  spec.frames = 2;
  spec.jpeg_quality = 60;
  const RealisticScene scene(spec);
  const auto dir = std::filesystem::path(::testing::TempDir()) / "realistic_write";
  std::filesystem::remove_all(dir);
  const RealisticSceneReport report = WriteRealisticScene(scene, dir.string());
  const cv::Mat jpeg =
      cv::imread((dir / "frames" / "frame_0001.jpg").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(jpeg.empty());
  const cv::Mat exact = scene.RenderFrame(1);
  const double diff = cv::norm(jpeg, exact, cv::NORM_L2) / std::sqrt(jpeg.total());
  EXPECT_GT(diff, 1.0);   // Lossy at quality 60...
  EXPECT_LT(diff, 20.0);  // ...but the same picture.
  H5Reader in(report.truth_h5);
  Dims dims;
  const std::vector<double> v = in.ReadDouble("truth/v_px", &dims);
  ASSERT_EQ(dims.size(), 3u);
  EXPECT_EQ(dims[0], 2u);
  int cols = 0, rows = 0;
  scene.GridPoints(&cols, &rows);
  EXPECT_EQ(dims[1], static_cast<std::size_t>(rows));
  EXPECT_EQ(dims[2], static_cast<std::size_t>(cols));
  EXPECT_TRUE(in.Exists("truth/straddles_shear_band"));
}

}  // namespace
}  // namespace impactdic
