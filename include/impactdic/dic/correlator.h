// Subset DIC in the style of GeoPIV-RG (docs/dic.md): a grid of Lagrangian subsets tracked
// through an image sequence with IC-GN, reliability-guided initial guesses and reference updating.
//
//   DicOptions options;                     // subset 25, step 10, bicubic, affine, auto update
//   Correlator correlator(options);
//   correlator.SetReference(ReadGreyImage("f000.tif"));
//   for (const std::string& path : deformed) {
//     FrameResult r = correlator.Correlate(ReadGreyImage(path));
//     // r.u_px[i], r.v_px[i]: accumulated displacement of subset i since the first reference
//   }
//   LogInfo("{}", correlator.summary().BriefReport());
//
// Algorithm per frame:
//  1. B-spline coefficients of the frame, only over the region the subsets can reach.
//  2. Initial guesses: in a sequence, each subset starts from the prediction of its previous
//     increments (constant velocity), all in parallel. Subsets without a prediction, or whose
//     IC-GN failed from it, are solved by reliability-guided propagation (Pan, "Reliability-guided
//     digital image correlation for image deformation measurement", Appl. Opt. 48 (2009) 1535,
//     doi:10.1364/AO.48.001535) from seed points found by an integer-pixel ZNCC search
//     (cv::matchTemplate, FFT based for large windows). The propagation runs in waves: in each
//     wave, every unsolved subset next to a solved one starts from its solved neighbours' warps;
//     the subsets of one wave are solved in parallel and committed together, so the result does
//     not depend on the thread count. The waves first cover the lattice of every second subset
//     (start: a least-squares affine fit to the solved lattice neighbours' displacements and
//     gradients); every other subset then starts from the same fit to its solved lattice
//     neighbours (2 or 4, symmetric about it), which is closer to its solution than one
//     neighbour's warp, so IC-GN needs fewer iterations. What is left is solved by waves over all
//     subsets from the best solved neighbour (highest ZNCC, ties to the lowest index),
//     transferred to its own centre. A subset that fails from its neighbour gets its own search.
//     In a sequence the prediction uses the last increment averaged over 3x3 subsets.
//  3. IC-GN (Baker & Matthews, "Lucas-Kanade 20 years on", IJCV 56 (2004) 221,
//     doi:10.1023/B:VISI.0000011205.11775.fd; Pan, Li & Tong, "Fast, robust and accurate digital
//     image correlation calculation without redundant computations", Exp. Mech. 53 (2013) 1277,
//     doi:10.1007/s11340-013-9717-6) with the ZNSSD criterion. The reference subset data
//     (mean, norm, gradient sums and the inverse Hessian) is computed once per reference.
//     Convergence: the warp increment moves every subset corner by less than
//     IcgnOptions::convergence_px; at most IcgnOptions::max_iterations iterations.
//  4. Reference updating (UpdateOptions). A new reference's subsets are centred on the nearest
//     pixel to the tracked material points, and the displacement of the tracked point (not of the
//     pixel centre) is read from the subset's warp, so the same material points are followed
//     through every update and their displacements compose exactly. `auto` switches to the last
//     frame only if that rescues a subset that decorrelated (it passes against the last frame,
//     tested on those subsets alone, keeping at most UpdateOptions::auto_rescue_decorrelation of
//     the decorrelation it had against the reference if it matched there); subsets that fail
//     against both references (covered by an
//     object entering the view, a blurred frame) keep the reference and are found again when
//     they reappear. A subset not found in the frame that becomes the reference (any mode) is
//     kept against the reference it was last found in, tried against it in every frame (`lost`
//     while not found) and rejoins at the next update after it is found.
//  5. The post-checks of the frame's results: the continuity check (DicOptions::continuity,
//     dic/continuity_check.h; off by default): subsets straddling a body edge or a shear band
//     become `discontinuous` (NaN); then the normalized median test (DicOptions::outliers,
//     dic/outlier_check.h; on by default): spurious vectors become `outlier` (NaN). Flagged
//     subsets are untracked in this frame as other failures are (no prediction from them; NaN at
//     a reference update, so `lost` against the old reference until found again) and are counted
//     in the summary. The checks run after the `auto` redo.
//  Pairs (DicOptions::mode = kPairs): every image is correlated against the first reference as
//  the first frame of a sequence is (steps 1-3, no prediction, no update).
#ifndef IMPACTDIC_DIC_CORRELATOR_H_
#define IMPACTDIC_DIC_CORRELATOR_H_

#include <algorithm>
#include <array>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/dic/options.h"

