// Random walk of the reference-update policies on a long sequence, under GeoPIV-RG's scheme names
// (docs/dic.md, "GeoPIV-RG's analysis schemes"): per scheme, the reference
// updates, the RMS error of the accumulated displacement at frames 25, 50, 100 and the last, the
// growth exponent of that error with the frame number (slope of log RMS against log k over frames
// 10..last: 0.5 for a random walk), the lowest fraction of subsets converged in a frame, and the
// run time of the correlation.
//
// The sequences are those of tests/dic/geopiv_schemes_test.cc: a speckle image (blob sigma 2 px,
// 240 x 160 px by default); frame k has k/(frames-1) of the final field, a drift (default (20, -5)
// px: 0.1 px per frame over 201 frames) plus a settlement-like vertical compression (3 % at the
// top, decaying over 80 px: 2.1 px at the top); Gaussian noise sigma 2 grey levels, a new
// realisation per image (seeded), 8-bit. --tone T: the tone curve also steepens, I -> I^(1 + T k /
// (frames - 1)) on the normalised intensity (the texture darkens non-linearly, as wetting sand
// does, the speckle stays in place), so the correlation with the first image decays while
// consecutive images still correlate. Subset 25, step 10, bicubic, affine, no uncertainty limit.
//
//   reference_update_benchmark [--frames N] [--size WxH] [--drift U,V] [--tone T] [--threads N]
//                              [--schemes A,B,...] [--realisations R]
//
// Defaults: 201 frames, 240x160, drift 20,-5, tone 0, 1 thread, the schemes sequential, every:10,
// leapfrog, preconditioned, 1 realisation (R > 1: RMS over R noise realisations pooled, time the
// mean). The commands of the tables in docs/dic.md are written there.
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <opencv2/core.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/timer.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/dic/options.h"
#include "impactdic/synth/fields.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {
namespace {

struct Config {
  int width = 240, height = 160;
  double drift_u = 20, drift_v = -5;
  int frames = 201;
  std::vector<double> tones = {0};
  int threads = 1;
  int realisations = 1;
  std::vector<std::string> schemes = {"sequential", "every:10", "leapfrog", "preconditioned"};
};

DisplacementSequence Fields(const Config& c) {
  return LinearSequence(Sum({Translation(c.drift_u, c.drift_v),
                             ExponentialCompression(/*surface_strain=*/0.03,
                                                    /*decay_length_px=*/80, /*y_surface_px=*/0,
                                                    /*y_fixed_px=*/c.height)}),
                        c.frames);
}

std::vector<cv::Mat> Images(const Config& c, const DisplacementSequence& fields, double tone,
                            std::uint64_t noise_seed) {
  SpeckleOptions speckle;
  speckle.blob_radius_px = 2.0;
  speckle.seed = 21;
  const SpecklePattern pattern(speckle, c.width, c.height);
  RenderOptions render;
  render.supersampling = 2;
  render.bits = 16;  // Noise-free; the tone curve, the noise and 8-bit rounding follow.
  cv::RNG rng(noise_seed);
  std::vector<cv::Mat> images;
  for (int k = 0; k < fields.frames; ++k) {
    cv::Mat image;
    RenderImage(pattern, c.width, c.height, fields.at(k), render)
        .convertTo(image, CV_32F, 1.0 / 65535);
    cv::pow(image, 1 + tone * k / (fields.frames - 1), image);
    cv::Mat noise(image.size(), CV_32F);
    rng.fill(noise, cv::RNG::NORMAL, 0, 2);
    cv::Mat image8;
    cv::Mat(255 * image + noise).convertTo(image8, CV_8U);  // Rounds and saturates.
    images.push_back(image8);
  }
  return images;
}

struct Row {
  std::vector<double> sum_sq;  // Per frame: sum of squared errors over converged subsets.
  std::vector<long long> count;
  double min_valid = 1;
  int updates = 0;
  int subsets = 0;
  double seconds = 0;
};

void Accumulate(const DicResult& r, const DisplacementSequence& fields, Row* row) {
  for (const FrameResult& f : r.frames) {
    const DisplacementField truth = fields.at(f.frame);
    long long valid = 0;
    for (std::size_t i = 0; i < r.positions.size(); ++i) {
      if (f.status[i] != SubsetStatus::kConverged) continue;
      const cv::Vec2d u = truth.u(r.positions[i].x, r.positions[i].y);
      const double du = f.u_px[i] - u[0], dv = f.v_px[i] - u[1];
      row->sum_sq[f.frame] += du * du + dv * dv;
      ++row->count[f.frame];
      ++valid;
    }
    row->min_valid = std::min(row->min_valid, double(valid) / r.positions.size());
  }
}

double Rms(const Row& row, int k) {
  return row.count[k] ? std::sqrt(row.sum_sq[k] / row.count[k]) : NAN;
}

double GrowthExponent(const Row& row, int frames) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (int k = 10; k < frames; ++k) {
    const double rms = Rms(row, k);
    if (!(rms > 0)) continue;
    const double x = std::log(k), y = std::log(rms);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    ++n;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

void Table(const Config& c, double tone) {
  const DisplacementSequence fields = Fields(c);
  std::vector<std::vector<cv::Mat>> sets;
  sets.reserve(c.realisations);
  for (int r = 0; r < c.realisations; ++r) sets.push_back(Images(c, fields, tone, 2021 + r));
  const int last = c.frames - 1;
  std::printf(
      "\n%d frames, tone %.1f, %d realisation(s), %d thread(s)\n\n| scheme | reference updates | "
      "RMS error at frame 25 / 50 / 100 / %d [px] | growth exponent | min valid | time [s] |\n"
      "|---|---|---|---|---|---|\n",
      c.frames, tone, c.realisations, c.threads, last);
  int subsets = 0;
  for (const std::string& scheme : c.schemes) {
    DicOptions options;
    options.grid.step = 10;
    options.icgn.max_uncertainty_px = 0;
    options.update.policy = scheme;
    options.Check();
    Row row;
    row.sum_sq.assign(c.frames, 0);
    row.count.assign(c.frames, 0);
    for (const auto& images : sets) {
      WallTimer timer;
      const DicResult r = CorrelateSequence(images, options);
      row.seconds += timer.ElapsedSeconds() / sets.size();
      row.updates = r.summary.reference_updates;
      row.subsets = r.summary.subsets;
      Accumulate(r, fields, &row);
    }
    std::printf("| `%s` | %d | %.4f / %.4f / %.4f / %.4f | %.2f | %.1f %% | %.2f |\n",
                scheme.c_str(), row.updates, Rms(row, std::min(25, last)),
                Rms(row, std::min(50, last)), Rms(row, std::min(100, last)), Rms(row, last),
                GrowthExponent(row, c.frames), 100 * row.min_valid, row.seconds);
    subsets = row.subsets;
    std::fflush(stdout);
  }
  std::printf("\n%d subsets (subset 25, step 10)\n", subsets);
}

std::vector<std::string> Split(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, ',')) parts.push_back(part);
  return parts;
}

}  // namespace
}  // namespace impactdic

