// Shared helpers of the render tests: scratch folders, PNG checks and synthetic velocity fields.
#ifndef IMPACTDIC_TESTS_RENDER_TEST_UTIL_H_
#define IMPACTDIC_TESTS_RENDER_TEST_UTIL_H_

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <string>
#include <system_error>
#include <vector>

#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/render/velocity_field.h"

namespace impactdic::test {

// A fresh, empty folder under the system temp folder, removed at the end of the test.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& name) {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            ("impactdic_render_" + name + "_" + (info ? info->name() : "x") + "_" +
             std::to_string(getpid()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string operator/(const std::string& name) const { return (path_ / name).string(); }
  const std::filesystem::path& path() const { return path_; }
  // Names of all entries (hidden temporaries included).
  std::vector<std::string> Entries() const {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(path_)) {
      names.push_back(e.path().filename().string());
    }
    return names;
  }

 private:
  std::filesystem::path path_;
};

// The PNG at `path` decodes and is at least min_w x min_h.
inline ::testing::AssertionResult IsPngOfSize(const std::string& path, int min_w, int min_h) {
  static constexpr unsigned char kSig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return ::testing::AssertionFailure() << path << " does not exist";
  unsigned char head[8] = {};
  const std::size_t got = std::fread(head, 1, 8, f);
  std::fclose(f);
  if (got != 8 || std::memcmp(head, kSig, 8) != 0) {
    return ::testing::AssertionFailure() << path << " lacks the PNG signature";
  }
  const cv::Mat img = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (img.empty()) return ::testing::AssertionFailure() << path << " does not decode";
  if (img.cols < min_w || img.rows < min_h) {
    return ::testing::AssertionFailure() << path << " is " << img.cols << "x" << img.rows
                                         << ", expected >= " << min_w << "x" << min_h;
  }
  return ::testing::AssertionSuccess();
}

// A synthetic sequence: speckle frames (seeded), a regular grid of subsets with `step` px spacing
// inside the central part of the frame, and a velocity field (mm/s) that grows with the frame
// index and points down and outwards: v = (k * (x - cx) / w, k * 300) with k = frame + 1.
inline VelocityFieldSequence MakeSequence(int frames, int width, int height, int step,
                                          int depth = CV_8U, unsigned seed = 7) {
  VelocityFieldSequence seq;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  cv::Mat base(height, width, CV_32F);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) base.at<float>(y, x) = float(uni(rng));
  }
  for (int i = 0; i < frames; ++i) {
    cv::Mat frame;
    const double full = depth == CV_16U ? 4095.0 : depth == CV_32F ? 1.0 : 255.0;
    base.convertTo(frame, depth, 0.2 * full + 0 * i, 0.4 * full);
    seq.frames.push_back(frame);
    seq.time_ms.push_back(0.625 * i);
  }
  for (int y = height / 3; y < height - step / 2; y += step) {
    for (int x = width / 6; x < width - width / 6; x += step) {
      seq.x_px.push_back(x);
      seq.y_px.push_back(y);
    }
  }
  seq.num_subsets = seq.x_px.size();
  for (int i = 0; i < frames; ++i) {
    for (std::size_t s = 0; s < seq.num_subsets; ++s) {
      const double k = i + 1;
      seq.vx_mm_s.push_back(k * 200.0 * (seq.x_px[s] - width / 2.0) / width);
      seq.vy_mm_s.push_back(k * 30.0);
    }
  }
  seq.mm_per_px = 0.25;
  return seq;
}

// Writes the 8-bit frames of `seq` into a results file as `impactdic run` stores them
// (/frames/images, int32 grey values, bit_depth 8).
inline void WriteFrames(const VelocityFieldSequence& seq, H5Writer& out) {
  namespace L = results_layout;
  const int rows = seq.frames.at(0).rows, cols = seq.frames.at(0).cols;
  std::vector<std::int32_t> pixels;
  for (const auto& f : seq.frames) {
    for (int y = 0; y < rows; ++y) {
      for (int x = 0; x < cols; ++x) pixels.push_back(f.at<unsigned char>(y, x));
    }
  }
  out.Write(L::kFrameImages, pixels, {seq.frames.size(), std::size_t(rows), std::size_t(cols)},
            "grey value", "frames");
  out.SetAttribute(L::kFramesGroup, L::kBitDepthAttr, 8.0);
}

// The front in a space-time diagram (render/wave_figures.h): in each image row of the plot area
// (above the x axis: the row with the most dark pixels, the axis line; left of the colour bar:
// the right 15 % of the image) the leftmost pixel of at least half the colour scale downward
// (from the palette's #f4a582 to its top #b2182b; the red minus green test admits a legend's
// orange #D55E00 markers only where they blend into white), i.e. the arrival at that depth;
// *rows gets how many rows have one. `deepest_fraction` < 1 keeps only that deepest fraction of
// those rows (below a punched cone, where the soil is reached by the front, not pushed at the
// contact).
inline double FrontRankCorrelation(const std::string& png, int* rows,
                                   double deepest_fraction = 1.0) {
  const cv::Mat img = cv::imread(png, cv::IMREAD_COLOR);
  int axis_row = img.rows, most_dark = 0;
  for (int y = 0; y < img.rows; ++y) {
    int dark = 0;
    for (int x = 0; x < img.cols; ++x) {
      const cv::Vec3b p = img.at<cv::Vec3b>(y, x);
      dark += p[0] < 80 && p[1] < 80 && p[2] < 80;
    }
    if (dark > most_dark) most_dark = dark, axis_row = y;
  }
  std::vector<double> ys, xs;
  for (int y = 0; y < axis_row; ++y) {
    for (int x = 0; x < img.cols * 85 / 100; ++x) {
      const cv::Vec3b p = img.at<cv::Vec3b>(y, x);  // B, G, R.
      if (p[2] >= 170 && p[2] - p[1] >= 75 && p[0] >= 35) {
        ys.push_back(y);
        xs.push_back(x);
        break;
      }
    }
  }
  const auto skip = static_cast<std::ptrdiff_t>(
      std::lround(static_cast<double>(ys.size()) * (1 - std::clamp(deepest_fraction, 0.0, 1.0))));
  ys.erase(ys.begin(), ys.begin() + skip);
  xs.erase(xs.begin(), xs.begin() + skip);
  *rows = static_cast<int>(ys.size());
  if (ys.size() < 3) return 0;
  const auto ranks = [](const std::vector<double>& v) {
    std::vector<std::size_t> order(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return v[a] < v[b]; });
    std::vector<double> r(v.size());
    for (std::size_t i = 0; i < v.size();) {  // Ties get their mean rank.
      std::size_t j = i;
      while (j + 1 < v.size() && v[order[j + 1]] == v[order[i]]) ++j;
      for (std::size_t k = i; k <= j; ++k) r[order[k]] = 0.5 * static_cast<double>(i + j);
      i = j + 1;
    }
    return r;
  };
  const std::vector<double> a = ranks(ys), b = ranks(xs);
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) ma += a[i], mb += b[i];
  ma /= static_cast<double>(a.size());
  mb /= static_cast<double>(b.size());
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return saa > 0 && sbb > 0 ? sab / std::sqrt(saa * sbb) : 0;
}

}  // namespace impactdic::test

#endif  // IMPACTDIC_TESTS_RENDER_TEST_UTIL_H_
