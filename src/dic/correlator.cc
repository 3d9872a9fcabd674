#include "impactdic/dic/correlator.h"

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <span>
#include <utility>

#include "icgn.h"
#include "impactdic/core/error.h"
#include "impactdic/core/numeric.h"
#include "impactdic/core/timer.h"
#include "impactdic/dic/bspline.h"
#include "impactdic/dic/continuity_check.h"
#include "impactdic/dic/outlier_check.h"
#include "impactdic/dic/reference_update.h"
#include "impactdic/io/image_io.h"

namespace impactdic {

using internal::DeformedImage;
using internal::IcgnResult;
using internal::Params;
using internal::RefImages;
using internal::Shape;
using internal::SubsetRef;

namespace {

constexpr int kBorderPx = 4;
// Patches per row of the reference images' patch layout (RefImages).
constexpr int kPatchColumns = 64;

bool Usable(SubsetStatus s) { return s == SubsetStatus::kConverged; }

// A reference subset centred on the pixel nearest to the material point `pos` (the offset is
// kept, so the displacement of `pos` itself is read from the warp).
SubsetRef CentredSubset(cv::Point2d pos) {
  SubsetRef s;
  s.cx = static_cast<int>(std::lround(pos.x));
  s.cy = static_cast<int>(std::lround(pos.y));
  s.ox = pos.x - s.cx;
  s.oy = pos.y - s.cy;
  return s;
}

// The saturation level of the sequence's data: of `data_bits` (DicOptions::data_bits) when
// given, else of the first reference's (io DataBits: 255, 4095 for 12-bit data in 16-bit
// containers, 65535). The contrast and featureless limits are relative to it, so the same
// speckle as 12-bit or 16-bit data passes the same subsets. Float data has no saturation level:
// its largest magnitude in the first reference stands for it (just above it, so that no pixel
// counts as saturated at the top), so float images scaled to 0..1 or to 0..255 pass the same
// subsets as their 8-bit original.
double FullScale(const cv::Mat& raw, int data_bits) {
  const int bits = data_bits > 0 ? data_bits : DataBits(raw);
  if (bits > 0) return static_cast<double>((1 << bits) - 1);
  double lo = 0, hi = 0;
  cv::minMaxLoc(raw.reshape(1), &lo, &hi);
  const double magnitude = std::max(std::abs(lo), std::abs(hi));
  return std::isfinite(magnitude) && magnitude > 0 ? magnitude * (1 + 1e-6) : 1.0;
}

struct Frame {
  int index = 0;
  cv::Mat raw;
  // The image for the integer search: the 8-bit image itself, else a float copy (made on
  // demand; cv::matchTemplate takes 8-bit or float images).
  cv::Mat image32;
  BsplineImage spline;
  cv::Rect reach;
  DeformedImage view;
  const cv::Mat& Float() {
    if (image32.empty()) {
      if (raw.depth() == CV_8U || raw.depth() == CV_32F)
        image32 = raw;
      else
        raw.convertTo(image32, CV_32F);
    }
    return image32;
  }
};

struct Reference {
  int frame = 0;
  cv::Mat image32;
  RefImages images;
  std::vector<SubsetRef> subsets;
  std::vector<double> hinv;
};

// What an orphan keeps of the reference it was last found in: what IC-GN (RunIcgn reads the
// reference intensities and node gradients over the subset's footprint alone) and the integer
// search (its template is the footprint) read of it, copied out of the reference. An orphan so
// holds a few kB (3 x 25^2 floats, the 25^2 template, its subset data and its n x n inverse
// Hessian for subset 25), never the reference itself (images and data of every subset: 150 MB
// and more at 4096 x 3000, once per update that lost a subset), so the memory of a long
// recording does not grow with its reference updates.
struct OrphanRef {
  SubsetRef subset;
  std::vector<double> hinv;  // n x n, row-major; empty unless the subset is usable.
  RefImages images;          // f, gx, gy over the footprint; empty unless usable.
  cv::Mat search_template;   // The search image over the footprint; empty if it leaves the image.
  std::size_t Bytes() const {
    const auto bytes = [](const cv::Mat& m) { return m.total() * m.elemSize(); };
    return sizeof(OrphanRef) + hinv.size() * sizeof(double) + bytes(images.f) + bytes(images.gx) +
           bytes(images.gy) + bytes(search_template);
  }
};

// A subset that was not found in the frame that became the reference: it stays tracked against
// the reference it was last found in (the part of it kept in OrphanRef), is tried against it in
// every frame (status `lost` while it fails) and rejoins the tracked subsets at the next reference
// update after it is found again.
struct Orphan {
  std::shared_ptr<const OrphanRef> ref;  // Null unless orphaned.
  cv::Point2d ref_pos;                   // Its tracked point in that reference.
};

// A displacement gradient H = F - I (du/dX, du/dY, dv/dX, dv/dY).
using Gradient = std::array<double, 4>;
constexpr Gradient kNoGradient{kNaN, kNaN, kNaN, kNaN};

// The gradient of two warps applied one after the other: first `first` (X -> x_r), then
// `second` (x_r -> x), evaluated at the matching points: F = F_second F_first, so
// H = H_second + H_first + H_second H_first (2 x 2 matrices, row-major).
Gradient ComposeGradients(const Gradient& second, const Gradient& first) {
  const auto& [a, b, c, d] = second;
  const auto& [e, f, g, h] = first;
  return {a + e + a * e + b * g, b + f + a * f + b * h, c + g + c * e + d * g,
          d + h + c * f + d * h};
}

struct Attempt {
  IcgnResult r;
  bool solved = false, searched = false, propagated = false;
};

}  // namespace

double DicSummary::SubsetsPerSecond() const {
  return seconds_total > 0 ? double(subsets) * frames / seconds_total : 0;
}

std::string DicSummary::BriefReport() const {
  return fmt::format(
      "{} subsets x {} frames: {:.2f}% valid, {:.2f} iterations/subset, {} reference updates, "
      "{:.3f} s ({:.0f} subsets/s){}{}{}",
      subsets, frames, 100 * valid_fraction, mean_iterations, reference_updates, seconds_total,
      SubsetsPerSecond(),
      data_bits == 10 || data_bits == 12 ? fmt::format("; {}-bit data in 16-bit images", data_bits)
                                         : "",
      Discontinuous() > 0 ? fmt::format("; {} subset results flagged as straddling a "
                                        "discontinuity",
                                        Discontinuous())
                          : "",
      Outliers() > 0 ? fmt::format("; {} subset results flagged as outliers", Outliers()) : "");
}

std::string DicSummary::NothingUsable(const std::string& min_zncc_name, double min_zncc) const {
  if (frames == 0 || valid_fraction > 0) return "";
  std::size_t most = 0;
  long long total = 0;
  for (std::size_t i = 0; i < status_counts.size(); ++i) {
    total += status_counts[i];
    if (status_counts[i] > status_counts[most]) most = i;
  }
  return fmt::format(
      "no valid subset in any of the {} frames after the reference ({} subsets; most common "
      "status: {} in {} of {} results; {} = {})",
      frames, subsets, ToString(static_cast<SubsetStatus>(most)), status_counts[most], total,
      min_zncc_name, min_zncc);
}

long long DicSummary::Outliers() const {
  return status_counts[static_cast<int>(SubsetStatus::kOutlier)];
}

long long DicSummary::Discontinuous() const {
  return status_counts[static_cast<int>(SubsetStatus::kDiscontinuous)];
}

std::string DicSummary::FullReport() const {
  std::string s = BriefReport() + "\n";
  s += fmt::format(
      "  time: coefficients {:.3f} s, reference {:.3f} s, initial guess {:.3f} s ({} searches), "
      "IC-GN {:.3f} s\n",
      seconds_coefficients, seconds_reference, seconds_initial_guess, searches, seconds_icgn);
  if (data_bits > 0)
    s += fmt::format("  data: {}-bit (saturation at grey level {})\n", data_bits,
                     (1 << data_bits) - 1);
  if (orphan_reference_bytes > 0)
    s += fmt::format("  lost subsets: at most {:.1f} kB of earlier references kept for them\n",
                     orphan_reference_bytes / 1024.0);
  s += "  status:";
  for (int i = 0; i < kSubsetStatusCount; ++i) {
    if (status_counts[i] > 0)
      s += fmt::format(" {}={}", ToString(static_cast<SubsetStatus>(i)), status_counts[i]);
  }
  return s;
}

struct Correlator::Impl {
  DicOptions options;
  Shape shape;
  int half = 12, size = 25;
  int nx = 0, ny = 0;
  cv::Size image_size;
  int depth = CV_8U;
  double full_scale = 255;  // FullScale of the first reference: the range of the sequence's data.
  std::vector<cv::Point2d> initial;     // X0: centres in the first reference.
  std::vector<char> active;             // Still tracked.
  std::vector<SubsetStatus> permanent;  // Status of subsets no longer tracked.
  std::vector<Orphan> orphans;          // Per subset; ref == nullptr unless orphaned.
  Reference ref;
  // Tracked point in the current reference image.
  std::vector<cv::Point2d> ref_pos;
  // Positions of the tracked points in the last two frames (NaN = unknown), and the last warp
  // relative to the current reference.
  std::vector<cv::Point2d> pos_last, pos_prev;
  std::vector<Params> params_last;
  std::vector<char> params_valid;
  // options.keep_warp_gradient (empty otherwise), per subset: the displacement gradient since
  // the first reference at the tracked point when its current reference (ref_pos, or its
  // orphan's) was made (F_prev - I; 0 for the first reference), and the gradient in the last
  // solved frame (NaN where not converged), which becomes the former if that frame becomes the
  // reference.
  std::vector<Gradient> gradient_at_ref, gradient_last;
  int last_index = 0;
  std::unique_ptr<ReferenceUpdatePolicy> policy;  // From options.update (kSequence).
  std::unique_ptr<Frame> last_frame;  // For policies that KeepsLastFrame(): the last good frame.
  // A frame done with: the next frame reuses its coefficient buffer (Recycle).
  std::unique_ptr<Frame> spare_frame;
  void Recycle(std::unique_ptr<Frame> frame);
  std::unique_ptr<Frame> NewFrame();
  DicSummary summary;
  long long iteration_sum = 0, converged_sum = 0;
  tbb::enumerable_thread_specific<cv::Mat> scratch;

