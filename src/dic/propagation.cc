// One frame against the reference: every tracked subset from its prediction, then
// reliability-guided propagation with integer searches at seeds (FrameSolver), then the orphans.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

#include "correlator_impl.h"
#include "impactdic/core/progress.h"
#include "impactdic/core/timer.h"

namespace impactdic {

namespace {

// Solves a x = b for a symmetric positive definite 3x3 `a` by Gaussian elimination without
// pivoting (its pivots are positive), in this order of operations. Eigen's decompositions (LLT,
// LDLT, partially or fully pivoted LU) agree with it to 3e-13 px on FitGuess' systems but not bit
// for bit, and IC-GN carries the guess's last bits into some results of a sequence: with
// fullPivLu, up to 1.6e-6 px in 405 of the 107,313 valid results of the 10th frame of
// real-sand/test48. This order keeps the results of earlier versions.
Eigen::Vector3d SolveSymmetric3(Eigen::Matrix3d a, Eigen::Vector3d b) {
  for (int col = 0; col < 3; ++col) {
    for (int row = col + 1; row < 3; ++row) {
      const double f = a(row, col) / a(col, col);
      for (int k = col; k < 3; ++k) a(row, k) -= f * a(col, k);
      b(row) -= f * b(col);
    }
  }
  Eigen::Vector3d x;
  for (int row = 2; row >= 0; --row) {
    double v = b(row);
    for (int k = row + 1; k < 3; ++k) v -= a(row, k) * x(k);
    x(row) = v / a(row, row);
  }
  return x;
}

}  // namespace

using internal::Attempt;
using internal::IcgnResult;
using internal::Params;
using internal::SubsetRef;
using internal::Usable;

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
    tbb::parallel_for(0, n_, [&](int i) {  // at_ is assigned here (Attempts).
      const internal::SubsetTrack& t = m.tracks[i];
      usable_[i] = t.active && Usable(m.ref.subsets[i].status);
      at_[i] = Attempt{};
      at_[i].r.status =
          t.active ? (usable_[i] ? SubsetStatus::kNotFound : m.ref.subsets[i].status) : t.permanent;
    });
  }

  Attempts Run() {
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
  // body(k, guess(k)) for k = 0 .. list.size() - 1 as ParallelForWithStops runs it; before each,
  // the subset list[k + 1] that the same thread solves next is prefetched (PrefetchSubset) at the
  // translation of guess(k + 1), each guess computed once (a prediction, or a solved neighbour's
  // warp as a hint).
  template <typename Guess, typename Body>
  void ForEachPrefetched(const std::vector<int>& list, const Guess& guess, const Body& body) {
    const int nm = m_.shape.nm;
    internal::ParallelRangesWithStops(
        static_cast<int>(list.size()), [&](const tbb::blocked_range<int>& range) {
          Params next = guess(range.begin());
          for (int k = range.begin(); k != range.end(); ++k) {
            const Params current = next;
            if (k + 1 < range.end()) {
              next = guess(k + 1);
              internal::PrefetchSubset(m_.shape, m_.ref.images, m_.ref.subsets[list[k + 1]],
                                       frame_.view, next[0], next[nm]);
            }
            body(k, current);
          }
        });
  }

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
    const std::vector<internal::SubsetTrack>& all = m_.tracks;
    const internal::SubsetTrack& t = all[i];
    if (std::isnan(t.pos_last.x)) return false;
    cv::Point2d pred = t.pos_last;
    if (!std::isnan(t.pos_prev.x)) {
      const int r = i / grid_nx, c = i % grid_nx;
      cv::Point2d velocity(0, 0);
      int count = 0;
      for (int rr = std::max(0, r - 1); rr <= std::min(grid_ny - 1, r + 1); ++rr) {
        for (int cc = std::max(0, c - 1); cc <= std::min(grid_nx - 1, c + 1); ++cc) {
          const int j = rr * grid_nx + cc;
          const internal::SubsetTrack& tj = all[j];
          if (std::isnan(tj.pos_last.x) || std::isnan(tj.pos_prev.x)) continue;
          velocity += tj.pos_last - tj.pos_prev;
          ++count;
        }
      }
      pred += velocity / count;
    }
    const SubsetRef& s = m_.ref.subsets[i];
    Params p = t.params_valid ? t.params_last : Params{};
    double du, dv;
    internal::Displacement(m_.shape, p, s.ox, s.oy, &du, &dv);
    const cv::Point2d d = pred - t.ref_pos;
    p[0] += d.x - du;
    p[m_.shape.nm] += d.y - dv;
    *p0 = p;
    return true;
  }

  // 1. Prediction from previous increments, all subsets in parallel.
  void SolveFromPredictions() {
    timer_.Restart();
    const std::vector<int> list = internal::IndicesWhere(
        n_, [&](int i) { return usable_[i] && !std::isnan(m_.tracks[i].pos_last.x); });
    // Each subset starts from its prediction, which is also the hint of its prefetch (on 4k
    // frames at step 50, no two subsets share a cache line: without it each waits for memory).
    ForEachPrefetched(
        list,
        [&](int k) {
          Params p0{};  // Every listed subset has a prediction (pos_last is known).
          Predict(list[k], &p0);
          return p0;
        },
        [&](int k, const Params& p0) {
          const int i = list[k];
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
  // The subsets i on the lattice of `stride` with keep(i), in increasing order (IndicesWhere): the
  // waves' scans visit the lattice alone (a scan of every subset read each one's Attempt).
  template <typename Keep>
  std::vector<int> OnLatticeWhere(int stride, const Keep& keep) const {
    const int cols = (m_.nx + stride - 1) / stride, rows = (m_.ny + stride - 1) / stride;
    std::vector<int> found = internal::IndicesWhere(cols * rows, [&](int k) {
      return keep((k / cols) * stride * m_.nx + (k % cols) * stride);
    });
    for (int& k : found) k = (k / cols) * stride * m_.nx + (k % cols) * stride;
    return found;
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
      Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
      Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
      for (int k = 0; k < count; ++k) {
        const Params& pj = at_[from[k]].r.p;
        const Eigen::Vector3d d(1, double(m_.ref.subsets[from[k]].cx - si.cx),
                                double(m_.ref.subsets[from[k]].cy - si.cy));
        a += d * d.transpose();
        rhs += d * pj[o];
        for (int q = 1; q < 3; ++q) {
          a(q, q) += gradient_weight;
          rhs(q) += gradient_weight * pj[o + q];
        }
        for (int q = 3; q < nm; ++q) p0[o + q] += pj[o + q] / count;
      }
      const Eigen::Vector3d x = SolveSymmetric3(a, rhs);
      for (int q = 0; q < 3; ++q) p0[o + q] = x(q);
    }
    return p0;
  }

  // 2. Reliability-guided propagation in deterministic waves on the lattice of `stride`, with
  // searches at seeds when no wave can start.
  // A stop point after each wave (core/progress.h).
  void Propagate(int stride) {
    while (PropagateWave(stride) || SearchSeeds(stride)) StopPoint();
  }

  // One wave: every unsolved lattice subset with a solved neighbour starts from it (stride 1:
  // its warp; coarser: the fit of all solved neighbours); those that fail get their own search
  // around that guess. false if no subset had a solved neighbour.
  bool PropagateWave(int stride) {
    const int grid_nx = m_.nx, grid_ny = m_.ny;
    // Solved neighbours are listed before the wave runs (the wave changes `at_`).
    std::vector<int> frontier, best, neighbour_count;
    std::vector<std::array<int, 8>> neighbours;
    const std::vector<int> open = OnLatticeWhere(stride, [&](int i) {
      return usable_[i] && !at_[i].solved && !at_[i].propagated && SolvedNeighbour(i, stride) >= 0;
    });
    for (const int i : open) {
      const int j = SolvedNeighbour(i, stride);
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
    const auto& subsets = m_.ref.subsets;
    timer_.Restart();
    ForEachPrefetched(
        frontier, [&](int k) { return at_[best[k]].r.p; },
        [&](int k, const Params& /*hint*/) {
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
    // Not those whose guess from a solved neighbour left the image: nothing to search for.
    candidates = OnLatticeWhere(stride, [&](int i) {
      return usable_[i] && !at_[i].solved && !at_[i].searched &&
             !(at_[i].propagated && at_[i].r.status == SubsetStatus::kOutOfImage);
    });
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
    const std::vector<int> fill = internal::IndicesWhere(n_, [&](int i) {
      return usable_[i] && !at_[i].solved && !at_[i].searched && !OnLattice(i, stride);
    });
    std::vector<int> node;  // A lattice node next to each (its guess's scale).
    node.reserve(fill.size());
    for (const int i : fill) {
      const int r = i / grid_nx, c = i % grid_nx;
      node.push_back((r - r % stride) * grid_nx + (c - c % stride));
    }
    timer_.Restart();
    ForEachPrefetched(
        fill, [&](int k) { return at_[node[k]].r.p; },
        [&](int k, const Params& /*hint*/) {
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
  Attempts at_;
  std::vector<char> usable_;
  WallTimer timer_;
};

Correlator::Impl::Attempts Correlator::Impl::Solve(Frame& frame, FrameResult* out) {
  return FrameSolver(*this, frame, out).Run();
}

}  // namespace impactdic
