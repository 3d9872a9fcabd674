// Speed and accuracy of the correlation engine (docs/dic_speed.md).
//
// The case: a 1920x1440 synthetic speckle pair (u = 0.3, v = -0.7 px, noise sigma 2 grey levels,
// 8-bit), subset 25, step 10, bicubic, affine, 2 threads. Images are rendered once into a cache
// folder (PNG) and every measured run reads them from disk: "frame pair" times the whole job
// (load both images, reference precomputation, coefficients, initial guess, IC-GN); "sequence"
// times one more frame of a sequence (load + correlate), starting from the previous solution.
//
//   dic_benchmark [--threads N] [--cache DIR] [benchmark flags]
//   dic_benchmark --work-precision [--threads N] [--cache DIR] [--plot FILE.png]
//
// --work-precision prints bias, sd and run time for bicubic/biquintic x affine/quadratic x
// subset 21/25/31/41 on the pair, and plots error against time with gnuplot.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/core/timer.h"
#include "impactdic/dic/bspline.h"
#include "impactdic/dic/correlate_frames.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/dic/dic_io.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/frame_source.h"
#include "impactdic/io/image_io.h"
#include "impactdic/synth/fields.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 1920, kHeight = 1440, kSequenceFrames = 6;
constexpr double kU = 0.3, kV = -0.7;
std::string g_cache = "/tmp/impactdic_dic_bench";
int g_threads = 2;

std::string FramePath(int k) { return g_cache + "/frame_" + std::to_string(k) + ".png"; }

// Frame k is the pattern translated by k * (u, v), each with its own noise.
void EnsureImages() {
  fs::create_directories(g_cache);
  SpeckleOptions speckle;
  speckle.blob_radius_px = 2.0;
  SpecklePattern pattern(speckle, kWidth, kHeight);
  for (int k = 0; k < kSequenceFrames; ++k) {
    if (fs::exists(FramePath(k))) continue;
    RenderOptions render;
    render.noise_sigma = 2;
    render.noise_seed = 100 + k;
    std::fprintf(stderr, "rendering %s\n", FramePath(k).c_str());
    WriteImage(FramePath(k),
               RenderImage(pattern, kWidth, kHeight, Translation(k * kU, k * kV), render));
  }
}

struct Accuracy {
  double bias_u = 0, bias_v = 0, sd_u = 0, sd_v = 0;
};

Accuracy Measure(const FrameResult& f, double u, double v) {
  Accuracy a;
  int n = 0;
  for (std::size_t i = 0; i < f.u_px.size(); ++i) {
    if (f.status[i] != SubsetStatus::kConverged) continue;
    a.bias_u += f.u_px[i] - u;
    a.bias_v += f.v_px[i] - v;
    ++n;
  }
  a.bias_u /= std::max(n, 1);
  a.bias_v /= std::max(n, 1);
  for (std::size_t i = 0; i < f.u_px.size(); ++i) {
    if (f.status[i] != SubsetStatus::kConverged) continue;
    a.sd_u += std::pow(f.u_px[i] - u - a.bias_u, 2) / std::max(n - 1, 1);
    a.sd_v += std::pow(f.v_px[i] - v - a.bias_v, 2) / std::max(n - 1, 1);
  }
  a.sd_u = std::sqrt(a.sd_u);
  a.sd_v = std::sqrt(a.sd_v);
  return a;
}

DicOptions BenchOptions() {
  DicOptions o;
  o.grid.subset_size = 25;
  o.grid.step = 10;
  return o;
}

void SetCounters(benchmark::State& state, const DicSummary& s, const FrameResult& f, double u,
                 double v, double seconds) {
  const Accuracy a = Measure(f, u, v);
  state.counters["subsets"] = s.subsets;
  state.counters["subsets_per_s"] = s.subsets / seconds;
  state.counters["valid_pct"] = 100.0 * f.u_px.size() > 0 ? 100.0 * s.valid_fraction : 0;
  state.counters["iterations"] = s.mean_iterations;
  state.counters["bias_u"] = a.bias_u;
  state.counters["bias_v"] = a.bias_v;
  state.counters["sd_u"] = a.sd_u;
  state.counters["sd_v"] = a.sd_v;
  state.counters["t_coef"] = f.seconds_coefficients;
  state.counters["t_ref"] = f.seconds_reference;
  state.counters["t_init"] = f.seconds_initial_guess;
  state.counters["t_icgn"] = f.seconds_icgn;
}

// The whole job for a pair, including image loading, as `impactdic correlate` runs it
// (CorrelateFrames on the image files: the deformed image is decoded while the reference is
// precomputed).
void BM_FramePair(benchmark::State& state) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, g_threads);
  const DicOptions options = BenchOptions();
  double best = 1e300;
  for (auto _ : state) {
    WallTimer timer;
    const std::unique_ptr<FrameSource> pair = MakeImageFileSource({FramePath(0), FramePath(1)});
    const DicResult result = CorrelateFrames(*pair, options);
    const double seconds = timer.ElapsedSeconds();
    best = std::min(best, seconds);
    state.SetIterationTime(seconds);
    FrameResult timing = result.frames.front();
    timing.seconds_coefficients = result.summary.seconds_coefficients;
    timing.seconds_reference = result.summary.seconds_reference;
    SetCounters(state, result.summary, timing, kU, kV, seconds);
  }
  state.counters["best_s"] = best;
  state.counters["best_subsets_per_s"] = state.counters["subsets"] / best;
}