  void BuildReference(int frame_index, const cv::Mat& raw, const BsplineImage* spline_in,
                      const cv::Mat& image32, FrameResult* timing);
  void MakeFrame(const cv::Mat& raw, int index, Frame* frame);
  // Solves every tracked subset of `frame` against the current reference (FrameSolver).
  std::vector<Attempt> Solve(Frame& frame, FrameResult* out);
  class FrameSolver;
  std::vector<char> RescuedByLastFrame(const std::vector<int>& which,
                                       const std::vector<Attempt>& at, const Frame& frame,
                                       FrameResult* out);
  void SolveOrphans(Frame& frame, std::vector<Attempt>& at, FrameResult* out);
  // Makes `pos` (the tracked points in the last solved frame, NaN = not found) the reference
  // points, `gradient` (gradient_last of that frame) their gradients since the first reference.
  void MoveReferencePoints(const std::vector<cv::Point2d>& pos,
                           const std::vector<Gradient>& gradient);
  // The search template of subset s: `image32` (the reference's search image) over its
  // footprint, a view; empty if the footprint leaves the image.
  cv::Mat SearchTemplate(const SubsetRef& s, const cv::Mat& image32) const;
  // Integer-pixel ZNCC search of `templ` (SearchTemplate; empty: not found) around the guess.
  bool Search(const SubsetRef& s, const cv::Mat& templ, Frame& frame, double gu, double gv,
              cv::Mat* scratch_mat, Params* p0) const;
  // What orphan i keeps of the current reference (OrphanRef).
  std::shared_ptr<const OrphanRef> KeepForOrphan(int i) const;
  void CheckImage(const cv::Mat& image, const char* what) const;

