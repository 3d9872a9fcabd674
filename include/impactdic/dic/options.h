// Options of the correlation engine (docs/dic.md), nested by concern.
//
//   DicOptions options;
//   options.grid.subset_size = 25;
//   options.grid.step = 10;
//   options.icgn.interpolation = Interpolation::kBiquintic;
//   options.update.policy = "auto";
//   options.Check();  // Error naming the broken field.
#ifndef IMPACTDIC_DIC_OPTIONS_H_
#define IMPACTDIC_DIC_OPTIONS_H_

#include <array>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <string>

#include "impactdic/core/enum_names.h"
#include "impactdic/core/range.h"
#include "impactdic/dic/bspline.h"

namespace impactdic {

// Subset shape function: first order (affine: u, du/dx, du/dy, v, dv/dx, dv/dy; 6 parameters)
// or second order (adds the 3 second derivatives of u and of v; 12 parameters).
enum class ShapeFunction { kAffine, kQuadratic };
inline constexpr EnumNames<ShapeFunction, 2> kShapeFunctionNames{
    {{{ShapeFunction::kAffine, "affine"}, {ShapeFunction::kQuadratic, "quadratic"}}}};
const char* ToString(ShapeFunction shape);
ShapeFunction ShapeFunctionFromString(const std::string& name);

// The reference-update policy as written in the options and the scene ("auto", "every:5"; the
// policies are in dic/reference_update.h).
struct UpdateOptions;
std::string ReferenceUpdateText(const UpdateOptions& update);

// Allowed values of the options below, shared by their Check() and the scene's `dic.*` keys.
inline constexpr ValueRange kSubsetSizeRange{5, 201, "px"};  // And odd.
inline constexpr ValueRange kGridStepRange{1, 1e6, "px"};
inline constexpr ValueRange kSearchRadiusRange{1, 2000, "px"};
inline constexpr ValueRange kConvergenceRange{0, 1, "px", /*min_open=*/true};
inline constexpr ValueRange kConvergenceSigmaFractionRange{0, 1, ""};
inline constexpr ValueRange kMaxIterationsRange{1, 200, ""};
inline constexpr ValueRange kMinZnccRange{-1, 1, "", /*min_open=*/false, /*max_open=*/true};
inline constexpr ValueRange kAutoMinZnccRange{-1, 1, "", /*min_open=*/true};
inline constexpr ValueRange kAutoRescueDecorrelationRange{0, 1, "", /*min_open=*/true};
inline constexpr ValueRange kMinMisfitRange{0, 1, "", /*min_open=*/false, /*max_open=*/true};
// An 8-bit image's standard deviation is at most 127.5 grey levels.
inline constexpr ValueRange kMinContrastRange{0, 255, "grey levels"};
inline constexpr ValueRange kMaxPredictedUncertaintyRange{0, 100, "px", /*min_open=*/true};
inline constexpr ValueRange kMaxSaturatedFractionRange{0, 1, "", /*min_open=*/true};

struct GridOptions {
  int subset_size = 25;  // Subset side S [px], odd, kSubsetSizeRange.
  int step = 10;         // Grid spacing [px], kGridStepRange.
  // Region of interest [px] in the first reference; subsets lie entirely inside it. An empty
  // rectangle means the whole image.
  cv::Rect roi;
  // Optional mask (CV_8U, image size): a subset whose centre pixel is 0 is `masked`.
  cv::Mat mask;
  void Check() const;
};

struct InitialGuessOptions {
  // Integer-pixel ZNCC search radius [px] around the predicted position, kSearchRadiusRange
  // (the scene's dic.search_radius_px and correlate's --search-radius). The search runs
  // at seed points and for subsets the propagation could not solve.
  int search_radius_px = 40;
  // Seeds lie on every `seed_spacing`-th grid node in x and y (plus the grid centre), >= 1.
  int seed_spacing = 24;
  // Minimum integer-pixel ZNCC for a search result to be used, in (-1, 1).
  double min_search_zncc = 0.5;
  void Check() const;
};

struct IcgnOptions {
  Interpolation interpolation = Interpolation::kBicubic;
  ShapeFunction shape = ShapeFunction::kAffine;
  // Convergence: the increment of the warp moves every subset corner by < this [px],
  // kConvergenceRange.
  double convergence_px = 1e-3;
  // ... or by less than this fraction of the corner's own standard deviation (least-squares,
  // independent residuals), kConvergenceSigmaFractionRange: on poor texture (sigma 0.05-0.5 px)
  // an increment of 1e-3 px is far below what the data can resolve, and IC-GN would run into the
  // iteration cap; 0.05 sigma adds 0.25 % to the variance. 0: convergence_px alone.
  double convergence_sigma_fraction = 0.1;
  int max_iterations = 20;  // Iteration cap, kMaxIterationsRange.
  // A converged subset whose ZNCC is below this is `low_correlation` (failed), kMinZnccRange.
  // Validity only: the `auto` reference update has its own threshold,
  // UpdateOptions::auto_min_zncc.
  double min_zncc = 0.8;
  // Reference subsets whose predicted displacement standard deviation exceeds this [px] are
  // `low_contrast` (failed), kMaxPredictedUncertaintyRange. The prediction is the uncertainty
  // model's (the residuals' noise on the inverse Hessian, errors in variables) before any
  // correlation: the frame's estimated noise (ImageLevelsOf) on the subset's gradient energy
  // less the noise's own share of it, infinite where the noise accounts for all of it. A subset
  // that cannot place itself within half a pixel cannot be told from its neighbours' positions.
  double max_predicted_uncertainty_px = 0.5;
  // Reference subsets whose intensity standard deviation is below this [grey levels of an 8-bit
  // image, scaled to the grey-level range the reference frame uses (its 0.1st to 99.9th
  // percentile), at most the data's full scale] are `low_contrast`, kMinContrastRange. Kept
  // beside the predicted uncertainty for compressed frames: JPEG removes the fine noise the
  // single-image estimate sees, and flattened blocks pass the prediction (real 4k sand: 442
  // more subsets with an RMS error of 0.53 px on a static pair without this limit). Relative to
  // the used range, a 12-bit high-speed frame at short exposure (grey levels 110-1731 of 4095)
  // is judged by its own contrast, not by the container's.
  double min_contrast = 4.0;
  // Reference subsets with more than this fraction of pixels at 0 or full scale are
  // `saturated`, kMaxSaturatedFractionRange.
  double max_saturated_fraction = 0.2;
  // Converged subsets whose displacement standard deviation (the larger of sigma_u and sigma_v,
  // estimated from the residuals and the inverse Hessian, allowing for spatially correlated
  // residuals: docs/dic.md "Uncertainty per subset") exceeds this [px] are `uncertain` (failed),
  // >= 0. 0 or +inf (the default): no limit, every converged subset is reported with its sigma_u,
  // sigma_v (FrameResult) for downstream stages to weight or exclude (the kinematics leave out
  // samples far above the frame's median sigma: momentum.max_sigma_ratio). No fixed limit by
  // default: what a subset can resolve depends on the texture, and a fixed 0.025 px dropped 18 %
  // of good subsets on real sand and all of them on a low-resolution recording (measured
  // 2026-11-27). The one default of the scene key `dic.max_uncertainty_px` and of `correlate
  // --max-uncertainty`.
  double max_uncertainty_px = std::numeric_limits<double>::infinity();
  bool LimitsUncertainty() const {
    return max_uncertainty_px > 0 && std::isfinite(max_uncertainty_px);
  }
  void Check() const;
};

// When the reference image changes during a sequence (GeoPIV-RG's answer to random walk): a
// registered policy by name (dic/reference_update.h):
// "fixed": always the first image; "incremental": the previous frame; "every:N": every N frames;
// "auto": keep the reference while every subset that is still tracked correlates at or above
// auto_min_zncc; when one does not, switch to the last good frame and redo the frame against it,
// but only if that rescues one of the subsets that failed (tested on those subsets alone; a
// subset that matched the reference must keep at most auto_rescue_decorrelation of its
// decorrelation);
// subsets that fail against both references (e.g. covered by the pounder) keep the reference and
// are found again when they reappear.
struct UpdateOptions {
  std::string policy = "auto";  // A registered policy (ReferenceUpdatePolicyFromString).
  // "auto": the reference is updated once a tracked subset correlates below this,
  // kAutoMinZnccRange. Above IcgnOptions::min_zncc on purpose: the reference moves on while the
  // subsets still correlate well, before they fail.
  double auto_min_zncc = 0.95;
  // "auto": the share of a subset's decorrelation (1 - ZNCC) against the reference that may be left
  // against the last frame for the subset to count as rescued, when against the reference it
  // converged (below auto_min_zncc) or reached the iteration cap: the last frame must do clearly
  // better than two draws of the same noise (docs/dic.md, "Reference updating"),
  // kAutoRescueDecorrelationRange (0, 1]; 1: any result at or above auto_min_zncc that is no worse.
  double auto_rescue_decorrelation = 1.0 / 3.0;
  void Check() const;
};

// How the deformed images relate to each other (docs/dic.md):
// kSequence: a time sequence (default): each frame starts from the prediction of the previous
//   ones and the reference is updated by UpdateOptions.
// kPairs: independent images, each correlated against the reference alone: no prediction from
//   another image, no reference update (UpdateOptions does not apply), no subset is ever `lost`.
enum class SequenceMode { kSequence, kPairs };
inline constexpr EnumNames<SequenceMode, 2> kSequenceModeNames{
    {{{SequenceMode::kSequence, "sequence"}, {SequenceMode::kPairs, "pairs"}}}};
const char* ToString(SequenceMode mode);
// "sequence" or "pairs"; an Error naming `where` otherwise.
SequenceMode SequenceModeFromString(const std::string& text, const std::string& where);
// The uncertainty limit as written in a scene or on the command line: a number >= 0 [px], or
// "none" (no limit, +inf); an Error naming `where` otherwise.
double MaxUncertaintyFromString(const std::string& text, const std::string& where);
// The uncertainty limit as written: the number, or "none" for no limit (0 or +inf).
std::string MaxUncertaintyText(double max_uncertainty_px);

// The post-check of each correlated frame for subsets straddling a discontinuity (a body edge, a
// shear band): converged subsets whose result is a mixture of both sides rather than the motion
// of their centre become `discontinuous` (NaN). Criteria and evidence: dic/continuity_check.h,
// docs/dic_real_images.md ("Realistic footage: straddling subsets"). Scene keys dic.continuity_*,
// flags `correlate --continuity-*`.
struct ContinuityCheckOptions {
  // Run the check on every correlated frame. Off by default since 2026-11-27: on the DEM
  // validation it removed the coherent high-gradient motion under the pounder in the peak stage
  // (84 subset results, t_e not measurable); spurious vectors are found by the normalized median
  // test (OutlierCheckOptions) instead. On for footage with body edges inside the grid.
  bool enabled = false;
  // Misfit: 1 - ZNCC above this many times the median 1 - ZNCC of the converged subsets in the
  // 7 x 7 neighbourhood, > 1; +inf (the default) switches the criterion off: on low-contrast
  // noisy speckle it flags accurate subsets whose texture is poorer than their neighbours'
  // (Uncertainty.NoLimitReportsEverySubsetWithItsSigma), and on the realistic scenes the
  // difference criteria catch every garbage subset without it (docs/dic.md). 2.5 when used.
  double misfit_ratio = std::numeric_limits<double>::infinity();
  // ... and 1 - ZNCC above this as well, kMinMisfitRange: on clean speckle 1 - ZNCC is ~1e-3 and
  // varies by more than misfit_ratio between subsets without any discontinuity (the committed
  // sample).
  double min_misfit = 0.02;
  // A second difference of the displacement along a grid row or column,
  // |d_i - (d_left + d_right) / 2|, above this [px], > 0; +inf switches it off.
  double max_second_difference_px = 0.25;
  // The displacements of adjacent subsets differ by more than this [px], > 0; +inf switches it
  // off.
  double max_neighbour_difference_px = 0.4;
  // The two criteria above flag a value only above this many times its median over the converged
  // 7 x 7 neighbourhood as well, > 1: a smooth field with a large strain at a coarse step has
  // large differences everywhere around, a discontinuity only at the subsets next to it. +inf:
  // the two thresholds alone (no comparison with the neighbourhood).
  double local_ratio = 4;
  void Check() const;
};
// A threshold of ContinuityCheckOptions: the one definition of its name, bound, unit and what
// "none" (+inf) means, read by Check(), the scene keys (dic.continuity_<name>) and the
// `correlate --continuity-*` flags.
struct ContinuityLimit {
  double ContinuityCheckOptions::*field;
  const char* name;       // The field's name, e.g. "max_second_difference_px".
  double above;           // A value must be > this.
  const char* unit;       // "px", or "" for a ratio.
  const char* when_none;  // What none (+inf) does, e.g. "criterion off".
  // "a number > 0 px, or none (criterion off)".
  std::string Expected() const;
  // The threshold as written in a scene or on the command line: a number > `above`, or "none"
  // (+inf); an Error naming `where` with Expected() otherwise.
  double FromString(const std::string& text, const std::string& where) const;
};
// The four thresholds, in the order of ContinuityCheckOptions.
inline constexpr std::array<ContinuityLimit, 4> kContinuityLimits{{
    {&ContinuityCheckOptions::misfit_ratio, "misfit_ratio", 1, "", "criterion off"},
    {&ContinuityCheckOptions::max_second_difference_px, "max_second_difference_px", 0, "px",
     "criterion off"},
    {&ContinuityCheckOptions::max_neighbour_difference_px, "max_neighbour_difference_px", 0, "px",
     "criterion off"},
    {&ContinuityCheckOptions::local_ratio, "local_ratio", 1, "", "the thresholds alone"},
}};
// The entry of kContinuityLimits for `field`.
const ContinuityLimit& ContinuityLimitOf(double ContinuityCheckOptions::*field);
// "off", or "on (misfit_ratio 2.5, ...)" with the thresholds (inf: criterion off).
std::string ContinuityCheckText(const ContinuityCheckOptions& continuity);
// A continuity threshold as written: the number, or "none" for +inf.
std::string ContinuityLimitText(double limit);
// "on"/"off" (also true/false): an Error naming `where` otherwise.
bool OnOffFromString(const std::string& text, const std::string& where);

// The normalized median test (Westerweel & Scarano 2005) on every correlated frame: converged
// subsets whose displacement departs from their 3 x 3 neighbours' median by much more than the
// neighbours vary among themselves, and by much more than their own sigma, become `outlier`
// (NaN). Criteria and evidence: dic/outlier_check.h, docs/dic.md ("Spurious vectors"). Scene keys
// dic.outlier_*, flags `correlate --outlier-*`.
struct OutlierCheckOptions {
  bool enabled = true;  // Run the test on every correlated frame.
  // The normalized residual |d_0 - d_m| / (r_m + noise_px) above which a subset is an outlier,
  // kOutlierThresholdRange; 2 in Westerweel & Scarano (2005).
  double threshold = 2;
  // The noise level epsilon of the test [px], kOutlierNoiseRange: it keeps a uniform field
  // (r_m ~ 0) from flagging sub-pixel noise; 0.1 px in Westerweel & Scarano (2005).
  double noise_px = 0.1;
  // ... and the deviation above this many times the subset's own sigma (hypot(sigma_u,
  // sigma_v)), kOutlierSigmaFactorRange: a poorly textured subset that scatters within its
  // reported uncertainty is reported with it, not removed.
  double sigma_factor = 3;
  // Neighbours (of 8, in opposite pairs that both converged) needed to judge a subset,
  // kOutlierNeighboursRange: 4 = two pairs.
  int min_neighbours = 4;
  void Check() const;
};
// "off", or "on (threshold 2, noise_px 0.1, sigma_factor 3, min_neighbours 4)".
std::string OutlierCheckText(const OutlierCheckOptions& outliers);
inline constexpr ValueRange kOutlierThresholdRange{0, 1e6, "", /*min_open=*/true};
inline constexpr ValueRange kOutlierNoiseRange{0, 100, "px"};
inline constexpr ValueRange kOutlierSigmaFactorRange{0, 1e6, ""};
inline constexpr ValueRange kOutlierNeighboursRange{2, 8, ""};

struct DicOptions {
  SequenceMode mode = SequenceMode::kSequence;
  GridOptions grid;
  InitialGuessOptions init;
  IcgnOptions icgn;
  UpdateOptions update;
  ContinuityCheckOptions continuity;
  OutlierCheckOptions outliers;
  // Significant bits of the frames' data: 8, or 10, 12, 16 in 16-bit images; 0 = measured from the
  // first reference (io DataBits, which takes any 16-bit image whose maximum is at most 4095 for
  // 12-bit data, so it cannot tell 10-bit data from 12-bit). The saturation level and the contrast
  // limits follow it. The correlation driver (dic/correlate_frames.h) sets it from a source that
  // states its bit depth (a camera file).
  int data_bits = 0;
  // Keep, per subset and frame, the displacement gradient of the subset warp since the first
  // reference (FrameResult::dudx ... dvdy; the /dic datasets *_warp, `correlate --warp-gradient`):
  // IC-GN's affine parameters at the tracked point, composed across reference updates
  // (docs/dic_accuracy.md, "Warp gradient"). Off by default: the frames' results then hold no
  // gradient (4 doubles per subset and frame more when on). Both shape functions (affine,
  // quadratic) carry a gradient.
  bool keep_warp_gradient = false;
  void Check() const;
};

// Per-subset outcome. Everything except kConverged has NaN displacement.
enum class SubsetStatus {
  kConverged = 0,        // IC-GN converged with ZNCC >= min_zncc.
  kMaxIterations = 1,    // The iteration cap was reached.
  kLowCorrelation = 2,   // Converged, but ZNCC < min_zncc (decorrelated, occluded).
  kSingularHessian = 3,  // The reference subset has no usable gradients (featureless).
  kOutOfImage = 4,       // The subset (in the reference or the warped one) leaves the image.
  kMasked = 5,           // Excluded by the mask.
  kLowContrast = 6,      // Predicted uncertainty above max_predicted_uncertainty_px, or
                         // standard deviation below min_contrast.
  kSaturated = 7,        // Too many reference pixels at 0 or full scale.
  kNotFound = 8,         // No initial guess (search failed, no solved neighbour).
  kLost = 9,             // Failed in the frame that became the reference, and not found again
                         // against the reference it was last found in (tried every frame).
  kUncertain = 10,       // Converged, but the estimated standard deviation of the displacement
                         // exceeds IcgnOptions::max_uncertainty_px (e.g. few features).
  kDiscontinuous = 11,   // Converged, but flagged by the continuity post-check
                         // (ContinuityCheckOptions): it straddles a body edge or a shear band.
  kOutlier = 12,         // Converged, but a spurious vector by the normalized median test
                         // (OutlierCheckOptions).
};
constexpr int kSubsetStatusCount = 13;
const char* ToString(SubsetStatus status);
// "0=converged,1=max_iterations,...": every status code with its name (HDF5 attributes).
std::string SubsetStatusCodes();
SubsetStatus SubsetStatusFromString(const std::string& name);

}  // namespace impactdic

#endif  // IMPACTDIC_DIC_OPTIONS_H_