// One frame of a sequence (load + correlate), after the sequence has started. The next frame is
// decoded while the current one is correlated.
void BM_SequenceFrame(benchmark::State& state) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, g_threads);
  DicOptions options = BenchOptions();
  options.update.policy = "fixed";
  std::vector<std::string> paths;
  for (int k = 0; k < kSequenceFrames; ++k) paths.push_back(FramePath(k));
  double best = 1e300;
  for (auto _ : state) {
    state.PauseTiming();
    auto correlator = std::make_unique<Correlator>(options);
    correlator->SetReference(ReadGreyImage(paths[0]));
    correlator->Correlate(ReadGreyImage(paths[1]));
    correlator->Correlate(ReadGreyImage(paths[2]));
    state.ResumeTiming();
    WallTimer timer;
    FrameResult f;
    cv::Mat current = ReadGreyImage(paths[3]), next;
    int k = 3;
    for (; k < kSequenceFrames; ++k) {
      tbb::task_group prefetch;
      if (k + 1 < kSequenceFrames) prefetch.run([&] { next = ReadGreyImage(paths[k + 1]); });
      f = correlator->Correlate(current);
      prefetch.wait();
      current = next;
    }
    const double seconds = timer.ElapsedSeconds();
    const int frames = kSequenceFrames - 3;
    best = std::min(best, seconds / frames);
    state.SetIterationTime(seconds / frames);
    SetCounters(state, correlator->summary(), f, (k - 1) * kU, (k - 1) * kV, seconds / frames);
  }
  state.counters["best_s"] = best;
  state.counters["best_subsets_per_s"] = state.counters["subsets"] / best;
}

void WorkPrecision(const std::string& plot) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, g_threads);
  const cv::Mat ref = ReadGreyImage(FramePath(0));
  const cv::Mat def = ReadGreyImage(FramePath(1));
  const std::string data = g_cache + "/work_precision.dat";
  FILE* out = std::fopen(data.c_str(), "w");
  std::printf("%-10s %-9s %6s %9s %9s %9s %9s %8s %9s %12s\n", "interp", "shape", "subset",
              "bias_u", "bias_v", "sd_u", "sd_v", "time_s", "iter", "subsets/s");
  for (Interpolation interp : {Interpolation::kBicubic, Interpolation::kBiquintic}) {
    for (ShapeFunction shape : {ShapeFunction::kAffine, ShapeFunction::kQuadratic}) {
      for (int subset : {21, 25, 31, 41}) {
        DicOptions o = BenchOptions();
        o.grid.subset_size = subset;
        o.icgn.interpolation = interp;
        o.icgn.shape = shape;
        WallTimer timer;
        Correlator c(o);
        c.SetReference(ref);
        const FrameResult f = c.Correlate(def);
        const double t = timer.ElapsedSeconds();
        const Accuracy a = Measure(f, kU, kV);
        std::printf("%-10s %-9s %6d %9.5f %9.5f %9.5f %9.5f %8.3f %9.2f %12.0f\n", ToString(interp),
                    ToString(shape), subset, a.bias_u, a.bias_v, a.sd_u, a.sd_v, t,
                    c.summary().mean_iterations, c.subsets() / t);
        if (out)
          std::fprintf(out, "%s-%s %d %.6f %.6f %.6f\n", ToString(interp), ToString(shape), subset,
                       t, std::hypot(a.sd_u, a.sd_v), std::hypot(a.bias_u, a.bias_v));
      }
      if (out) std::fprintf(out, "\n\n");
    }
  }
  if (out) std::fclose(out);
  if (plot.empty()) return;
  const std::string temp = plot + ".tmp.png";
  const std::string script =
      "set terminal pngcairo size 900,600; set output '" + temp +
      "'; set logscale y; set xlabel 'run time [s] (1920x1440, step 10, " +
      std::to_string(g_threads) +
      " threads)'; set ylabel 'random error sqrt(sd_u^2+sd_v^2) [px]'; set key outside; "
      "titles='bicubic-affine bicubic-quadratic biquintic-affine biquintic-quadratic'; "
      "plot for [i=0:3] '" +
      data +
      "' index i using 3:4 with linespoints title word(titles, i+1), for [i=0:3] '' index i "
      "using 3:4:(sprintf('%d',\\$2)) with labels offset 1,0.5 notitle";
  const std::string command = "gnuplot -e \"" + script + "\" 2>/dev/null";
  if (std::system(command.c_str()) == 0 && fs::exists(temp)) {
    fs::rename(temp, plot);
    std::printf("plot: %s\n", plot.c_str());
  } else {
    std::fprintf(stderr, "gnuplot failed; data in %s\n", data.c_str());
  }
}

}  // namespace
}  // namespace impactdic

int main(int argc, char** argv) {
  using namespace impactdic;
  bool work_precision = false;
  std::string plot;
  std::vector<char*> rest = {argv[0]};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--work-precision") {
      work_precision = true;
    } else if (a == "--threads" && i + 1 < argc) {
      g_threads = std::atoi(argv[++i]);
    } else if (a == "--cache" && i + 1 < argc) {
      g_cache = argv[++i];
    } else if (a == "--plot" && i + 1 < argc) {
      plot = argv[++i];
    } else {
      rest.push_back(argv[i]);
    }
  }
  EnsureImages();
  if (work_precision) {
    WorkPrecision(plot);
    return 0;
  }
  benchmark::RegisterBenchmark("dic/frame_pair_1920x1440", BM_FramePair)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond)
      ->Iterations(5);
  benchmark::RegisterBenchmark("dic/sequence_frame_1920x1440", BM_SequenceFrame)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond)
      ->Iterations(3);
  int n = static_cast<int>(rest.size());
  benchmark::Initialize(&n, rest.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