  // The steps of Correlate after the frame is solved against the current reference.
  struct FrameView {  // Storage of a SolvedFrame.
    std::vector<SubsetStatus> status;
    std::vector<float> zncc;
    std::vector<char> trackable;
  };
  SolvedFrame View(int frame_index, const std::vector<Attempt>& at, FrameView* storage) const;
  // Redoes the frame against the last solved frame when the policy asks and that rescues one of
  // the subsets it named.
  void RedoIfThePolicyAsks(Frame& frame, std::vector<Attempt>* at, FrameResult* out);
  // The results of `at` into out (displacements, ZNCC, sigma, status), the warps kept for the
  // next prediction; returns the tracked positions (NaN where not converged).
  std::vector<cv::Point2d> StoreResults(const std::vector<Attempt>& at, FrameResult* out);
  // The post-checks on the stored results: the continuity check (options.continuity), then the
  // normalized median test (options.outliers). Flagged subsets become `discontinuous` or
  // `outlier` in out and `at`, untracked in this frame (NaN position) like other failures.
  void PostCheck(std::vector<Attempt>* at, std::vector<cv::Point2d>* pos, FrameResult* out);
  // Makes the subsets that a post-check set to `flagged` in out failures in `at` too.
  void Untrack(SubsetStatus flagged, std::vector<Attempt>* at, std::vector<cv::Point2d>* pos,
               const FrameResult& out);
  // options.keep_warp_gradient: NaN gradients where a post-check failed the subset, and the
  // frame's gradients kept as gradient_last.
  void KeepGradients(FrameResult* out);
  // Makes the frame the reference if the policy says so, else keeps it if the policy needs it.
  void AdvanceReference(const cv::Mat& image, std::unique_ptr<Frame> frame,
                        const std::vector<Attempt>& at, const std::vector<cv::Point2d>& pos,
                        FrameResult* out);
  void AddToSummary(const FrameResult& out);
};

void Correlator::Impl::CheckImage(const cv::Mat& image, const char* what) const {
  CheckValue(!image.empty() && image.channels() == 1, what,
             image.empty() ? "an empty image" : "a multi-channel image", "a one-channel image");
  if (!image_size.empty()) {
    CheckValue(image.size() == image_size, what,
               std::to_string(image.cols) + "x" + std::to_string(image.rows),
               "the reference size " + std::to_string(image_size.width) + "x" +
                   std::to_string(image_size.height));
  }
}

void Correlator::Impl::BuildReference(int frame_index, const cv::Mat& raw,
                                      const BsplineImage* spline_in, const cv::Mat& image32,
                                      FrameResult* timing) {
  WallTimer timer;
  ref.frame = frame_index;
  ref.image32 = image32;
  // Region the reference subsets occupy (+2 px).
  const int n = static_cast<int>(initial.size());
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (int i = 0; i < n; ++i) {
    if (!active[i]) continue;
    x0 = std::min(x0, ref_pos[i].x);
    x1 = std::max(x1, ref_pos[i].x);
    y0 = std::min(y0, ref_pos[i].y);
    y1 = std::max(y1, ref_pos[i].y);
  }
  const cv::Rect full(0, 0, image_size.width, image_size.height);
  cv::Rect region = full;
  if (x0 <= x1) {
    const int m = half + 3;
    region = cv::Rect(cv::Point(static_cast<int>(std::floor(x0)) - m,
                                static_cast<int>(std::floor(y0)) - m),
                      cv::Point(static_cast<int>(std::ceil(x1)) + m + 1,
                                static_cast<int>(std::ceil(y1)) + m + 1)) &
             full;
  }
  BsplineImage local;
  const BsplineImage* spline = spline_in;
  WallTimer coef_timer;
  if (!spline || (spline->region() & region) != region ||
      spline->kind() != options.icgn.interpolation) {
    local.Build(raw, options.icgn.interpolation, region);
    spline = &local;
  }
  const double coef_seconds = coef_timer.ElapsedSeconds();
  if (timing) timing->seconds_coefficients += coef_seconds;
  // The reference images (RefImages): in the patch layout (subset i's intensities and node
  // gradients in patch i) when the tracked subsets cover less than the region, so that an update
  // of a sparse grid costs the subsets' pixels, not the image's; over the region for dense grids
  // (overlapping subsets). Both give the same values.
  RefImages& im = ref.images;
  im.region = spline->region();
  im.full_scale = full_scale;
  const long long tracked = std::count(active.begin(), active.end(), 1);
  const bool patches = tracked * size * size < static_cast<long long>(im.region.area());
  im.patch_size = patches ? size : 0;
  im.patch_cols = patches ? std::clamp(n, 1, kPatchColumns) : 0;
  if (patches) {
    const cv::Size atlas(im.patch_cols * size, ((n + im.patch_cols - 1) / im.patch_cols) * size);
    im.f.create(atlas, CV_32F);
    im.gx.create(atlas, CV_32F);
    im.gy.create(atlas, CV_32F);
  } else {
    spline->NodeGradients(&im.gx, &im.gy);
    raw(im.region).convertTo(im.f, CV_32F);
  }
  ref.subsets.assign(n, SubsetRef{});
  ref.hinv.assign(static_cast<std::size_t>(n) * shape.n * shape.n, 0.0);
  tbb::parallel_for(0, n, [&](int i) {
    SubsetRef& s = ref.subsets[i];
    if (!active[i]) {
      s.status = permanent[i];
      return;
    }
    s = CentredSubset(ref_pos[i]);
    const cv::Rect box(s.cx - half, s.cy - half, size, size);
    if (patches && (box & im.region) == box) {  // Else PrepareSubset finds it out of the image.
      s.patch = i;
      const cv::Rect patch = im.Patch(i);
      cv::Mat f = im.f(patch), gx = im.gx(patch), gy = im.gy(patch);
      raw(box).convertTo(f, CV_32F);
      spline->NodeGradients(box, &gx, &gy);
    }
    internal::PrepareSubset(shape, im, options.icgn, &s,
                            &ref.hinv[static_cast<std::size_t>(i) * shape.n * shape.n]);
  });
  params_valid.assign(n, 0);
  if (timing) timing->seconds_reference += timer.ElapsedSeconds() - coef_seconds;
}

void Correlator::Impl::MakeFrame(const cv::Mat& raw, int index, Frame* out) {
  Frame& f = *out;
  f.index = index;
  f.raw = raw;
  // Region the subsets can reach: their reference positions grown by the subset half size, the
  // search radius and the largest displacement seen so far.
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (std::size_t i = 0; i < initial.size(); ++i) {
    if (!active[i] && !orphans[i].ref) continue;
    cv::Point2d p = ref_pos[i];
    x0 = std::min(x0, p.x);
    x1 = std::max(x1, p.x);
    y0 = std::min(y0, p.y);
    y1 = std::max(y1, p.y);
    if (!std::isnan(pos_last[i].x)) {
      x0 = std::min(x0, pos_last[i].x);
      x1 = std::max(x1, pos_last[i].x);
      y0 = std::min(y0, pos_last[i].y);
      y1 = std::max(y1, pos_last[i].y);
    }
  }
  const cv::Rect full(0, 0, image_size.width, image_size.height);
  cv::Rect reach = full;
  if (x0 <= x1) {
    const int m = half + options.init.search_radius_px + 2;
    reach = cv::Rect(cv::Point(static_cast<int>(std::floor(x0)) - m,
                               static_cast<int>(std::floor(y0)) - m),
                     cv::Point(static_cast<int>(std::ceil(x1)) + m + 1,
                               static_cast<int>(std::ceil(y1)) + m + 1)) &
            full;
  }
  f.reach = reach;
  f.spline.Build(raw, options.icgn.interpolation, reach);
  f.view.spline = &f.spline;
  f.view.x_min = std::max<double>(reach.x, f.spline.x_min());
  f.view.y_min = std::max<double>(reach.y, f.spline.y_min());
  f.view.x_max = std::min<double>(reach.x + reach.width - 1, f.spline.x_max());
  f.view.y_max = std::min<double>(reach.y + reach.height - 1, f.spline.y_max());
}

cv::Mat Correlator::Impl::SearchTemplate(const SubsetRef& s, const cv::Mat& image32) const {
  const cv::Rect full(0, 0, image_size.width, image_size.height);
  const cv::Rect templ_rect(s.cx - half, s.cy - half, size, size);
  if ((templ_rect & full) != templ_rect) return {};
  return image32(templ_rect);
}

bool Correlator::Impl::Search(const SubsetRef& s, const cv::Mat& templ, Frame& frame, double gu,
                              double gv, cv::Mat* result, Params* p0) const {
  if (templ.empty()) return false;
  const int R = options.init.search_radius_px;
  const cv::Rect full(0, 0, image_size.width, image_size.height);
  const int wx = s.cx + static_cast<int>(std::lround(gu)),
            wy = s.cy + static_cast<int>(std::lround(gv));
  const cv::Rect window = cv::Rect(wx - half - R, wy - half - R, size + 2 * R, size + 2 * R) & full;
  if (window.width < size || window.height < size) return false;
  cv::matchTemplate(frame.image32(window), templ, *result, cv::TM_CCOEFF_NORMED);
  double best = -2;
  cv::Point loc(-1, -1);
  // Deterministic arg-max (first maximum in row-major order), ignoring non-finite scores.
  for (int r = 0; r < result->rows; ++r) {
    const float* row = result->ptr<float>(r);
    for (int c = 0; c < result->cols; ++c) {
      if (std::isfinite(row[c]) && row[c] > best) {
        best = row[c];
        loc = cv::Point(c, r);
      }
    }
  }
  if (loc.x < 0 || best < options.init.min_search_zncc) return false;
  *p0 = Params{};
  (*p0)[0] = window.x + loc.x + half - s.cx;
  (*p0)[shape.nm] = window.y + loc.y + half - s.cy;
  return true;
}

// The steps of Solve: 1. every subset with a prediction from the previous increments; 2a.
// reliability-guided propagation waves on the lattice of every second subset, with integer
// searches at seeds, then the other subsets from the fit of their solved lattice neighbours; 2b.
// waves over all subsets for what is left; then the orphans.
class Correlator::Impl::FrameSolver {
 public:
  FrameSolver(Impl& m, Frame& frame, FrameResult* out)
      : m_(m),
        frame_(frame),
        out_(out),
        n_(static_cast<int>(m.initial.size())),
        at_(n_),
        usable_(n_, 0) {
    for (int i = 0; i < n_; ++i) {
      usable_[i] = m.active[i] && Usable(m.ref.subsets[i].status);
      at_[i].r.status = m.active[i]
                            ? (usable_[i] ? SubsetStatus::kNotFound : m.ref.subsets[i].status)
                            : m.permanent[i];
    }
  }

  std::vector<Attempt> Run() {
    SolveFromPredictions();
    constexpr int kCoarse = 2;
    if (m_.nx > kCoarse && m_.ny > kCoarse) {
      Propagate(kCoarse);
      FillFromLattice(kCoarse);
    }
    Propagate(1);
    m_.SolveOrphans(frame_, at_, out_);
    return std::move(at_);
  }

 private:
  IcgnResult Icgn(int i, const Params& p0) const {
    const std::size_t nn = static_cast<std::size_t>(m_.shape.n) * m_.shape.n;
    return internal::RunIcgn(m_.shape, m_.ref.images, m_.ref.subsets[i], &m_.ref.hinv[i * nn],
                             frame_.view, m_.options.icgn, p0);
  }

