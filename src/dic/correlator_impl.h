// Private to src/dic: the state of a Correlator and the steps of a frame, one idea per file.
//   correlator.cc         the driver: SetReference, Correlate, the accessors;
//   subset_grid.cc        the grid: ROI, mask, subset centres, the data's full scale;
//   frame_images.cc       the images correlation reads: the reference, each deformed frame;
//   propagation.cc        one frame against the reference: predictions, reliability-guided
//                         propagation, integer searches (FrameSolver);
//   orphans.cc            subsets lost at a reference update, tracked against an older one;
//   reference_rescue.cc   when the reference moves, and the `auto` policy's rescue test;
//   result_store.cc       a frame's results into FrameResult, its post-checks, the summary;
//   dic_summary.cc        DicSummary's reports.
#ifndef IMPACTDIC_SRC_DIC_CORRELATOR_IMPL_H_
#define IMPACTDIC_SRC_DIC_CORRELATOR_IMPL_H_

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "icgn.h"
#include "impactdic/core/memory.h"
#include "impactdic/core/numeric.h"
#include "impactdic/core/progress.h"
#include "impactdic/dic/bspline.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/dic/reference_update.h"

namespace impactdic {
namespace internal {

// tbb::parallel_for over [0, n) in blocks of kStopBlock indices with a stop point
// (core/progress.h) after each, so that a caller can stop a loop over every subset within about
// 0.1 s (a block of 4096 subsets on 2 threads). Only for loops whose iterations do not depend on
// each other: the results are those of one parallel_for. range_body(range) gets each thread's
// tbb::blocked_range<int> (to look ahead within it); ParallelForWithStops' body one index.
constexpr int kStopBlock = 4096;
template <typename RangeBody>
void ParallelRangesWithStops(int n, const RangeBody& range_body) {
  for (int begin = 0; begin < n; begin += kStopBlock) {
    tbb::parallel_for(tbb::blocked_range<int>(begin, std::min(n, begin + kStopBlock)), range_body);
    StopPoint();
  }
}
template <typename Body>
void ParallelForWithStops(int n, const Body& body) {
  ParallelRangesWithStops(n, [&body](const tbb::blocked_range<int>& range) {
    for (int i = range.begin(); i != range.end(); ++i) body(i);
  });
}

// The k in [0, n) with keep(k), in increasing order: blocks of k tested on the pool's threads,
// their lists joined in order (the solver's scans of the subsets, which read each one's Attempt:
// ~0.5 ms a scan of the 1920x1440 pair on one thread).
template <typename Keep>
std::vector<int> IndicesWhere(int n, const Keep& keep) {
  constexpr int kBlock = 2048;
  std::vector<std::vector<int>> found((n + kBlock - 1) / kBlock);
  tbb::parallel_for(0, static_cast<int>(found.size()), [&](int b) {
    for (int k = b * kBlock; k < std::min(n, (b + 1) * kBlock); ++k)
      if (keep(k)) found[b].push_back(k);
  });
  std::vector<int> out;
  for (const std::vector<int>& block : found) out.insert(out.end(), block.begin(), block.end());
  return out;
}

inline bool Usable(SubsetStatus s) { return s == SubsetStatus::kConverged; }

// A reference subset centred on the pixel nearest to the material point `pos` (the offset is
// kept, so the displacement of `pos` itself is read from the warp).
SubsetRef CentredSubset(cv::Point2d pos);

// The saturation level of the sequence's data: of `data_bits` (DicOptions::data_bits) when
// given, else of the first reference's (io DataBits: 255, 4095 for 12-bit data in 16-bit
// containers, 65535). The contrast and featureless limits are relative to it, so the same
// speckle as 12-bit or 16-bit data passes the same subsets. Float data has no saturation level:
// its largest magnitude in the first reference stands for it (just above it, so that no pixel
// counts as saturated at the top), so float images scaled to 0..1 or to 0..255 pass the same
// subsets as their 8-bit original.
double FullScale(const cv::Mat& raw, int data_bits);

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
  // Filled by BuildReference's parallel loop.
  FilledInParallel<SubsetRef> subsets;
  FilledInParallel<double> hinv;
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
Gradient ComposeGradients(const Gradient& second, const Gradient& first);

// What one subset carries from frame to frame (Correlator::Impl::tracks, one per grid point, in
// the grid's row-major order).
struct SubsetTrack {
  bool active = true;                                 // Still tracked.
  SubsetStatus permanent = SubsetStatus::kConverged;  // Its status once no longer tracked.
  Orphan orphan;                                      // ref == nullptr unless orphaned.
  cv::Point2d ref_pos;                                // Tracked point in the current reference.
  // Positions of the tracked point in the last two frames (NaN = unknown), and the last warp
  // relative to the current reference.
  cv::Point2d pos_last{kNaN, kNaN}, pos_prev{kNaN, kNaN};
  bool params_valid = false;
  Params params_last{};
  // options.keep_warp_gradient (unused otherwise): the displacement gradient since the first
  // reference at the tracked point when its current reference (ref_pos, or its orphan's) was
  // made (F_prev - I; 0 for the first reference), and the gradient in the last solved frame (NaN
  // where not converged), which becomes the former if that frame becomes the reference.
  Gradient gradient_at_ref{}, gradient_last = kNoGradient;
};

// One subset's attempts in a frame.
struct Attempt {
  IcgnResult r;
  bool solved = false, searched = false, propagated = false;
};
// One per subset, set up by a parallel loop (FrameSolver).
using Attempts = FilledInParallel<Attempt>;

}  // namespace internal

struct Correlator::Impl {
  using Attempt = internal::Attempt;
  using Attempts = internal::Attempts;
  using Frame = internal::Frame;

