// Sub-pixel bias of the correlation engine on an analogue of DIC Challenge 1.0 Sample 3 (the
// analysis is in docs/dic_accuracy.md, "Sub-pixel bias").
//
// The analogue: one speckle image (`sharp`: painted-style dots with sharp edges, synth
// SharpSpeckle; `blob`: the smooth Gaussian-blob speckle of the tests), translated in x by
// 0.0, 0.1, ..., 1.0 px by an exact band-limited (Fourier) shift (synth FourierShift), scaled to
// grey levels [kDark, kBright], with Gaussian noise (sigma chosen so that the noise limit at
// subset 25 is --target-sd px, or given by --noise) and rounded to 8 bits, each image with its own
// noise. Every image is correlated against the unshifted one (pairs mode, subset 25, step 10) with
// the bicubic and the biquintic B-spline, without and with a Gaussian pre-filter of both images
// (preprocess Gaussian blur, as `correlate --gaussian` and the scene's preprocess.gaussian.*
// apply it). Per shift it prints the bias (mean error) and sd of u over the subsets and the noise
// limit sqrt(2) sigma / sqrt(sum over the subset of (dI/dx)^2) of the noise-free shifted image.
//
//   dic_bias_benchmark [--pattern sharp|blob] [--dot-radius PX] [--psf SIGMA] [--size N]
//                      [--target-sd PX | --noise SIGMA] [--diagonal] [--realisations R]
//                      [--prefilter S1,S2,...] [--per-shift S1,S2,...] [--kernel K]
//                      [--threads N] [--experiments]
//
// --dot-radius: of the sharp dots (default 2 px); --psf: a Gaussian lens blur [px] of the
// noise-free pattern; --diagonal: shifts (0.1 k, 0.1 k) as in Sample 3 (default: in x only).
// --experiments runs the controlled experiments of the analysis instead (noise off / on, 8-bit
// rounding, the pre-filter with and without rounding its output) and a double-precision
// translation-only IC-GN (B-spline coefficients of the whole image, no guard band) with three
// reference gradients (B-spline, central difference, 4th-order difference) to separate precision,
// the B-spline boundary and the gradient source from the engine.
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/dic/bspline.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/dic/options.h"
#include "impactdic/preprocess/preprocess.h"
#include "impactdic/synth/fourier_shift.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {
namespace {

constexpr double kDark = 30, kBright = 220;  // Grey levels of the dots and the background.
constexpr int kShifts = 11;                  // 0.0 .. 1.0 px.
// --diagonal: shift k is (0.1 k, 0.1 k) px as in DIC Challenge Sample 3, else (0.1 k, 0).
bool g_diagonal = false;

struct Config {
  std::string pattern = "sharp";
  int size = 512;
  double target_sd = 0.005;
  double noise = -1;  // < 0: from target_sd.
  std::vector<double> prefilter = {0, 0.5, 0.6, 0.8, 1.0};
  std::vector<double> per_shift = {0, 0.8};  // Pre-filters whose per-shift tables are printed.
  int kernel = 5;
  int realisations = 2;
  bool experiments = false;
  double dot_radius = 2.0;  // SharpSpeckle dot radius [px].
  double psf = 0;           // Lens blur of the noise-free pattern (Gaussian sigma [px], 0: none).
};

// The noise-free pattern in grey levels (CV_64F).
cv::Mat BasePattern(const Config& c) {
  cv::Mat unit;
  if (c.pattern == "sharp") {
    unit = SharpSpeckle(c.size, c.size, c.dot_radius, /*seed=*/3);
  } else {
    SpeckleOptions speckle;
    speckle.seed = 3;
    speckle.blob_radius_px = 2.0;
    RenderOptions render;
    render.bits = 16;
    const SpecklePattern pattern(speckle, c.size, c.size);
    RenderImage(pattern, c.size, c.size, ZeroField(), render).convertTo(unit, CV_64F, 1 / 65535.0);
    cv::normalize(unit, unit, 0, 1, cv::NORM_MINMAX);
  }
  if (c.psf > 0) cv::GaussianBlur(unit, unit, cv::Size(), c.psf, c.psf, cv::BORDER_REFLECT_101);
  return unit * (kBright - kDark) + kDark;
}

// sum over the subset (side 2 half + 1) of (dI/dx)^2 for every subset centre (spline gradients).
std::vector<double> GradientEnergy(const cv::Mat& clean, const std::vector<cv::Point2d>& centres,
                                   int half) {
  BsplineImage spline;
  spline.Build(clean, Interpolation::kBicubic);
  cv::Mat gx, gy;
  spline.NodeGradients(&gx, &gy);
  std::vector<double> out;
  for (const cv::Point2d& p : centres) {
    double s = 0;
    for (int r = -half; r <= half; ++r)
      for (int k = -half; k <= half; ++k)
        s += std::pow(gx.at<float>(static_cast<int>(p.y) + r, static_cast<int>(p.x) + k), 2);
    out.push_back(s);
  }
  return out;
}

// sqrt(mean over the subsets of 2 sigma^2 / sum (dI/dx)^2).
double NoiseLimit(const std::vector<double>& energy, double sigma) {
  double v = 0;
  for (double e : energy) v += 2 * sigma * sigma / e / energy.size();
  return std::sqrt(v);
}

struct ShiftStats {
  double bias_u = 0, sd_u = 0, bias_v = 0;
  int valid = 0, total = 0;
};

ShiftStats Stats(const FrameResult& f, double shift) {
  ShiftStats s;
  std::vector<double> eu, ev;
  for (std::size_t i = 0; i < f.u_px.size(); ++i) {
    ++s.total;
    if (f.status[i] != SubsetStatus::kConverged) continue;
    eu.push_back(f.u_px[i] - shift);
    ev.push_back(f.v_px[i] - (g_diagonal ? shift : 0.0));
  }
  s.valid = static_cast<int>(eu.size());
  if (eu.empty()) return s;
  s.bias_u = std::accumulate(eu.begin(), eu.end(), 0.0) / eu.size();
  s.bias_v = std::accumulate(ev.begin(), ev.end(), 0.0) / ev.size();
  for (double e : eu)
    s.sd_u += (e - s.bias_u) * (e - s.bias_u) / std::max<double>(1, eu.size() - 1);
  s.sd_u = std::sqrt(s.sd_u);
  return s;
}

// The images of one noise realisation: [0] the reference, [k] shifted by 0.1 (k - 1) px... laid
// out as the correlator's pairs input: reference first, then shifts 0.0 .. 1.0.
struct Series {
  std::vector<cv::Mat> clean;  // Noise-free, not rounded (CV_64F), shift k at [k].
  double sigma = 0;
};

Series MakeSeries(const Config& c) {
  const cv::Mat base = BasePattern(c);
  Series s;
  for (int k = 0; k < kShifts; ++k)
    s.clean.push_back(FourierShift(base, 0.1 * k, g_diagonal ? 0.1 * k : 0.0));
  return s;
}

std::vector<cv::Mat> Noisy(const Series& s, double sigma, int realisation) {
  std::vector<cv::Mat> out;
  const std::uint64_t seed = 1000 * (realisation + 1);
  out.push_back(QuantiseWithNoise(s.clean[0], sigma, 8, seed));
  for (int k = 0; k < kShifts; ++k)
    out.push_back(QuantiseWithNoise(s.clean[k], sigma, 8, seed + 1 + k));
  return out;
}

std::vector<cv::Mat> Prefiltered(const std::vector<cv::Mat>& images, double sigma, int kernel) {
  if (sigma <= 0) return images;
  PreprocessOptions options;
  options.gaussian.mode = GaussianMode::kOn;
  options.gaussian.sigma_px = sigma;
  options.gaussian.kernel_size = kernel;
  Preprocessor pre(options, /*calibration=*/nullptr, images[0].size());
  std::vector<cv::Mat> out;
  for (const cv::Mat& m : images) out.push_back(pre.Apply(m));
  return out;
}

DicOptions PairOptions(Interpolation interp) {
  DicOptions o;
  o.mode = SequenceMode::kPairs;
  o.grid.subset_size = 25;
  o.grid.step = 10;
  o.icgn.interpolation = interp;
  o.icgn.max_uncertainty_px = 0;  // Report every converged subset.
  return o;
}

// Per-shift statistics pooled over the realisations (bias: mean of the means; sd: rms of the
// sds).
std::vector<ShiftStats> CorrelateSeries(const std::vector<std::vector<cv::Mat>>& sets,
                                        Interpolation interp) {
  std::vector<ShiftStats> pooled(kShifts);
  for (const auto& images : sets) {
    const DicResult r = CorrelateSequence(images, PairOptions(interp));
    if (r.summary.valid_fraction < 0.99)
      std::fprintf(stderr, "warning: %s\n", r.summary.FullReport().c_str());
    for (int k = 0; k < kShifts; ++k) {
      const ShiftStats s = Stats(r.frames[k], 0.1 * k);
      pooled[k].bias_u += s.bias_u / sets.size();
      pooled[k].bias_v += s.bias_v / sets.size();
      pooled[k].sd_u += s.sd_u * s.sd_u / sets.size();
      pooled[k].valid += s.valid;
      pooled[k].total += s.total;
    }
  }
  for (auto& s : pooled) s.sd_u = std::sqrt(s.sd_u);
  return pooled;
}

std::vector<cv::Point2d> Centres(const cv::Mat& image) {
  Correlator c(PairOptions(Interpolation::kBicubic));
  c.SetReference(image);
  return c.positions();
}

void PrintTable(const char* title, const std::vector<ShiftStats>& s,
                const std::vector<double>& limits) {
  std::printf("\n%s\n", title);
  std::printf(
      "| shift [px] | bias u [px] | sd u [px] | noise limit [px] | bias v [px] | valid |\n");
  std::printf("|---|---|---|---|---|---|\n");
  double max_bias = 0, sd = 0;
  for (int k = 0; k < kShifts; ++k) {
    std::printf("| %.1f | %+.4f | %.4f | %.4f | %+.4f | %d/%d |\n", 0.1 * k, s[k].bias_u, s[k].sd_u,
                limits[k], s[k].bias_v, s[k].valid, s[k].total);
    max_bias = std::max(max_bias, std::abs(s[k].bias_u));
    sd += s[k].sd_u / kShifts;
  }
  std::printf("max |bias u| %.4f px, mean sd u %.4f px\n", max_bias, sd);
}

double MaxBias(const std::vector<ShiftStats>& s) {
  double m = 0;
  for (const auto& x : s) m = std::max(m, std::abs(x.bias_u));
  return m;
}
double MeanSd(const std::vector<ShiftStats>& s) {
  double m = 0;
  for (const auto& x : s) m += x.sd_u / s.size();
  return m;
}

void Tables(const Config& c) {
  const Series series = MakeSeries(c);
  const std::vector<cv::Point2d> centres = Centres(series.clean[0]);
  std::vector<double> energy0 = GradientEnergy(series.clean[0], centres, 12);
  const double sigma =
      c.noise >= 0 ? c.noise : c.target_sd / NoiseLimit(energy0, 1.0);  // Limit is linear in sigma.
  std::vector<double> limits;
  for (int k = 0; k < kShifts; ++k)
    limits.push_back(NoiseLimit(GradientEnergy(series.clean[k], centres, 12), sigma));
  std::printf(
      "pattern %s (dot radius %.1f px, lens blur %.1f px), %dx%d px, grey levels "
      "%.0f..%.0f, noise sigma %.3f grey levels, %zu subsets x %d realisations, "
      "pre-filter kernel %d\n",
      c.pattern.c_str(), c.dot_radius, c.psf, c.size, c.size, kDark, kBright, sigma, centres.size(),
      c.realisations, c.kernel);
  std::vector<std::vector<cv::Mat>> noisy;
  for (int r = 0; r < c.realisations; ++r) noisy.push_back(Noisy(series, sigma, r));
  std::printf(
      "\n| pre-filter sigma [px] | bicubic max abs bias [px] | bicubic mean sd [px] | "
      "biquintic max abs bias [px] | biquintic mean sd [px] |\n|---|---|---|---|---|\n");
  for (double pf : c.prefilter) {
    std::vector<std::vector<cv::Mat>> sets;
    for (const auto& n : noisy) sets.push_back(Prefiltered(n, pf, c.kernel));
    const auto cubic = CorrelateSeries(sets, Interpolation::kBicubic);
    const auto quintic = CorrelateSeries(sets, Interpolation::kBiquintic);
    std::printf("| %.1f | %.4f | %.4f | %.4f | %.4f |\n", pf, MaxBias(cubic), MeanSd(cubic),
                MaxBias(quintic), MeanSd(quintic));
    std::fflush(stdout);
  }
  // The per-shift tables (recomputed: cheap next to making the images).
  for (double pf : c.per_shift) {
    std::vector<std::vector<cv::Mat>> sets;
    for (const auto& n : noisy) sets.push_back(Prefiltered(n, pf, c.kernel));
    for (Interpolation interp : {Interpolation::kBicubic, Interpolation::kBiquintic}) {
      char title[128];
      std::snprintf(title, sizeof(title),
                    "%s, pre-filter sigma %.1f px (kernel %d):", ToString(interp), pf, c.kernel);
      PrintTable(title, CorrelateSeries(sets, interp), limits);
    }
  }
}

// One row of the experiments table: max |bias u| and the bias at 0.3 and 0.7 px, both
// interpolators, and the mean sd.
void ExperimentRow(const char* name, const std::vector<std::vector<cv::Mat>>& sets) {
  std::printf("| %s |", name);
  for (Interpolation interp : {Interpolation::kBicubic, Interpolation::kBiquintic}) {
    const auto s = CorrelateSeries(sets, interp);
    std::printf(" %.4f (%+.4f, %+.4f) | %.4f |", MaxBias(s), s[3].bias_u, s[7].bias_u, MeanSd(s));
  }
  std::printf("\n");
  std::fflush(stdout);
}

// The images without 8-bit rounding: grey levels and noise times 257 in 16-bit images (a rounding
// step of 1/257 grey level). The engine takes float images too, but its contrast and featureless
// limits are relative to the data's full scale, which float images do not have.
constexpr double k16 = 257;
std::vector<cv::Mat> Fine(const Series& s, double sigma, int realisation) {
  std::vector<cv::Mat> out;
  const std::uint64_t seed = 5000 * (realisation + 1);
  out.push_back(QuantiseWithNoise(s.clean[0] * k16, sigma * k16, 16, seed));
  for (int k = 0; k < kShifts; ++k)
    out.push_back(QuantiseWithNoise(s.clean[k] * k16, sigma * k16, 16, seed + 1 + k));
  return out;
}

// The Gaussian pre-filter without rounding the blurred images to 8 bits (16-bit output).
std::vector<cv::Mat> FineBlur(const std::vector<cv::Mat>& images, double sigma, int kernel) {
  std::vector<cv::Mat> out;
  for (const cv::Mat& m : images) {
    cv::Mat f, b, o;
    m.convertTo(f, CV_32F, m.depth() == CV_8U ? k16 : 1.0);
    cv::GaussianBlur(f, b, cv::Size(kernel, kernel), sigma, sigma, cv::BORDER_REFLECT_101);
    b.convertTo(o, CV_16U);
    out.push_back(o);
  }
  return out;
}

// A double-precision, translation-only IC-GN with the ZNSSD criterion, written for the
// experiments only (the engine is affine, float): it separates precision and the source of the
// reference gradients from the engine. The deformed image is interpolated with BsplineImage
// (double arithmetic on its float coefficients).
enum class GradientSource { kSpline, kCentral, kFourthOrder };
const char* ToString(GradientSource g) {
  return g == GradientSource::kSpline    ? "B-spline derivative"
         : g == GradientSource::kCentral ? "central difference"
                                         : "4th-order difference";
}

// Mean error of u over the subsets (every second one of the engine's grid in x and y).
double ReferenceIcgnBias(const cv::Mat& ref8, const cv::Mat& def8,
                         const std::vector<cv::Point2d>& centres, double shift,
                         Interpolation interp, GradientSource source) {
  cv::Mat f;
  ref8.convertTo(f, CV_64F);
  BsplineImage ref_spline, def_spline;
  ref_spline.Build(ref8, interp);
  def_spline.Build(def8, interp);
  cv::Mat sgx, sgy;
  ref_spline.NodeGradients(&sgx, &sgy);
  auto gradient = [&](int x, int y, double* gx, double* gy) {
    const auto at = [&](int xx, int yy) { return f.at<double>(yy, xx); };
    switch (source) {
      case GradientSource::kSpline:
        *gx = sgx.at<float>(y, x);
        *gy = sgy.at<float>(y, x);
        break;
      case GradientSource::kCentral:
        *gx = (at(x + 1, y) - at(x - 1, y)) / 2;
        *gy = (at(x, y + 1) - at(x, y - 1)) / 2;
        break;
      case GradientSource::kFourthOrder:
        *gx = (-at(x + 2, y) + 8 * at(x + 1, y) - 8 * at(x - 1, y) + at(x - 2, y)) / 12;
        *gy = (-at(x, y + 2) + 8 * at(x, y + 1) - 8 * at(x, y - 1) + at(x, y - 2)) / 12;
        break;
    }
  };
  constexpr int h = 12;
  std::vector<double> errors(centres.size(), std::nan(""));
  tbb::parallel_for(std::size_t{0}, centres.size(), [&](std::size_t i) {
    const int cx = static_cast<int>(centres[i].x), cy = static_cast<int>(centres[i].y);
    if ((cx / 10) % 2 || (cy / 10) % 2) return;
    std::vector<double> fv, gxv, gyv;
    double h11 = 0, h12 = 0, h22 = 0, fm = 0;
    for (int y = cy - h; y <= cy + h; ++y) {
      for (int x = cx - h; x <= cx + h; ++x) {
        double gx = 0, gy = 0;
        gradient(x, y, &gx, &gy);
        fv.push_back(f.at<double>(y, x));
        gxv.push_back(gx);
        gyv.push_back(gy);
        h11 += gx * gx;
        h12 += gx * gy;
        h22 += gy * gy;
        fm += fv.back() / ((2 * h + 1) * (2 * h + 1));
      }
    }
    double fn = 0;
    for (double v : fv) fn += (v - fm) * (v - fm);
    fn = std::sqrt(fn);
    const double det = h11 * h22 - h12 * h12;
    double u = shift + 0.05, v = (g_diagonal ? shift : 0.0) + 0.05;
    std::vector<double> g(fv.size());
    for (int it = 0; it < 50; ++it) {
      double gm = 0;
      std::size_t k = 0;
      for (int y = cy - h; y <= cy + h; ++y)
        for (int x = cx - h; x <= cx + h; ++x) gm += (g[k++] = def_spline.Value(x + u, y + v));
      gm /= g.size();
      double gn = 0;
      for (double w : g) gn += (w - gm) * (w - gm);
      gn = std::sqrt(gn);
      double b1 = 0, b2 = 0;
      for (k = 0; k < g.size(); ++k) {
        const double r = (fn / gn) * (g[k] - gm) - (fv[k] - fm);
        b1 += gxv[k] * r;
        b2 += gyv[k] * r;
      }
      const double du = (h22 * b1 - h12 * b2) / det, dv = (h11 * b2 - h12 * b1) / det;
      u -= du;
      v -= dv;
      if (std::hypot(du, dv) < 1e-7) break;
    }
    errors[i] = u - shift;
  });
  double sum = 0;
  int n = 0;
  for (double e : errors) {
    if (std::isnan(e)) continue;
    sum += e;
    ++n;
  }
  return sum / std::max(n, 1);
}

// Max |bias| and the bias at 0.3 / 0.7 px of the reference IC-GN on noise-free 16-bit images.
void ReferenceIcgnRows(const Series& series, const std::vector<cv::Point2d>& centres) {
  const std::vector<cv::Mat> images = Fine(series, 0, 0);
  for (GradientSource source :
       {GradientSource::kSpline, GradientSource::kCentral, GradientSource::kFourthOrder}) {
    std::printf("| double IC-GN (translation), no noise, %s |", ToString(source));
    for (Interpolation interp : {Interpolation::kBicubic, Interpolation::kBiquintic}) {
      double max_bias = 0, b3 = 0, b7 = 0;
      for (int k = 1; k < kShifts - 1; ++k) {
        const double b =
            ReferenceIcgnBias(images[0], images[k + 1], centres, 0.1 * k, interp, source);
        max_bias = std::max(max_bias, std::abs(b));
        if (k == 3) b3 = b;
        if (k == 7) b7 = b;
      }
      std::printf(" %.4f (%+.4f, %+.4f) | - |", max_bias, b3, b7);
    }
    std::printf("\n");
    std::fflush(stdout);
  }
}

void Experiments(const Config& c) {
  const Series series = MakeSeries(c);
  const std::vector<cv::Point2d> centres = Centres(series.clean[0]);
  const double sigma =
      c.noise >= 0 ? c.noise
                   : c.target_sd / NoiseLimit(GradientEnergy(series.clean[0], centres, 12), 1.0);
  std::printf("pattern %s, %dx%d px, noise sigma %.3f grey levels, %d realisations\n",
              c.pattern.c_str(), c.size, c.size, sigma, c.realisations);
  std::printf(
      "\n| experiment | bicubic max abs bias (at 0.3, 0.7) [px] | bicubic sd [px] | "
      "biquintic max abs bias (at 0.3, 0.7) [px] | biquintic sd [px] |\n"
      "|---|---|---|---|---|\n");
  auto sets = [&](auto make) {
    std::vector<std::vector<cv::Mat>> out;
    for (int r = 0; r < c.realisations; ++r) out.push_back(make(r));
    return out;
  };
  ExperimentRow("no noise, no 8-bit rounding", sets([&](int) { return Fine(series, 0, 0); }));
  ReferenceIcgnRows(series, centres);
  ExperimentRow("8-bit rounding, no noise", sets([&](int r) { return Noisy(series, 0, r); }));
  ExperimentRow("noise, no 8-bit rounding", sets([&](int r) { return Fine(series, sigma, r); }));
  ExperimentRow("noise + 8-bit rounding", sets([&](int r) { return Noisy(series, sigma, r); }));
  ExperimentRow("noise x2 + 8-bit rounding",
                sets([&](int r) { return Noisy(series, 2 * sigma, r); }));
  for (double pf : {0.6, 0.8}) {
    char name[96];
    std::snprintf(name, sizeof(name), "no noise, no rounding, pre-filter %.1f", pf);
    ExperimentRow(name, sets([&](int) { return FineBlur(Fine(series, 0, 0), pf, c.kernel); }));
    std::snprintf(name, sizeof(name), "noise + 8-bit, pre-filter %.1f (8-bit out)", pf);
    ExperimentRow(name,
                  sets([&](int r) { return Prefiltered(Noisy(series, sigma, r), pf, c.kernel); }));
    std::snprintf(name, sizeof(name), "noise + 8-bit, pre-filter %.1f (16-bit out)", pf);
    ExperimentRow(name,
                  sets([&](int r) { return FineBlur(Noisy(series, sigma, r), pf, c.kernel); }));
  }
}

}  // namespace
}  // namespace impactdic