  // Prediction of the displacement of subset i's tracked point (relative to the reference).
  // The velocity (last increment) is averaged over the subset and its solved grid neighbours:
  // the increments of neighbouring subsets share the motion but not all of the noise, so the mean
  // is a better prediction (fewer IC-GN iterations) wherever the motion is smooth over 3x3
  // subsets.
  bool Predict(int i, Params* p0) const {
    const int grid_nx = m_.nx, grid_ny = m_.ny;
    const std::vector<cv::Point2d>& last = m_.pos_last;
    const std::vector<cv::Point2d>& prev = m_.pos_prev;
    if (std::isnan(last[i].x)) return false;
    cv::Point2d pred = last[i];
    if (!std::isnan(prev[i].x)) {
      const int r = i / grid_nx, c = i % grid_nx;
      cv::Point2d velocity(0, 0);
      int count = 0;
      for (int rr = std::max(0, r - 1); rr <= std::min(grid_ny - 1, r + 1); ++rr) {
        for (int cc = std::max(0, c - 1); cc <= std::min(grid_nx - 1, c + 1); ++cc) {
          const int j = rr * grid_nx + cc;
          if (std::isnan(last[j].x) || std::isnan(prev[j].x)) continue;
          velocity += last[j] - prev[j];
          ++count;
        }
      }
      pred += velocity / count;
    }
    const SubsetRef& s = m_.ref.subsets[i];
    Params p = m_.params_valid[i] ? m_.params_last[i] : Params{};
    double du, dv;
    internal::Displacement(m_.shape, p, s.ox, s.oy, &du, &dv);
    const cv::Point2d d = pred - m_.ref_pos[i];
    p[0] += d.x - du;
    p[m_.shape.nm] += d.y - dv;
    *p0 = p;
    return true;
  }

  // 1. Prediction from previous increments, all subsets in parallel.
  void SolveFromPredictions() {
    timer_.Restart();
    std::vector<int> list;
    for (int i = 0; i < n_; ++i)
      if (usable_[i] && !std::isnan(m_.pos_last[i].x)) list.push_back(i);
    tbb::parallel_for(0, static_cast<int>(list.size()), [&](int k) {
      const int i = list[k];
      Params p0;
      Predict(i, &p0);
      at_[i].r = Icgn(i, p0);
      at_[i].solved = at_[i].r.status == SubsetStatus::kConverged;
    });
    out_->seconds_icgn += timer_.ElapsedSeconds();
  }

  // The waves run on a lattice of every `stride`-th subset in x and y (neighbours `stride` nodes
  // apart).
  bool OnLattice(int i, int stride) const {
    return (i / m_.nx) % stride == 0 && (i % m_.nx) % stride == 0;
  }

  // The solved lattice neighbour of i with the highest ZNCC (lowest index on ties); -1 if none.
  int SolvedNeighbour(int i, int stride) const {
    const int grid_nx = m_.nx, grid_ny = m_.ny;
    const int r = i / grid_nx, c = i % grid_nx;
    int best = -1;
    for (int dr = -stride; dr <= stride; dr += stride) {
      for (int dc = -stride; dc <= stride; dc += stride) {
        if (!dr && !dc) continue;
        const int rr = r + dr, cc = c + dc;
        if (rr < 0 || rr >= grid_ny || cc < 0 || cc >= grid_nx) continue;
        const int j = rr * grid_nx + cc;
        if (!at_[j].solved) continue;
        if (best < 0 || at_[j].r.zncc > at_[best].r.zncc ||
            (at_[j].r.zncc == at_[best].r.zncc && j < best))
          best = j;
      }
    }
    return best;
  }

  // Integer-pixel search around `guess` (else the prediction, else no displacement), then IC-GN.
  void SearchAndSolve(int i, const Params* guess) {
    cv::Mat& result = m_.scratch.local();
    double gu = 0, gv = 0;
    Params p0;
    if (guess) {
      gu = (*guess)[0];
      gv = (*guess)[m_.shape.nm];
    } else if (Predict(i, &p0)) {
      gu = p0[0];
      gv = p0[m_.shape.nm];
    }
    at_[i].searched = true;
    const SubsetRef& s = m_.ref.subsets[i];
    if (!m_.Search(s, m_.SearchTemplate(s, m_.ref.image32), frame_, gu, gv, &result, &p0)) {
      if (!at_[i].propagated) at_[i].r.status = SubsetStatus::kNotFound;
      return;
    }
    IcgnResult r = Icgn(i, p0);
    if (r.status == SubsetStatus::kConverged || !at_[i].propagated) at_[i].r = r;
    at_[i].solved = r.status == SubsetStatus::kConverged;
  }

  // Guess for subset i from solved neighbours `from`: per displacement component, the affine
  // field a + g . (x - x_i) fitted by least squares to the neighbours' displacements at their
  // centres and to their gradients. The gradients are weighted by the variance of the subset
  // coordinate, (S^2 - 1) / 12, the ratio of the noise variances of a subset's displacement and
  // of its gradient. Second-order terms (quadratic shape) are averaged.
  Params FitGuess(const SubsetRef& si, const int* from, int count) const {
    const double gradient_weight = (double(m_.size) * m_.size - 1) / 12;
    const int nm = m_.shape.nm;
    Params p0{};
    for (int comp = 0; comp < 2; ++comp) {
      const int o = comp * nm;
      double a[3][3] = {}, rhs[3] = {};
      for (int k = 0; k < count; ++k) {
        const Params& pj = at_[from[k]].r.p;
        const double d[3] = {1, double(m_.ref.subsets[from[k]].cx - si.cx),
                             double(m_.ref.subsets[from[k]].cy - si.cy)};
        for (int row = 0; row < 3; ++row) {
          for (int col = 0; col < 3; ++col) a[row][col] += d[row] * d[col];
          rhs[row] += d[row] * pj[o];
        }
        for (int q = 1; q < 3; ++q) {
          a[q][q] += gradient_weight;
          rhs[q] += gradient_weight * pj[o + q];
        }
        for (int q = 3; q < nm; ++q) p0[o + q] += pj[o + q] / count;
      }
      // Solve the 3x3 system (symmetric positive definite: gradient rows always present).
      for (int col = 0; col < 3; ++col) {
        for (int row = col + 1; row < 3; ++row) {
          const double f = a[row][col] / a[col][col];
          for (int k = col; k < 3; ++k) a[row][k] -= f * a[col][k];
          rhs[row] -= f * rhs[col];
        }
      }
      for (int row = 2; row >= 0; --row) {
        double v = rhs[row];
        for (int k = row + 1; k < 3; ++k) v -= a[row][k] * p0[o + k];
        p0[o + row] = v / a[row][row];
      }
    }
    return p0;
  }

  // 2. Reliability-guided propagation in deterministic waves on the lattice of `stride`, with
  // searches at seeds when no wave can start.
  void Propagate(int stride) {
    while (PropagateWave(stride) || SearchSeeds(stride)) {
    }
  }

