// The images correlation reads: the reference (its images in the region or patch layout and
// every subset's reference data) and each deformed frame (its B-spline over the reach of the
// subsets), with the frame buffers reused from frame to frame.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "correlator_impl.h"
#include "impactdic/core/error.h"
#include "impactdic/core/memory.h"
#include "impactdic/core/timer.h"

namespace impactdic {

using internal::RefImages;
using internal::SubsetRef;

namespace {
// Patches per row of the reference images' patch layout (RefImages).
constexpr int kPatchColumns = 64;
}  // namespace

SubsetRef internal::CentredSubset(cv::Point2d pos) {
  SubsetRef s;
  s.cx = static_cast<int>(std::lround(pos.x));
  s.cy = static_cast<int>(std::lround(pos.y));
  s.ox = pos.x - s.cx;
  s.oy = pos.y - s.cy;
  return s;
}

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
  for (const internal::SubsetTrack& t : tracks) {
    if (!t.active) continue;
    x0 = std::min(x0, t.ref_pos.x);
    x1 = std::max(x1, t.ref_pos.x);
    y0 = std::min(y0, t.ref_pos.y);
    y1 = std::max(y1, t.ref_pos.y);
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
  // The image's noise and range (a serial pass over sampled bands) on another thread meanwhile.
  internal::ImageLevels levels;
  tbb::task_group levels_task;
  levels_task.run([&] { levels = internal::ImageLevelsOf(raw, region); });
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
  levels_task.wait();
  im.noise = levels.noise;
  im.range = levels.range;
  const long long tracked = std::count_if(tracks.begin(), tracks.end(),
                                          [](const internal::SubsetTrack& t) { return t.active; });
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
    if (im.f.size() != im.region.size() || im.f.type() != CV_32F) {
      im.f.create(im.region.size(), CV_32F);
      AdviseHugePages(im.f.data, im.f.total() * im.f.elemSize());
    }
    // In bands of at least 4 MiB on the threads (the first touch of a fresh image's huge pages
    // too: a smaller band would share its pages with its neighbour's).
    const cv::Mat source = raw(im.region);
    const int band_rows = std::max<int>(1, (4 << 20) / static_cast<int>(im.f.step[0]));
    tbb::parallel_for(tbb::blocked_range<int>(0, source.rows, band_rows),
                      [&](const tbb::blocked_range<int>& rows) {
                        const cv::Range band(rows.begin(), rows.end());
                        source.rowRange(band).convertTo(im.f.rowRange(band), CV_32F);
                      });
  }
  // Several MB each for a dense grid: allocated, advised, then filled.
  const std::size_t hinv_size = static_cast<std::size_t>(n) * shape.n * shape.n;
  ref.subsets.reserve(n);
  ref.hinv.reserve(hinv_size);
  AdviseHugePages(ref.subsets.data(), ref.subsets.capacity() * sizeof(SubsetRef));
  AdviseHugePages(ref.hinv.data(), ref.hinv.capacity() * sizeof(double));
  // Every element is assigned by the loop (FilledInParallel).
  ref.subsets.resize(n);
  ref.hinv.resize(hinv_size);
  internal::ParallelForWithStops(n, [&](int i) {
    SubsetRef& s = ref.subsets[i];
    s = SubsetRef{};
    double* hinv = &ref.hinv[static_cast<std::size_t>(i) * shape.n * shape.n];
    std::fill_n(hinv, shape.n * shape.n, 0.0);
    if (!tracks[i].active) {
      s.status = tracks[i].permanent;
      return;
    }
    s = internal::CentredSubset(tracks[i].ref_pos);
    const cv::Rect box(s.cx - half, s.cy - half, size, size);
    if (patches && (box & im.region) == box) {  // Else PrepareSubset finds it out of the image.
      s.patch = i;
      const cv::Rect patch = im.Patch(i);
      cv::Mat f = im.f(patch), gx = im.gx(patch), gy = im.gy(patch);
      raw(box).convertTo(f, CV_32F);
      spline->NodeGradients(box, &gx, &gy);
    }
    internal::PrepareSubset(shape, im, options.icgn, &s, hinv);
  });
  for (internal::SubsetTrack& t : tracks) t.params_valid = false;
  if (timing) timing->seconds_reference += timer.ElapsedSeconds() - coef_seconds;
}

void Correlator::Impl::MakeFrame(const cv::Mat& raw, int index, Frame* out) {
  Frame& f = *out;
  f.index = index;
  f.raw = raw;
  // Region the subsets can reach: their reference positions grown by the subset half size, the
  // search radius and the largest displacement seen so far.
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const internal::SubsetTrack& t : tracks) {
    if (!t.active && !t.orphan.ref) continue;
    const cv::Point2d p = t.ref_pos;
    x0 = std::min(x0, p.x);
    x1 = std::max(x1, p.x);
    y0 = std::min(y0, p.y);
    y1 = std::max(y1, p.y);
    if (!std::isnan(t.pos_last.x)) {
      x0 = std::min(x0, t.pos_last.x);
      x1 = std::max(x1, t.pos_last.x);
      y0 = std::min(y0, t.pos_last.y);
      y1 = std::max(y1, t.pos_last.y);
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

void Correlator::Impl::Recycle(std::unique_ptr<internal::Frame> frame) {
  if (!frame) return;
  frame->raw.release();  // The images belong to the caller (or the reference).
  frame->image32.release();
  spare_frame = std::move(frame);
}

std::unique_ptr<internal::Frame> Correlator::Impl::NewFrame() {
  return spare_frame ? std::move(spare_frame) : std::make_unique<Frame>();
}

}  // namespace impactdic