  DicOptions options;
  internal::Shape shape;
  int half = 12, size = 25;
  int nx = 0, ny = 0;
  cv::Size image_size;
  int depth = CV_8U;
  double full_scale = 255;  // FullScale of the first reference: the range of the sequence's data.
  std::vector<cv::Point2d> initial;           // X0: centres in the first reference (positions()).
  std::vector<internal::SubsetTrack> tracks;  // Per subset.
  internal::Reference ref;
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

  // subset_grid.cc: checks the first reference and the grid options, lays out the grid
  // (nx, ny, initial) and resets every subset's track (masked subsets untracked).
  void SetUpGrid(const cv::Mat& image);

  // frame_images.cc
  void BuildReference(int frame_index, const cv::Mat& raw, const BsplineImage* spline_in,
                      const cv::Mat& image32, FrameResult* timing);
  void MakeFrame(const cv::Mat& raw, int index, Frame* frame);
  void CheckImage(const cv::Mat& image, const char* what) const;

  // propagation.cc: solves every tracked subset of `frame` against the current reference, then
  // the orphans (FrameSolver).
  Attempts Solve(Frame& frame, FrameResult* out);
  class FrameSolver;
  // The search template of subset s: `image32` (the reference's search image) over its
  // footprint, a view; empty if the footprint leaves the image.
  cv::Mat SearchTemplate(const internal::SubsetRef& s, const cv::Mat& image32) const;
  // Integer-pixel ZNCC search of `templ` (SearchTemplate; empty: not found) around the guess.
  bool Search(const internal::SubsetRef& s, const cv::Mat& templ, Frame& frame, double gu,
              double gv, cv::Mat* scratch_mat, internal::Params* p0) const;

  // orphans.cc
  void SolveOrphans(Frame& frame, Attempts& at, FrameResult* out);
  // Makes the tracked points in the last solved frame (pos_last, NaN = not found) the reference
  // points, their gradient_last their gradients since the first reference.
  void MoveReferencePoints();
  // What orphan i keeps of the current reference (OrphanRef).
  std::shared_ptr<const internal::OrphanRef> KeepForOrphan(int i) const;

  // reference_rescue.cc
  struct FrameView {  // Storage of a SolvedFrame.
    std::vector<SubsetStatus> status;
    std::vector<float> zncc;
    std::vector<char> trackable;
  };
  SolvedFrame View(int frame_index, const Attempts& at, FrameView* storage) const;
  std::vector<char> RescuedByLastFrame(const std::vector<int>& which, const Attempts& at,
                                       const Frame& frame, FrameResult* out);
  // Redoes the frame against the last solved frame when the policy asks and that rescues one of
  // the subsets it named.
  void RedoIfThePolicyAsks(Frame& frame, Attempts* at, FrameResult* out);
  // Makes the frame the reference if the policy says so (its tracked positions are the tracks'
  // pos_last), else keeps it if the policy needs it.
  void AdvanceReference(const cv::Mat& image, std::unique_ptr<Frame> frame, const Attempts& at,
                        FrameResult* out);

  // result_store.cc
  // The results of `at` into out (displacements, ZNCC, sigma, status), the warps kept for the
  // next prediction; returns the tracked positions (NaN where not converged).
  std::vector<cv::Point2d> StoreResults(const Attempts& at, FrameResult* out);
  // The post-checks on the stored results: the continuity check (options.continuity), then the
  // normalized median test (options.outliers). Flagged subsets become `discontinuous` or
  // `outlier` in out and `at`, untracked in this frame (NaN position) like other failures.
  void PostCheck(Attempts* at, std::vector<cv::Point2d>* pos, FrameResult* out);
  // Makes the subsets that a post-check set to `flagged` in out failures in `at` too.
  void Untrack(SubsetStatus flagged, Attempts* at, std::vector<cv::Point2d>* pos,
               const FrameResult& out);
  // options.keep_warp_gradient: NaN gradients where a post-check failed the subset, and the
  // frame's gradients kept as gradient_last.
  void KeepGradients(FrameResult* out);
  // The frame's positions `pos` become the tracks' last positions (the last ones the previous).
  void KeepPositions(const std::vector<cv::Point2d>& pos, int frame);
  void AddToSummary(const FrameResult& out);
};

}  // namespace impactdic

#endif  // IMPACTDIC_SRC_DIC_CORRELATOR_IMPL_H_