  // One wave: every unsolved lattice subset with a solved neighbour starts from it (stride 1:
  // its warp; coarser: the fit of all solved neighbours); those that fail get their own search
  // around that guess. false if no subset had a solved neighbour.
  bool PropagateWave(int stride) {
    const int grid_nx = m_.nx, grid_ny = m_.ny;
    // Solved neighbours are listed before the wave runs (the wave changes `at_`).
    std::vector<int> frontier, best, neighbour_count;
    std::vector<std::array<int, 8>> neighbours;
    for (int i = 0; i < n_; ++i) {
      if (!usable_[i] || at_[i].solved || at_[i].propagated || !OnLattice(i, stride)) continue;
      const int j = SolvedNeighbour(i, stride);
      if (j < 0) continue;
      frontier.push_back(i);
      best.push_back(j);
      if (stride > 1) {
        std::array<int, 8> from;
        int count = 0;
        const int r = i / grid_nx, c = i % grid_nx;
        for (int dr = -stride; dr <= stride; dr += stride) {
          for (int dc = -stride; dc <= stride; dc += stride) {
            const int rr = r + dr, cc = c + dc;
            if ((dr || dc) && rr >= 0 && rr < grid_ny && cc >= 0 && cc < grid_nx &&
                at_[rr * grid_nx + cc].solved)
              from[count++] = rr * grid_nx + cc;
          }
        }
        neighbours.push_back(from);
        neighbour_count.push_back(count);
      }
    }
    if (frontier.empty()) return false;
    const internal::Shape& warp = m_.shape;
    const std::vector<SubsetRef>& subsets = m_.ref.subsets;
    timer_.Restart();
    tbb::parallel_for(0, static_cast<int>(frontier.size()), [&](int k) {
      const int i = frontier[k], j = best[k];
      const SubsetRef& si = subsets[i];
      const SubsetRef& sj = subsets[j];
      at_[i].propagated = true;
      if (stride == 1) {
        at_[i].r = Icgn(i, internal::Transfer(warp, at_[j].r.p, si.cx - sj.cx, si.cy - sj.cy));
      } else {
        // On the coarse lattice the neighbours are far apart: fit all solved ones.
        at_[i].r = Icgn(i, FitGuess(si, neighbours[k].data(), neighbour_count[k]));
      }
      at_[i].solved = at_[i].r.status == SubsetStatus::kConverged;
    });
    out_->seconds_icgn += timer_.ElapsedSeconds();
    // Subsets that failed from their neighbour get their own search around its guess.
    std::vector<int> retry, from;
    for (std::size_t k = 0; k < frontier.size(); ++k) {
      const int i = frontier[k];
      if (!at_[i].solved && !at_[i].searched && at_[i].r.status != SubsetStatus::kOutOfImage) {
        retry.push_back(i);
        from.push_back(best[k]);
      }
    }
    if (!retry.empty()) {
      timer_.Restart();
      frame_.Float();
      tbb::parallel_for(0, static_cast<int>(retry.size()), [&](int k) {
        const int i = retry[k], j = from[k];
        const Params p0 = internal::Transfer(warp, at_[j].r.p, subsets[i].cx - subsets[j].cx,
                                             subsets[i].cy - subsets[j].cy);
        SearchAndSolve(i, &p0);
      });
      out_->searches += static_cast<int>(retry.size());
      out_->seconds_initial_guess += timer_.ElapsedSeconds();
    }
    return true;
  }

  // Integer searches at the seeds among the unsolved, unsearched lattice subsets (every
  // `seed_spacing`-th lattice node and the grid centre lines; all candidates if none is a seed).
  // false if there is no candidate left.
  bool SearchSeeds(int stride) {
    const int grid_nx = m_.nx, grid_ny = m_.ny;
    const int spacing = std::max(1, m_.options.init.seed_spacing / stride);
    const int lattice_nx = (grid_nx + stride - 1) / stride,
              lattice_ny = (grid_ny + stride - 1) / stride;
    std::vector<int> candidates, seeds;
    for (int i = 0; i < n_; ++i)
      // Not those whose guess from a solved neighbour left the image: nothing to search for.
      if (usable_[i] && !at_[i].solved && !at_[i].searched && OnLattice(i, stride) &&
          !(at_[i].propagated && at_[i].r.status == SubsetStatus::kOutOfImage))
        candidates.push_back(i);
    if (candidates.empty()) return false;
    for (int i : candidates) {
      const int r = i / grid_nx / stride, c = i % grid_nx / stride;
      if ((r % spacing == spacing / 2 || r == lattice_ny / 2) &&
          (c % spacing == spacing / 2 || c == lattice_nx / 2))
        seeds.push_back(i);
    }
    if (seeds.empty()) seeds = candidates;
    timer_.Restart();
    frame_.Float();
    tbb::parallel_for(0, static_cast<int>(seeds.size()),
                      [&](int k) { SearchAndSolve(seeds[k], nullptr); });
    out_->searches += static_cast<int>(seeds.size());
    out_->seconds_initial_guess += timer_.ElapsedSeconds();
    return true;
  }

  // 2a. After the waves on the lattice of every second subset, every other subset starts from
  // the fit of its solved lattice neighbours (2 or 4, placed symmetrically about it; 1 at the
  // grid edge), re-expressed about its own centre: for a smooth field this guess is more accurate
  // than one neighbour's warp (the neighbours' errors average out), so IC-GN needs fewer
  // iterations.
  void FillFromLattice(int stride) {
    const int grid_nx = m_.nx, grid_ny = m_.ny;
    std::vector<int> fill;
    for (int i = 0; i < n_; ++i)
      if (usable_[i] && !at_[i].solved && !at_[i].searched && !OnLattice(i, stride))
        fill.push_back(i);
    timer_.Restart();
    tbb::parallel_for(0, static_cast<int>(fill.size()), [&](int k) {
      const int i = fill[k], r = i / grid_nx, c = i % grid_nx;
      const SubsetRef& si = m_.ref.subsets[i];
      std::array<int, 8> from;
      int count = 0;
      for (int dr = -1; dr <= 1; ++dr) {
        for (int dc = -1; dc <= 1; ++dc) {
          const int rr = r + dr, cc = c + dc;
          if (rr < 0 || rr >= grid_ny || cc < 0 || cc >= grid_nx) continue;
          const int j = rr * grid_nx + cc;
          if (OnLattice(j, stride) && at_[j].solved) from[count++] = j;
        }
      }
      if (count == 0) return;
      const IcgnResult r0 = Icgn(i, FitGuess(si, from.data(), count));
      if (r0.status == SubsetStatus::kConverged) {
        at_[i].r = r0;
        at_[i].solved = true;
      }
    });
    out_->seconds_icgn += timer_.ElapsedSeconds();
  }

