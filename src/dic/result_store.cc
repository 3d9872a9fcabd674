// A frame's results: stored into FrameResult (accumulated displacements, ZNCC, uncertainty,
// status, warp gradients), the post-checks that untrack flagged subsets, the positions kept for
// the next prediction, and the run's summary.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <cstddef>
#include <vector>

#include "correlator_impl.h"
#include "impactdic/dic/continuity_check.h"
#include "impactdic/dic/outlier_check.h"

namespace impactdic {

using internal::Attempt;
using internal::Gradient;
using internal::IcgnResult;
using internal::Params;
using internal::SubsetRef;

internal::Gradient internal::ComposeGradients(const Gradient& second, const Gradient& first) {
  const auto& [a, b, c, d] = second;
  const auto& [e, f, g, h] = first;
  return {a + e + a * e + b * g, b + f + a * f + b * h, c + g + c * e + d * g,
          d + h + c * f + d * h};
}

std::vector<cv::Point2d> Correlator::Impl::StoreResults(const Attempts& at, FrameResult* out) {
  const int n = static_cast<int>(at.size());
  out->u_px.assign(n, kNaN);
  out->v_px.assign(n, kNaN);
  out->zncc.assign(n, kNaNf);
  out->iterations.assign(n, 0);
  out->sigma_px.assign(n, kNaNf);
  out->sigma_u_px = out->sigma_px;
  out->sigma_v_px = out->sigma_px;
  out->status.resize(n);
  const bool gradients = options.keep_warp_gradient;
  if (gradients)
    for (auto* g : {&out->dudx, &out->dudy, &out->dvdx, &out->dvdy}) g->assign(n, kNaN);
  std::vector<cv::Point2d> pos(n, cv::Point2d(kNaN, kNaN));
  // Each subset on its own, in parallel; the iteration and convergence counts summed per block
  // (integers: the same totals in any order).
  std::atomic<long long> iterations{0}, converged{0};
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 1024), [&](const tbb::blocked_range<int>& range) {
    long long block_iterations = 0, block_converged = 0;
    for (int i = range.begin(); i != range.end(); ++i) {
      const IcgnResult& r = at[i].r;
      out->status[i] = r.status;
      out->iterations[i] = r.iterations;
      if (r.iterations > 0) out->zncc[i] = r.zncc;
      if (r.status != SubsetStatus::kConverged) {
        tracks[i].params_valid = false;
        continue;
      }
      const internal::Orphan& orphan = tracks[i].orphan;
      const SubsetRef& s = orphan.ref ? orphan.ref->subset : ref.subsets[i];
      double du, dv;
      internal::Displacement(shape, r.p, s.ox, s.oy, &du, &dv);
      pos[i] = (orphan.ref ? orphan.ref_pos : tracks[i].ref_pos) + cv::Point2d(du, dv);
      out->u_px[i] = pos[i].x - initial[i].x;
      out->v_px[i] = pos[i].y - initial[i].y;
      out->sigma_u_px[i] = r.sigma_u_px;
      out->sigma_v_px[i] = r.sigma_v_px;
      out->sigma_px[i] = r.sigma_px;
      if (gradients) {
        // The warp's gradient at the tracked point (the subset centre moved by (ox, oy)), against
        // the reference the subset was solved in, composed with the gradient it had there.
        const Params at_point = internal::Transfer(shape, r.p, s.ox, s.oy);
        const Gradient h = internal::ComposeGradients(
            {at_point[1], at_point[2], at_point[shape.nm + 1], at_point[shape.nm + 2]},
            tracks[i].gradient_at_ref);
        out->dudx[i] = h[0];
        out->dudy[i] = h[1];
        out->dvdx[i] = h[2];
        out->dvdy[i] = h[3];
      }
      tracks[i].params_last = r.p;
      tracks[i].params_valid = !orphan.ref;
      block_iterations += r.iterations;
      ++block_converged;
    }
    iterations += block_iterations;
    converged += block_converged;
  });
  iteration_sum += iterations;
  converged_sum += converged;
  return pos;
}

void Correlator::Impl::PostCheck(Attempts* at, std::vector<cv::Point2d>* pos, FrameResult* out) {
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

void Correlator::Impl::Untrack(SubsetStatus flagged, Attempts* at, std::vector<cv::Point2d>* pos,
                               const FrameResult& out) {
  for (std::size_t i = 0; i < at->size(); ++i) {
    IcgnResult& r = (*at)[i].r;
    if (out.status[i] != flagged || r.status != SubsetStatus::kConverged) continue;
    r.status = flagged;
    (*pos)[i] = cv::Point2d(kNaN, kNaN);
    tracks[i].params_valid = false;
    iteration_sum -= r.iterations;
    --converged_sum;
  }
}

void Correlator::Impl::KeepGradients(FrameResult* out) {
  if (!options.keep_warp_gradient) return;
  for (std::size_t i = 0; i < out->status.size(); ++i) {
    if (out->status[i] != SubsetStatus::kConverged) {
      for (auto* g : {&out->dudx, &out->dudy, &out->dvdx, &out->dvdy}) (*g)[i] = kNaN;
    }
    tracks[i].gradient_last = {out->dudx[i], out->dudy[i], out->dvdx[i], out->dvdy[i]};
  }
}

void Correlator::Impl::KeepPositions(const std::vector<cv::Point2d>& pos, int frame) {
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    internal::SubsetTrack& t = tracks[i];
    t.pos_prev = t.pos_last;
    t.pos_last = pos[i];
    // No velocity from the reference frame on: a predicted increment needs two solved frames.
    if (frame == 1) t.pos_prev = initial[i];
  }
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

}  // namespace impactdic