namespace impactdic {

struct FrameResult {
  int frame = 0;            // Index of the image in the sequence (0 = first reference).
  int reference_frame = 0;  // Index of the reference image this frame was correlated against.
  bool reference_updated = false;  // The reference changed while processing this frame.
  // Per subset: accumulated displacement [px] of the subset centre since the first reference
  // (x right, y down), NaN unless status == kConverged.
  std::vector<double> u_px, v_px;
  std::vector<float> zncc;  // Zero-normalised cross-correlation, NaN if not computed.
  // Estimated standard deviations of the displacement from this frame's correlation [px]
  // (least-squares covariance sigma_r^2 H^-1 of the warp's translation: u, v, and the larger of
  // both), NaN unless status == kConverged. They do not include the error carried over from an
  // earlier reference (after a reference update).
  std::vector<float> sigma_u_px, sigma_v_px, sigma_px;
  // Per subset, only with DicOptions::keep_warp_gradient (empty otherwise): the displacement
  // gradient of the subset warp since the first reference, H = F - I with F = dx/dX, in
  // first-reference (material) coordinates X, image axes (x right, y down), at the tracked point;
  // NaN unless status == kConverged. Against the first reference it is IC-GN's affine parameters
  // (du/dx, du/dy, dv/dx, dv/dy); after reference updates the warps compose,
  // F = F_r(x_r) F_prev(X): F_r the warp's against the current reference at the subset's point
  // x_r in it, F_prev the total when that reference was made (docs/dic_accuracy.md, "Warp
  // gradient").
  std::vector<double> dudx, dudy, dvdx, dvdy;
  std::vector<int> iterations;  // IC-GN iterations of the final attempt.
  std::vector<SubsetStatus> status;
  // Costs of this frame [s].
  double seconds_coefficients = 0, seconds_reference = 0, seconds_initial_guess = 0,
         seconds_icgn = 0, seconds_total = 0;
  int searches = 0;  // Integer-pixel ZNCC searches run.
};

struct DicSummary {
  int subsets = 0;
  int frames = 0;              // Deformed frames correlated.
  double valid_fraction = 0;   // Converged results / (subsets x frames).
  double mean_iterations = 0;  // Mean IC-GN iterations of the converged results.
  int reference_updates = 0;
  long long searches = 0;
  // Dynamic range of the data: DicOptions::data_bits when given (a camera file's 10 bits), else
  // the first reference's (io DataBits: 8, 12 for 12-bit data in 16-bit images, 16; 0 for float
  // images): the contrast and saturation limits are relative to it.
  int data_bits = 0;
  std::array<long long, kSubsetStatusCount> status_counts{};
  // The most bytes of reference data kept, at any time, for subsets lost at a reference update
  // (tracked against the reference they were last found in): for each, its footprint's
  // intensities, gradients and search template and its subset data. At most the subsets times a
  // few kB, whatever the number of frames and updates (the current reference is not counted).
  long long orphan_reference_bytes = 0;
  // Time per phase [s], summed over frames: B-spline coefficients, reference precomputation
  // (gradients, per-subset Hessians), initial guesses (searches), IC-GN (including propagation).
  double seconds_coefficients = 0, seconds_reference = 0, seconds_initial_guess = 0,
         seconds_icgn = 0, seconds_total = 0;
  double SubsetsPerSecond() const;
  // Results flagged by the continuity post-check (status_counts of kDiscontinuous).
  long long Discontinuous() const;
  long long Outliers() const;  // Subset results flagged `outlier`.
  bool IsUsable() const { return frames > 0 && valid_fraction > 0.5; }
  // Why the correlation produced nothing usable, "" if it did: no valid subset in any deformed
  // frame. The one rule of `run` (a failed stage) and `correlate` (exit 1): "no valid subset in
  // any of the F frames after the reference (N subsets; most common status: S in K of T results;
  // MIN_ZNCC_NAME = Z)", `min_zncc_name` naming the setting as the caller's user knows it.
  std::string NothingUsable(const std::string& min_zncc_name, double min_zncc) const;
  std::string BriefReport() const;
  std::string FullReport() const;
};

class Correlator {
 public:
  explicit Correlator(const DicOptions& options);
  ~Correlator();
  Correlator(const Correlator&) = delete;
  Correlator& operator=(const Correlator&) = delete;

  // Sets the first reference (8/16-bit or float, one channel) and lays out the subset grid.
  void SetReference(const cv::Mat& image);
  // Correlates the next frame of the sequence (same size as the reference; Error otherwise).
  // SetReference must have been called (asserted).
  FrameResult Correlate(const cv::Mat& image);

  int subsets() const;
  // Subset centres in the first reference [px].
  const std::vector<cv::Point2d>& positions() const;
  // Grid shape: subsets are stored row by row, cols() per row.
  int rows() const;
  int cols() const;
  const DicSummary& summary() const;
  const DicOptions& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct DicResult {
  std::vector<cv::Point2d> positions;
  std::vector<FrameResult> frames;
  DicSummary summary;
  // The frame number of every image, the first reference included (dic CorrelateFrames: the
  // source's FrameSource::FrameNumber, e.g. 12 for frame_0012.png, -12 for a camera's frame
  // recorded before the trigger); empty from CorrelateSequence (then the indices).
  // frames[k] is image frames[k].frame.
  std::vector<long long> frame_numbers;
  // The time stamp [s] of every image, the first reference included, when the source has them
  // (camera files: FrameSource::TimeS); empty otherwise.
  std::vector<double> time_s;
  // What was done to the images before correlation (the results' /dic attribute `preprocess`),
  // "" if nothing.
  std::string preprocess;
  // Further /dic attributes set by the caller (e.g. the pre-filter's decision: preprocess
  // PrefilterAttributes).
  std::map<std::string, std::string> text_attributes;
  std::map<std::string, double> number_attributes;
  // What the caller should know (e.g. a colour image in a grey sequence), also logged.
  std::vector<std::string> warnings;
};

// Correlates images[1..] with images[0] as the first reference (dic CorrelateFrames on the
// frames in memory).
DicResult CorrelateSequence(const std::vector<cv::Mat>& images, const DicOptions& options);

}  // namespace impactdic

#endif  // IMPACTDIC_DIC_CORRELATOR_H_