int main(int argc, char** argv) {
  using namespace impactdic;
  Config c;
  int threads = 2;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--pattern") {
      c.pattern = next();
    } else if (a == "--size") {
      c.size = std::stoi(next());
    } else if (a == "--target-sd") {
      c.target_sd = std::stod(next());
    } else if (a == "--noise") {
      c.noise = std::stod(next());
    } else if (a == "--prefilter") {
      c.prefilter.clear();
      std::stringstream ss(next());
      std::string item;
      while (std::getline(ss, item, ',')) c.prefilter.push_back(std::stod(item));
    } else if (a == "--per-shift") {
      c.per_shift.clear();
      std::stringstream ss(next());
      std::string item;
      while (std::getline(ss, item, ',')) c.per_shift.push_back(std::stod(item));
    } else if (a == "--kernel") {
      c.kernel = std::stoi(next());
    } else if (a == "--realisations") {
      c.realisations = std::stoi(next());
    } else if (a == "--threads") {
      threads = std::stoi(next());
    } else if (a == "--dot-radius") {
      c.dot_radius = std::stod(next());
    } else if (a == "--psf") {
      c.psf = std::stod(next());
    } else if (a == "--diagonal") {
      g_diagonal = true;
    } else if (a == "--experiments") {
      c.experiments = true;
    } else {
      std::fprintf(stderr, "unknown argument %s (see the comment at the top of the file)\n",
                   a.c_str());
      return 2;
    }
  }
  if (c.pattern != "sharp" && c.pattern != "blob") {
    std::fprintf(stderr, "--pattern: sharp or blob, not %s\n", c.pattern.c_str());
    return 2;
  }
  tbb::global_control control(tbb::global_control::max_allowed_parallelism,
                              static_cast<std::size_t>(threads));
  if (c.experiments) {
    Experiments(c);
  } else {
    Tables(c);
  }
  return 0;
}
