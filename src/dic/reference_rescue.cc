// When the reference moves: the policy's view of a solved frame, the update to a solved frame,
// and the `auto` policy's rescue (redo the frame against the last good frame when that rescues a
// subset that failed against the current reference).
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

#include "correlator_impl.h"
#include "impactdic/core/timer.h"

namespace impactdic {

using internal::Attempt;
using internal::IcgnResult;
using internal::Params;
using internal::RefImages;
using internal::SubsetRef;
using internal::Usable;

// For policies that redo frames (`auto`): whether the subsets `which` (failed or below
// auto_min_zncc against the current reference) would pass against the candidate reference, the
// last frame, i.e. converge with a result the policy Rescues (`auto`: ZNCC >= auto_min_zncc with
// at most a third of the decorrelation it had against the current reference). Only these subsets
// are prepared (the test costs a few subsets, not a reference), each centred on the pixel nearest
// to its tracked point in the last frame as BuildReference would, with its intensities and the
// node gradients of the last frame's spline over the subset alone (BsplineImage::NodeGradients
// over its rectangle: the values BuildReference computes there). IC-GN starts from the result
// against the current reference if it converged, else from the constant-velocity prediction.
// Subsets not tracked in the last frame cannot pass.
std::vector<char> Correlator::Impl::RescuedByLastFrame(const std::vector<int>& which,
                                                       const Attempts& at, const Frame& frame,
                                                       FrameResult* out) {
  WallTimer timer;
  const Frame& last = *last_frame;
  std::vector<char> rescued(which.size(), 0);
  tbb::parallel_for(0, static_cast<int>(which.size()), [&](int k) {
    const int i = which[k];
    const internal::SubsetTrack& t = tracks[i];
    if (std::isnan(t.pos_last.x)) return;
    SubsetRef s = internal::CentredSubset(t.pos_last);
    RefImages im;
    im.region = cv::Rect(s.cx - half, s.cy - half, size, size);
    if (!last.spline.Inside(im.region.x, im.region.y) ||
        !last.spline.Inside(im.region.x + size - 1, im.region.y + size - 1))
      return;
    last.raw(im.region).convertTo(im.f, CV_32F);
    im.full_scale = full_scale;
    im.noise = ref.images.noise;  // The camera's noise and range: the reference's.
    im.range = ref.images.range;
    // The node gradients BuildReference would give these pixels, over the subset alone.
    last.spline.NodeGradients(im.region, &im.gx, &im.gy);
    std::array<double, std::size_t{12} * 12> hinv;  // At most 12 warp parameters (quadratic).
    internal::PrepareSubset(shape, im, options.icgn, &s, hinv.data());
    if (!Usable(s.status)) return;
    // Guess: the displacement from the tracked point in the last frame to its expected position.
    cv::Point2d expected = t.pos_last;
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
      expected = t.ref_pos + cv::Point2d(du, dv);
    } else if (!std::isnan(t.pos_prev.x)) {
      expected += t.pos_last - t.pos_prev;
    }
    Params p0{};
    p0[0] = expected.x - t.pos_last.x;
    p0[shape.nm] = expected.y - t.pos_last.y;
    const IcgnResult r = internal::RunIcgn(shape, im, s, hinv.data(), frame.view, options.icgn, p0);
    rescued[k] = policy->Rescues({.status = r.status,
                                  .zncc = r.zncc,
                                  .reference_status = st,
                                  .reference_zncc = at[i].r.iterations > 0
                                                        ? std::optional<float>(at[i].r.zncc)
                                                        : std::nullopt});
  });
  out->seconds_reference += timer.ElapsedSeconds();
  return rescued;
}

SolvedFrame Correlator::Impl::View(int frame_index, const Attempts& at, FrameView* storage) const {
  const std::size_t n = at.size();
  storage->status.resize(n);
  storage->zncc.resize(n);
  storage->trackable.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    storage->status[i] = at[i].r.status;
    storage->zncc[i] = at[i].r.zncc;
    storage->trackable[i] = tracks[i].active && Usable(ref.subsets[i].status) ? 1 : 0;
  }
  return {.frame = frame_index,
          .reference_frame = ref.frame,
          .status = storage->status,
          .zncc = storage->zncc,
          .trackable = storage->trackable};
}

void Correlator::Impl::RedoIfThePolicyAsks(Frame& frame, Attempts* at, FrameResult* out) {
  if (!policy->KeepsLastFrame() || !last_frame || last_frame->index <= ref.frame) return;
  FrameView storage;
  const std::vector<int> candidates = policy->RedoCandidates(View(out->frame, *at, &storage));
  if (candidates.empty()) return;
  // The switch is made only if it rescues a candidate: one that passes against the last frame as
  // reference. Subsets covered by an object entering the view fail against both.
  const std::vector<char> rescued = RescuedByLastFrame(candidates, *at, frame, out);
  if (std::find(rescued.begin(), rescued.end(), 1) != rescued.end()) {
    // Switch to the last good frame: its tracked positions become the new reference points.
    MoveReferencePoints();
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

void Correlator::Impl::AdvanceReference(const cv::Mat& image,
                                        std::unique_ptr<internal::Frame> frame, const Attempts& at,
                                        FrameResult* out) {
  FrameView storage;
  if (policy->MakesFrameTheReference(View(out->frame, at, &storage))) {
    // The frame just solved becomes the reference.
    MoveReferencePoints();
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

}  // namespace impactdic
