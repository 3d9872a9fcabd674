// Orphans: subsets lost at a reference update, tracked against the part of the reference they
// were last found in (OrphanRef) until they are found again.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <vector>

#include "correlator_impl.h"
#include "impactdic/core/timer.h"

namespace impactdic {

using internal::Attempt;
using internal::IcgnResult;
using internal::Orphan;
using internal::OrphanRef;
using internal::Params;
using internal::RefImages;
using internal::SubsetRef;
using internal::Usable;

// Orphans (lost at a reference update) are tried against the reference they were last found in.
// Guess: the position found in the last frame; else the mean accumulated displacement of the
// solved tracked subsets among the 3x3 neighbours in this frame; else no motion. If IC-GN fails
// from it, an integer search around it. Runs after the tracked subsets are solved.
void Correlator::Impl::SolveOrphans(Frame& frame, Attempts& at, FrameResult* out) {
  const int n = static_cast<int>(initial.size());
  std::vector<int> list;
  for (int i = 0; i < n; ++i)
    if (!tracks[i].active && tracks[i].orphan.ref && Usable(tracks[i].orphan.ref->subset.status))
      list.push_back(i);
  if (list.empty()) return;
  WallTimer timer;
  frame.Float();
  std::vector<char> searched(list.size(), 0);
  tbb::parallel_for(0, static_cast<int>(list.size()), [&](int k) {
    const int i = list[k];
    const Orphan& o = tracks[i].orphan;
    const OrphanRef& old = *o.ref;
    const SubsetRef& s = old.subset;
    cv::Point2d expected = tracks[i].pos_last;
    if (std::isnan(expected.x)) {
      const int r = i / nx, c = i % nx;
      cv::Point2d sum(0, 0);
      int count = 0;
      for (int rr = std::max(0, r - 1); rr <= std::min(ny - 1, r + 1); ++rr) {
        for (int cc = std::max(0, c - 1); cc <= std::min(nx - 1, c + 1); ++cc) {
          const int j = rr * nx + cc;
          if (!tracks[j].active || !at[j].solved) continue;
          double du, dv;
          internal::Displacement(shape, at[j].r.p, ref.subsets[j].ox, ref.subsets[j].oy, &du, &dv);
          sum += tracks[j].ref_pos + cv::Point2d(du, dv) - initial[j];
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

// Before a reference update to the frame whose tracked positions are the tracks' pos_last:
// tracked subsets move their reference point there; those not found in it become orphans of the
// current reference (status `lost` while they fail); orphans found in it rejoin the tracked
// subsets.
void Correlator::Impl::MoveReferencePoints() {
  const int n = static_cast<int>(initial.size());
  // A subset found in the new reference composes its later warps with its gradient there; a lost
  // one keeps the gradient of the reference it stays tracked against.
  const auto move = [&](internal::SubsetTrack& t) {
    t.ref_pos = t.pos_last;
    if (options.keep_warp_gradient) t.gradient_at_ref = t.gradient_last;
  };
  std::vector<int> lost;
  for (int i = 0; i < n; ++i) {
    internal::SubsetTrack& t = tracks[i];
    const bool found = !std::isnan(t.pos_last.x);
    if (!t.active) {
      if (t.orphan.ref && found) {
        t.active = true;
        t.permanent = SubsetStatus::kConverged;
        move(t);
        t.orphan = Orphan{};
      }
      continue;
    }
    if (found)
      move(t);
    else
      lost.push_back(i);
  }
  // What each lost subset needs of the current reference is copied out of it (KeepForOrphan);
  // the reference itself is rebuilt for the new frame.
  for (int i : lost) {
    internal::SubsetTrack& t = tracks[i];
    t.active = false;
    // A subset the reference could not use (low contrast, saturated, out of the image) was never
    // tracked: it keeps the reason, not `lost`.
    const SubsetStatus own = ref.subsets[i].status;
    t.permanent = Usable(own) ? SubsetStatus::kLost : own;
    t.orphan = Orphan{KeepForOrphan(i), t.ref_pos};
  }
  std::size_t bytes = 0;
  for (const internal::SubsetTrack& t : tracks)
    if (t.orphan.ref) bytes += t.orphan.ref->Bytes();
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
  kept->images.noise = im.noise;
  kept->images.range = im.range;
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

}  // namespace impactdic