int main(int argc, char** argv) {
  using namespace impactdic;
  Config c;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const char* next = i + 1 < argc ? argv[i + 1] : nullptr;
    if (a == "--frames" && next) {
      c.frames = std::atoi(argv[++i]);
    } else if (a == "--tone" && next) {
      c.tones = {std::atof(argv[++i])};
    } else if (a == "--threads" && next) {
      c.threads = std::atoi(argv[++i]);
    } else if (a == "--realisations" && next) {
      c.realisations = std::atoi(argv[++i]);
    } else if (a == "--size" && next) {
      std::sscanf(argv[++i], "%dx%d", &c.width, &c.height);
    } else if (a == "--drift" && next) {
      std::sscanf(argv[++i], "%lf,%lf", &c.drift_u, &c.drift_v);
    } else if (a == "--schemes" && next) {
      c.schemes = Split(argv[++i]);
    } else {
      std::fprintf(stderr,
                   "usage: reference_update_benchmark [--frames N] [--size WxH] [--drift U,V] "
                   "[--tone T] [--threads N] [--schemes A,B,...] [--realisations R]\n");
      return 2;
    }
  }
  if (c.frames < 12 || c.threads < 1 || c.realisations < 1) {
    std::fprintf(stderr, "--frames >= 12, --threads >= 1, --realisations >= 1\n");
    return 2;
  }
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, c.threads);
  try {
    for (double tone : c.tones) Table(c, tone);
  } catch (const Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