  Impl& m_;
  Frame& frame_;
  FrameResult* out_;
  const int n_;
  std::vector<Attempt> at_;
  std::vector<char> usable_;
  WallTimer timer_;
};

std::vector<Attempt> Correlator::Impl::Solve(Frame& frame, FrameResult* out) {
  return FrameSolver(*this, frame, out).Run();
}

// Orphans (lost at a reference update) are tried against the reference they were last found in.
// Guess: the position found in the last frame; else the mean accumulated displacement of the
// solved tracked subsets among the 3x3 neighbours in this frame; else no motion. If IC-GN fails
// from it, an integer search around it. Runs after the tracked subsets are solved.
void Correlator::Impl::SolveOrphans(Frame& frame, std::vector<Attempt>& at, FrameResult* out) {
  const int n = static_cast<int>(initial.size());
  std::vector<int> list;
  for (int i = 0; i < n; ++i)
    if (!active[i] && orphans[i].ref && Usable(orphans[i].ref->subset.status)) list.push_back(i);
  if (list.empty()) return;
  WallTimer timer;
  frame.Float();
  std::vector<char> searched(list.size(), 0);
  tbb::parallel_for(0, static_cast<int>(list.size()), [&](int k) {
    const int i = list[k];
    const Orphan& o = orphans[i];
    const OrphanRef& old = *o.ref;
    const SubsetRef& s = old.subset;
    cv::Point2d expected = pos_last[i];
    if (std::isnan(expected.x)) {
      const int r = i / nx, c = i % nx;
      cv::Point2d sum(0, 0);
      int count = 0;
      for (int rr = std::max(0, r - 1); rr <= std::min(ny - 1, r + 1); ++rr) {
        for (int cc = std::max(0, c - 1); cc <= std::min(nx - 1, c + 1); ++cc) {
          const int j = rr * nx + cc;
          if (!active[j] || !at[j].solved) continue;
          double du, dv;
          internal::Displacement(shape, at[j].r.p, ref.subsets[j].ox, ref.subsets[j].oy, &du, &dv);
          sum += ref_pos[j] + cv::Point2d(du, dv) - initial[j];
          ++count;
        }
      }
      expected = count ? initial[i] + sum / count : o.ref_pos;
    }
    Params p0{};
    p0[0] = expected.x - o.ref_pos.x;
    p0[shape.nm] = expected.y - o.ref_pos.y;
    IcgnResult r =
        internal::RunIcgn(shape, old.images, s, old.hinv.data(), frame.view, options.icgn, p0);
    Params p1;
    if (r.status != SubsetStatus::kConverged &&
        Search(s, old.search_template, frame, p0[0], p0[shape.nm], &scratch.local(), &p1)) {
      searched[k] = 1;
      r = internal::RunIcgn(shape, old.images, s, old.hinv.data(), frame.view, options.icgn, p1);
    }
    // Reported with the retry's outcome when IC-GN ran (e.g. `uncertain`), else still `lost`.
    if (r.iterations > 0) at[i].r = r;
    at[i].solved = r.status == SubsetStatus::kConverged;
  });
  out->searches += static_cast<int>(std::count(searched.begin(), searched.end(), 1));
  out->seconds_icgn += timer.ElapsedSeconds();
}

// Before a reference update to the frame whose tracked positions are `pos`: tracked subsets move
// their reference point there; those not found in it become orphans of the current reference
// (status `lost` while they fail); orphans found in it rejoin the tracked subsets.
void Correlator::Impl::MoveReferencePoints(const std::vector<cv::Point2d>& pos,
                                           const std::vector<Gradient>& gradient) {
  const int n = static_cast<int>(initial.size());
  // A subset found in the new reference composes its later warps with its gradient there; a lost
  // one keeps the gradient of the reference it stays tracked against.
  const auto move = [&](int i) {
    ref_pos[i] = pos[i];
    if (!gradient_at_ref.empty()) gradient_at_ref[i] = gradient[i];
  };
  std::vector<int> lost;
  for (int i = 0; i < n; ++i) {
    if (!active[i]) {
      if (orphans[i].ref && !std::isnan(pos[i].x)) {
        active[i] = 1;
        permanent[i] = SubsetStatus::kConverged;
        move(i);
        orphans[i] = Orphan{};
      }
      continue;
    }
    if (std::isnan(pos[i].x))
      lost.push_back(i);
    else
      move(i);
  }
  // What each lost subset needs of the current reference is copied out of it (KeepForOrphan);
  // the reference itself is rebuilt for the new frame.
  for (int i : lost) {
    active[i] = 0;
    permanent[i] = SubsetStatus::kLost;
    orphans[i] = Orphan{KeepForOrphan(i), ref_pos[i]};
  }
  std::size_t bytes = 0;
  for (const Orphan& o : orphans)
    if (o.ref) bytes += o.ref->Bytes();
  summary.orphan_reference_bytes =
      std::max<long long>(summary.orphan_reference_bytes, static_cast<long long>(bytes));
}

std::shared_ptr<const OrphanRef> Correlator::Impl::KeepForOrphan(int i) const {
  auto kept = std::make_shared<OrphanRef>();
  kept->subset = ref.subsets[i];
  if (!Usable(kept->subset.status)) return kept;  // Never tried again: its status is all it needs.
  const std::size_t nn = static_cast<std::size_t>(shape.n) * shape.n;
  kept->hinv.assign(ref.hinv.begin() + static_cast<std::ptrdiff_t>(i * nn),
                    ref.hinv.begin() + static_cast<std::ptrdiff_t>((i + 1) * nn));
  const SubsetRef& s = kept->subset;
  const RefImages& im = ref.images;
  kept->images.full_scale = im.full_scale;
  if (s.patch >= 0) {  // Patch layout: its own square, kept as a layout of one patch.
    const cv::Rect square = im.Patch(s.patch);
    kept->images.region = im.region;
    kept->images.patch_size = im.patch_size;
    kept->images.patch_cols = 1;
    kept->images.f = im.f(square).clone();
    kept->images.gx = im.gx(square).clone();
    kept->images.gy = im.gy(square).clone();
    kept->subset.patch = 0;
  } else {  // A usable subset's footprint lies inside the reference region (PrepareSubset).
    const cv::Rect footprint(s.cx - half, s.cy - half, size, size);
    const cv::Rect local = footprint - im.region.tl();
    kept->images.region = footprint;
    kept->images.f = im.f(local).clone();
    kept->images.gx = im.gx(local).clone();
    kept->images.gy = im.gy(local).clone();
  }
  const cv::Mat templ = SearchTemplate(s, ref.image32);
  if (!templ.empty()) kept->search_template = templ.clone();
  return kept;
}

// For policies that redo frames (`auto`): whether the subsets `which` (failed or below
// auto_min_zncc against the current reference) would pass against the candidate reference, the
// last frame, i.e. converge with a result the policy Rescues (ZNCC >= auto_min_zncc). Only these
// subsets are prepared, each centred on the pixel nearest to its tracked point in the last frame as
// BuildReference would, with its intensities and the node gradients of the last frame's spline over
// the subset alone (so the test costs a few subsets, not a reference). IC-GN starts from the result
// against the current reference if it converged, else from the constant-velocity prediction.
// Subsets not tracked in the last frame cannot pass.
std::vector<char> Correlator::Impl::RescuedByLastFrame(const std::vector<int>& which,
                                                       const std::vector<Attempt>& at,
                                                       const Frame& frame, FrameResult* out) {
  WallTimer timer;
  const Frame& last = *last_frame;
  std::vector<char> rescued(which.size(), 0);
  tbb::parallel_for(0, static_cast<int>(which.size()), [&](int k) {
    const int i = which[k];
    if (std::isnan(pos_last[i].x)) return;
    SubsetRef s = CentredSubset(pos_last[i]);
    RefImages im;
    im.region = cv::Rect(s.cx - half, s.cy - half, size, size);
    if (!last.spline.Inside(im.region.x, im.region.y) ||
        !last.spline.Inside(im.region.x + size - 1, im.region.y + size - 1))
      return;
    last.raw(im.region).convertTo(im.f, CV_32F);
    im.full_scale = full_scale;
    im.gx.create(size, size, CV_32F);
    im.gy.create(size, size, CV_32F);
    for (int r = 0; r < size; ++r) {
      for (int c = 0; c < size; ++c) {
        double value, gx, gy;
        last.spline.ValueGradient(im.region.x + c, im.region.y + r, &value, &gx, &gy);
        im.gx.at<float>(r, c) = static_cast<float>(gx);
        im.gy.at<float>(r, c) = static_cast<float>(gy);
      }
    }
    std::array<double, std::size_t{12} * 12> hinv;  // At most 12 warp parameters (quadratic).
    internal::PrepareSubset(shape, im, options.icgn, &s, hinv.data());
    if (!Usable(s.status)) return;
    // Guess: the displacement from the tracked point in the last frame to its expected position.
    cv::Point2d expected = pos_last[i];
    // The result against the current reference is the best guess when IC-GN reached a solution
    // that only failed the quality checks (decorrelated, uncertain).
    const SubsetStatus st = at[i].r.status;
    const bool solved = st == SubsetStatus::kConverged ||
                        ((st == SubsetStatus::kLowCorrelation || st == SubsetStatus::kUncertain) &&
                         at[i].r.iterations > 0 && std::isfinite(at[i].r.p[0]) &&
                         std::isfinite(at[i].r.p[shape.nm]));
    if (solved) {
      double du, dv;
      internal::Displacement(shape, at[i].r.p, ref.subsets[i].ox, ref.subsets[i].oy, &du, &dv);
      expected = ref_pos[i] + cv::Point2d(du, dv);
    } else if (!std::isnan(pos_prev[i].x)) {
      expected += pos_last[i] - pos_prev[i];
    }
    Params p0{};
    p0[0] = expected.x - pos_last[i].x;
    p0[shape.nm] = expected.y - pos_last[i].y;
    const IcgnResult r = internal::RunIcgn(shape, im, s, hinv.data(), frame.view, options.icgn, p0);
    rescued[k] = policy->Rescues(r.status, r.zncc);
  });
  out->seconds_reference += timer.ElapsedSeconds();
  return rescued;
}

Correlator::Correlator(const DicOptions& options) : impl_(std::make_unique<Impl>()) {
  options.Check();
  impl_->options = options;
  impl_->half = options.grid.subset_size / 2;
  impl_->size = options.grid.subset_size;
  impl_->shape = internal::MakeShape(options.icgn.shape, impl_->half);
  // Pairs: the reference never changes (UpdateOptions do not apply).
  impl_->policy = ReferenceUpdatePolicyFromString(
      options.mode == SequenceMode::kPairs ? "fixed" : options.update.policy, options.update);
}

Correlator::~Correlator() = default;

void Correlator::SetReference(const cv::Mat& image) {
  Impl& m = *impl_;
  m.image_size = cv::Size();
  m.CheckImage(image, "reference image");
  const GridOptions& g = m.options.grid;
  CheckValue(
      image.cols >= m.size && image.rows >= m.size, "subset size", std::to_string(m.size) + " px",
      "at most the image size " + std::to_string(image.cols) + "x" + std::to_string(image.rows));
  const cv::Rect image_rect(0, 0, image.cols, image.rows);
  cv::Rect roi = g.roi.area() > 0 ? g.roi : image_rect;
  CheckValue((roi & cv::Rect(0, 0, image.cols, image.rows)) == roi, "ROI",
             fmt::format("x {}..{}, y {}..{}", roi.x, roi.x + roi.width, roi.y, roi.y + roi.height),
             fmt::format("inside the image (0..{}, 0..{})", image.cols, image.rows));
  CheckValue(roi.width >= m.size && roi.height >= m.size, "ROI",
             fmt::format("{}x{} px", roi.width, roi.height),
             fmt::format("at least one subset ({} px) wide and high", m.size));
  CheckValue(g.mask.empty() || g.mask.size() == image.size(), "mask",
             fmt::format("{}x{}", g.mask.cols, g.mask.rows), "the image size");
  m.image_size = image.size();
  m.depth = image.depth();
  m.full_scale = FullScale(image, m.options.data_bits);
  // Subsets keep kBorderPx from the image border: the interpolation support of a subset that
  // moves by a pixel must stay inside the image.
  const cv::Rect inner(kBorderPx, kBorderPx, image.cols - 2 * kBorderPx,
                       image.rows - 2 * kBorderPx);
  roi &= inner;
  CheckValue(roi.width >= m.size && roi.height >= m.size, "ROI",
             fmt::format("{}x{} px after keeping {} px from the image border", roi.width,
                         roi.height, kBorderPx),
             fmt::format("room for at least one subset ({} px)", m.size));
  m.nx = (roi.width - m.size) / g.step + 1;
  m.ny = (roi.height - m.size) / g.step + 1;
  const int n = m.nx * m.ny;
  m.initial.resize(n);
  m.active.assign(n, 1);
  m.permanent.assign(n, SubsetStatus::kConverged);
  m.orphans.assign(n, Orphan{});
  for (int r = 0; r < m.ny; ++r) {
    for (int c = 0; c < m.nx; ++c) {
      const int i = r * m.nx + c;
      m.initial[i] = cv::Point2d(roi.x + m.half + c * g.step, roi.y + m.half + r * g.step);
      if (!g.mask.empty() && g.mask.at<std::uint8_t>(static_cast<int>(m.initial[i].y),
                                                     static_cast<int>(m.initial[i].x)) == 0) {
        m.active[i] = 0;
        m.permanent[i] = SubsetStatus::kMasked;
      }
    }
  }
  m.ref_pos = m.initial;
  m.pos_last.assign(n, cv::Point2d(kNaN, kNaN));
  m.pos_prev = m.pos_last;
  m.params_last.assign(n, Params{});
  m.params_valid.assign(n, 0);
  if (m.options.keep_warp_gradient) {
    m.gradient_at_ref.assign(n, Gradient{});  // The first reference: no deformation.
    m.gradient_last.assign(n, kNoGradient);
  } else {
    m.gradient_at_ref.clear();
    m.gradient_last.clear();
  }
  m.last_index = 0;
  m.summary = DicSummary{};
  m.summary.subsets = n;
  m.summary.data_bits = m.options.data_bits > 0 ? m.options.data_bits : DataBits(image);
  m.iteration_sum = m.converged_sum = 0;
  FrameResult timing;
  WallTimer timer;
  cv::Mat image32 = image;
  if (image.depth() != CV_8U && image.depth() != CV_32F) image.convertTo(image32, CV_32F);
  m.BuildReference(0, image, nullptr, image32, &timing);
  m.summary.seconds_coefficients += timing.seconds_coefficients;
  m.summary.seconds_reference += timing.seconds_reference;
  m.summary.seconds_total += timer.ElapsedSeconds();
  // The reference frame itself: every subset at zero displacement.
  m.last_frame.reset();
  for (int i = 0; i < n; ++i) {
    if (m.active[i] && Usable(m.ref.subsets[i].status)) m.pos_last[i] = m.initial[i];
  }
  m.pos_last.swap(m.pos_prev);
  m.pos_last.assign(n, cv::Point2d(kNaN, kNaN));
  // pos_prev now holds frame 0; the first Correlate() has no velocity yet: keep pos_last empty
  // so that it uses the seeds (pair mode) rather than a zero-displacement prediction.
}

SolvedFrame Correlator::Impl::View(int frame_index, const std::vector<Attempt>& at,
                                   FrameView* storage) const {
  const std::size_t n = at.size();
  storage->status.resize(n);
  storage->zncc.resize(n);
  storage->trackable.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    storage->status[i] = at[i].r.status;
    storage->zncc[i] = at[i].r.zncc;
    storage->trackable[i] = active[i] && Usable(ref.subsets[i].status) ? 1 : 0;
  }
  return {.frame = frame_index,
          .reference_frame = ref.frame,
          .status = storage->status,
          .zncc = storage->zncc,
          .trackable = storage->trackable};
}

