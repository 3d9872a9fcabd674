// Speed of the calibration and preprocessing stages:
// - undistortion of a full camera frame (1920x1440, 8- and 16-bit, bicubic and bilinear) with the
//   precomputed maps, and the map setup itself (once per sequence);
// - the whole preprocessing chain (undistort -> Gaussian 5x5 -> CLAHE 8x8) per frame;
// - rendering one 640x480 checkerboard view and calibrating from 12 of them.
//
//   calib_benchmark [benchmark flags]
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/calib/calibration.h"
#include "impactdic/calib/undistort.h"
#include "impactdic/core/log.h"
#include "impactdic/preprocess/preprocess.h"
#include "impactdic/synth/checkerboard.h"

namespace impactdic {
namespace {

// The sample lens scaled to the paper's camera (1920x1440).
CameraCalibration FullFrameCalibration() {
  const SynthCamera lens = SampleCamera();
  CameraCalibration c;
  c.image_width = 1920;
  c.image_height = 1440;
  c.fx = lens.fx * 3;
  c.fy = lens.fy * 3;
  c.cx = lens.cx * 3 + 1;
  c.cy = lens.cy * 3 + 1;
  c.dist = lens.dist;
  return c;
}

cv::Mat Frame(int depth) {
  cv::Mat frame(1440, 1920, depth);
  cv::RNG rng(3);
  rng.fill(frame, cv::RNG::UNIFORM, 0, depth == CV_8U ? 256 : 65536);
  return frame;
}

void BM_UndistortSetup(benchmark::State& state) {
  SetLogLevel(LogLevel::kWarning);
  const CameraCalibration c = FullFrameCalibration();
  for (auto _ : state) benchmark::DoNotOptimize(Undistorter(c, UndistortOptions{}).active());
}
BENCHMARK(BM_UndistortSetup)->Unit(benchmark::kMillisecond);

// Arguments: bit depth (8/16), interpolation (0 bilinear, 1 bicubic).
void BM_UndistortFrame(benchmark::State& state) {
  SetLogLevel(LogLevel::kWarning);
  UndistortOptions options;
  options.interpolation =
      state.range(1) ? UndistortInterpolation::kBicubic : UndistortInterpolation::kBilinear;
  const Undistorter undistort(FullFrameCalibration(), options);
  const cv::Mat frame = Frame(state.range(0) == 8 ? CV_8U : CV_16U);
  for (auto _ : state) benchmark::DoNotOptimize(undistort.Apply(frame).data);
}
BENCHMARK(BM_UndistortFrame)
    ->Args({8, 1})
    ->Args({16, 1})
    ->Args({8, 0})
    ->Unit(benchmark::kMillisecond);

void BM_PreprocessChain(benchmark::State& state) {
  SetLogLevel(LogLevel::kWarning);
  const CameraCalibration c = FullFrameCalibration();
  PreprocessOptions options;
  options.gaussian.mode = GaussianMode::kOn;
  options.clahe.enabled = true;
  Preprocessor pre(options, &c, c.ImageSize());
  const cv::Mat frame = Frame(state.range(0) == 8 ? CV_8U : CV_16U);
  for (auto _ : state) benchmark::DoNotOptimize(pre.Apply(frame).data);
}
BENCHMARK(BM_PreprocessChain)->Arg(8)->Arg(16)->Unit(benchmark::kMillisecond);

void BM_RenderCheckerboardView(benchmark::State& state) {
  const SynthCamera camera = SampleCamera();
  const CheckerboardSpec board;
  const BoardPose pose = CalibrationPoses(camera, board, 1, /*seed=*/1)[0];
  for (auto _ : state)
    benchmark::DoNotOptimize(
        RenderCheckerboard(camera, board, pose, CheckerboardRenderOptions{}).data);
}
BENCHMARK(BM_RenderCheckerboardView)->Unit(benchmark::kMillisecond);

void BM_Calibrate12Views(benchmark::State& state) {
  SetLogLevel(LogLevel::kWarning);
  const SynthCamera camera = SampleCamera();
  const CheckerboardSpec board;
  std::vector<cv::Mat> views;
  for (const BoardPose& pose : CalibrationPoses(camera, board, 12, /*seed=*/7))
    views.push_back(RenderCheckerboard(camera, board, pose, CheckerboardRenderOptions{}));
  CalibrationOptions options;
  for (auto _ : state) benchmark::DoNotOptimize(CalibrateCamera(views, {}, options).rms_px);
}
BENCHMARK(BM_Calibrate12Views)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace impactdic

BENCHMARK_MAIN();