void Correlator::Impl::RedoIfThePolicyAsks(Frame& frame, std::vector<Attempt>* at,
                                           FrameResult* out) {
  if (!policy->KeepsLastFrame() || !last_frame || last_frame->index <= ref.frame) return;
  FrameView storage;
  const std::vector<int> candidates = policy->RedoCandidates(View(out->frame, *at, &storage));
  if (candidates.empty()) return;
  // The switch is made only if it rescues a candidate: one that passes against the last frame as
  // reference. Subsets covered by an object entering the view fail against both.
  const std::vector<char> rescued = RescuedByLastFrame(candidates, *at, frame, out);
  if (std::find(rescued.begin(), rescued.end(), 1) != rescued.end()) {
    // Switch to the last good frame: its tracked positions become the new reference points.
    MoveReferencePoints(pos_last, gradient_last);
    Frame& last = *last_frame;
    BuildReference(last.index, last.raw, &last.spline, last.Float(), out);
    ++summary.reference_updates;
    out->reference_updated = true;
    *at = Solve(frame, out);
  }
  // Candidates that failed against both references (covered by an object, or a bad frame) stay
  // tracked against the kept reference: NaN in this frame, and found again when they reappear,
  // as with `fixed`. While they stay failed their rescue test costs nothing (no position in the
  // last frame).
}

std::vector<cv::Point2d> Correlator::Impl::StoreResults(const std::vector<Attempt>& at,
                                                        FrameResult* out) {
  const int n = static_cast<int>(at.size());
  out->u_px.assign(n, kNaN);
  out->v_px.assign(n, kNaN);
  out->zncc.assign(n, kNaNf);
  out->iterations.assign(n, 0);
  out->sigma_px.assign(n, kNaNf);
  out->sigma_u_px = out->sigma_px;
  out->sigma_v_px = out->sigma_px;
  out->status.resize(n);
  const bool gradients = !gradient_at_ref.empty();
  if (gradients)
    for (auto* g : {&out->dudx, &out->dudy, &out->dvdx, &out->dvdy}) g->assign(n, kNaN);
  std::vector<cv::Point2d> pos(n, cv::Point2d(kNaN, kNaN));
  for (int i = 0; i < n; ++i) {
    const IcgnResult& r = at[i].r;
    out->status[i] = r.status;
    out->iterations[i] = r.iterations;
    if (r.iterations > 0) out->zncc[i] = r.zncc;
    if (r.status != SubsetStatus::kConverged) {
      params_valid[i] = 0;
      continue;
    }
    const Orphan& orphan = orphans[i];
    const SubsetRef& s = orphan.ref ? orphan.ref->subset : ref.subsets[i];
    double du, dv;
    internal::Displacement(shape, r.p, s.ox, s.oy, &du, &dv);
    pos[i] = (orphan.ref ? orphan.ref_pos : ref_pos[i]) + cv::Point2d(du, dv);
    out->u_px[i] = pos[i].x - initial[i].x;
    out->v_px[i] = pos[i].y - initial[i].y;
    out->sigma_u_px[i] = r.sigma_u_px;
    out->sigma_v_px[i] = r.sigma_v_px;
    out->sigma_px[i] = r.sigma_px;
    if (gradients) {
      // The warp's gradient at the tracked point (the subset centre moved by (ox, oy)), against
      // the reference the subset was solved in, composed with the gradient it had there.
      const Params at_point = internal::Transfer(shape, r.p, s.ox, s.oy);
      const Gradient h = ComposeGradients(
          {at_point[1], at_point[2], at_point[shape.nm + 1], at_point[shape.nm + 2]},
          gradient_at_ref[i]);
      out->dudx[i] = h[0];
      out->dudy[i] = h[1];
      out->dvdx[i] = h[2];
      out->dvdy[i] = h[3];
    }
    params_last[i] = r.p;
    params_valid[i] = orphan.ref ? 0 : 1;
    iteration_sum += r.iterations;
    ++converged_sum;
  }
  return pos;
}

void Correlator::Impl::PostCheck(std::vector<Attempt>* at, std::vector<cv::Point2d>* pos,
                                 FrameResult* out) {
  if (options.continuity.enabled) {
    const ContinuityFlags flags = CheckContinuity(*out, nx, ny, options.continuity);
    if (flags.flagged > 0) {
      ApplyContinuityFlags(flags, out);
      Untrack(SubsetStatus::kDiscontinuous, at, pos, *out);
    }
  }
  if (options.outliers.enabled) {
    const OutlierFlags flags = FindOutliers(*out, nx, ny, options.outliers);
    if (flags.flagged > 0) {
      ApplyOutlierFlags(flags, out);
      Untrack(SubsetStatus::kOutlier, at, pos, *out);
    }
  }
}

void Correlator::Impl::Untrack(SubsetStatus flagged, std::vector<Attempt>* at,
                               std::vector<cv::Point2d>* pos, const FrameResult& out) {
  for (std::size_t i = 0; i < at->size(); ++i) {
    IcgnResult& r = (*at)[i].r;
    if (out.status[i] != flagged || r.status != SubsetStatus::kConverged) continue;
    r.status = flagged;
    (*pos)[i] = cv::Point2d(kNaN, kNaN);
    params_valid[i] = 0;
    iteration_sum -= r.iterations;
    --converged_sum;
  }
}

void Correlator::Impl::KeepGradients(FrameResult* out) {
  if (gradient_at_ref.empty()) return;
  for (std::size_t i = 0; i < out->status.size(); ++i) {
    if (out->status[i] != SubsetStatus::kConverged) {
      for (auto* g : {&out->dudx, &out->dudy, &out->dvdx, &out->dvdy}) (*g)[i] = kNaN;
    }
    gradient_last[i] = {out->dudx[i], out->dudy[i], out->dvdx[i], out->dvdy[i]};
  }
}

void Correlator::Impl::AdvanceReference(const cv::Mat& image, std::unique_ptr<Frame> frame,
                                        const std::vector<Attempt>& at,
                                        const std::vector<cv::Point2d>& pos, FrameResult* out) {
  FrameView storage;
  if (policy->MakesFrameTheReference(View(out->frame, at, &storage))) {
    // The frame just solved becomes the reference.
    MoveReferencePoints(pos, gradient_last);
    BuildReference(out->frame, image, &frame->spline, frame->Float(), out);
    ++summary.reference_updates;
    Recycle(std::move(last_frame));
    Recycle(std::move(frame));
  } else if (policy->KeepsLastFrame()) {
    Recycle(std::move(last_frame));
    last_frame = std::move(frame);
  } else {
    Recycle(std::move(frame));
  }
}

void Correlator::Impl::Recycle(std::unique_ptr<Frame> frame) {
  if (!frame) return;
  frame->raw.release();  // The images belong to the caller (or the reference).
  frame->image32.release();
  spare_frame = std::move(frame);
}

std::unique_ptr<Frame> Correlator::Impl::NewFrame() {
  return spare_frame ? std::move(spare_frame) : std::make_unique<Frame>();
}

void Correlator::Impl::AddToSummary(const FrameResult& out) {
  const int n = static_cast<int>(out.status.size());
  DicSummary& s = summary;
  ++s.frames;
  for (int i = 0; i < n; ++i) ++s.status_counts[static_cast<int>(out.status[i])];
  s.valid_fraction =
      double(s.status_counts[static_cast<int>(SubsetStatus::kConverged)]) / (double(n) * s.frames);
  s.mean_iterations = converged_sum ? double(iteration_sum) / converged_sum : 0;
  s.searches += out.searches;
  s.seconds_coefficients += out.seconds_coefficients;
  s.seconds_reference += out.seconds_reference;
  s.seconds_initial_guess += out.seconds_initial_guess;
  s.seconds_icgn += out.seconds_icgn;
  s.seconds_total += out.seconds_total;
}

FrameResult Correlator::Correlate(const cv::Mat& image) {
  Impl& m = *impl_;
  assert(!m.initial.empty() && "Correlator::SetReference() must come before Correlate()");
  m.CheckImage(image, "deformed image");
  WallTimer total;
  FrameResult out;
  out.frame = m.last_index + 1;
  const int n = static_cast<int>(m.initial.size());
  if (m.options.mode == SequenceMode::kPairs) {
    // An independent image: nothing is predicted from the images before it (seeds and
    // propagation, as for the first frame after the reference).
    m.pos_last.assign(n, cv::Point2d(kNaN, kNaN));
    m.params_valid.assign(n, 0);
  }
  // First frame after the reference: positions at frame 0 are the prediction base only through
  // the seeds; afterwards constant-velocity prediction.
  WallTimer timer;
  std::unique_ptr<Frame> frame = m.NewFrame();
  m.MakeFrame(image, out.frame, frame.get());
  out.seconds_coefficients += timer.ElapsedSeconds();
  std::vector<Attempt> at = m.Solve(*frame, &out);
  m.RedoIfThePolicyAsks(*frame, &at, &out);
  out.reference_frame = m.ref.frame;

  // Results: tracked positions and accumulated displacements.
  std::vector<cv::Point2d> pos = m.StoreResults(at, &out);
  m.PostCheck(&at, &pos, &out);
  m.KeepGradients(&out);
  m.pos_prev = m.pos_last;
  m.pos_last = pos;
  if (out.frame == 1) {
    // No velocity from the reference frame on: a predicted increment needs two solved frames.
    for (int i = 0; i < n; ++i) m.pos_prev[i] = m.initial[i];
  }
  m.last_index = out.frame;
  m.AdvanceReference(image, std::move(frame), at, pos, &out);
  out.seconds_total = total.ElapsedSeconds();
  m.AddToSummary(out);
  return out;
}

int Correlator::subsets() const { return static_cast<int>(impl_->initial.size()); }
const std::vector<cv::Point2d>& Correlator::positions() const { return impl_->initial; }
int Correlator::rows() const { return impl_->ny; }
int Correlator::cols() const { return impl_->nx; }
const DicSummary& Correlator::summary() const { return impl_->summary; }
const DicOptions& Correlator::options() const { return impl_->options; }

}  // namespace impactdic
