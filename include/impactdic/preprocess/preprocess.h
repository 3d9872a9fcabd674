// Frame preprocessing (docs/calibration.md): undistortion (when the lens needs it), then the
// filters GeoPIV-RG users rely on, each optional: Gaussian blur (sigma, kernel) and CLAHE
// (contrast-limited adaptive histogram equalisation, Zuiderveld 1994, Graphics Gems IV
// pp. 474-485, doi:10.1016/B978-0-12-336156-1.50061-6), on 8- and 16-bit frames.
//
// Fixed order, with the reasons:
//   1. undistort  -- a geometric correction of the raw sensor image; filtering first would make
//                    the filter act on a warped pixel grid (a blur kernel stretched by the lens);
//   2. Gaussian   -- removes sensor noise before contrast is raised; by default (mode auto) only
//                    when the first reference frame carries content near the Nyquist frequency
//                    that biases sub-pixel displacements (nyquist_bias.h; docs/dic_accuracy.md,
//                    "Sub-pixel bias"): the pre-filter of B. Pan, Opt. Lasers Eng. 51 (2013)
//                    1161-1167;
//   3. CLAHE      -- last, so it does not amplify the noise the blur removes, and its local
//                    histograms see the final geometry.
// Each step that is off, or that the skip rule leaves out, is an exact no-op (the frame's pixels
// are returned untouched) and the summary says what was skipped and why.
//
//   PreprocessOptions options;
//   options.gaussian.mode = GaussianMode::kOn;              // default kAuto
//   Preprocessor pre(options, &calibration, frame_size);   // maps computed once here
//   pre.DecideFrom(reference_frame);                       // auto: else the first frame applied
//   for (...) cv::Mat f = pre.Apply(frame);
//   LogInfo("{}", pre.summary().BriefReport());
#ifndef IMPACTDIC_PREPROCESS_PREPROCESS_H_
#define IMPACTDIC_PREPROCESS_PREPROCESS_H_

#include <algorithm>
#include <functional>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/calib/calibration.h"
#include "impactdic/calib/undistort.h"
#include "impactdic/core/enum_names.h"
#include "impactdic/core/range.h"
#include "impactdic/preprocess/nyquist_bias.h"

namespace impactdic {

// The allowed values, defined once: read by Check(), the scene keys (preprocess.gaussian.*,
// preprocess.clahe.*) and `correlate --gaussian`.
inline constexpr ValueRange kGaussianSigmaRange{0, 20, "px", /*min_open=*/true};
inline constexpr ValueRange kGaussianKernelRange{3, 201, "px"};  // And odd.
inline constexpr ValueRange kClaheClipLimitRange{0, 1000, "", /*min_open=*/true};
inline constexpr ValueRange kClaheTileGridRange{1, 64, ""};
inline constexpr ValueRange kNyquistBiasThresholdRange{0, 1, "px"};

// When the Gaussian blur runs: kOn always, kOff never, kAuto when the first reference frame's
// near-Nyquist bias figure (MeasureNyquistBias over the region of interest) exceeds
// GaussianBlurOptions::auto_threshold_px and, when the next frame is known, the filter lowers the
// expected total error of a subset (bias and random error in quadrature, MeasurePrefilterTrade):
// a noise-limited recording is not blurred for a bias far below its random error. Written "auto",
// "true" (also on, yes) and "false" (also off, no, none): the scene's preprocess.gaussian.enabled
// and `correlate --gaussian`.
enum class GaussianMode { kAuto, kOn, kOff };
inline constexpr EnumNames<GaussianMode, 3> kGaussianModeNames{
    {{{GaussianMode::kAuto, "auto"},
      {GaussianMode::kOn, "true", "on yes"},
      {GaussianMode::kOff, "false", "off no none"}}},
    /*ignore_case=*/true};
const char* ToString(GaussianMode mode);
GaussianMode GaussianModeFromString(const std::string& text, const std::string& where);

struct GaussianBlurOptions {
  GaussianMode mode = GaussianMode::kAuto;
  // Standard deviation [px], kGaussianSigmaRange. 0.7 px with the 5 px kernel brings DIC
  // Challenge 1.0 Sample 3 to max |bias| 0.0008 px at 1.06x the sd (0.8 px: 0.0007 px at 1.08x,
  // and 1.8x the extra sd on real sand; docs/dic_accuracy.md, "Sub-pixel bias").
  double sigma_px = 0.7;
  int kernel_size = 5;  // Kernel side [px], odd, kGaussianKernelRange (the scene's kernel).
  // kAuto: blur when the near-Nyquist bias figure [px] is above this, kNyquistBiasThresholdRange.
  // 0.0025 px sends DIC Challenge 1.0 Sample 3 (figure 0.0034 px) to the filter and leaves
  // Sample 14 (0.0019 px) alone (docs/dic_accuracy.md, "Sub-pixel bias").
  double auto_threshold_px = 0.0025;
  void Check() const;
};

// `correlate --gaussian`: auto | none (also off, false) | on (also true: the default sigma) |
// SIGMA[,KERNEL] (on, with that sigma and kernel). Error naming `where` otherwise.
GaussianBlurOptions GaussianFromString(const std::string& text, const std::string& where);

// What the Gaussian step does with a given reference frame: the options' mode resolved.
struct GaussianDecision {
  GaussianMode mode = GaussianMode::kAuto;  // As set.
  bool applied = false;
  double sigma_px = 0;
  int kernel_size = 0;
  double threshold_px = 0;
  NyquistBias figure;    // Of the reference (measured in every mode when a reference is given).
  PrefilterTrade trade;  // Of the first pair (auto, figure above the threshold, next frame given).
  // "auto, Gaussian sigma 0.8 px (kernel 5x5) applied: near-Nyquist bias figure 0.0034 px above
  // 0.0025 px; expected error per subset 0.0064 -> 0.0052 px", "auto, skipped: ... below ...",
  // "auto, skipped: ... above ...; but the expected error ... would rise ...", "on (set), ...",
  // "off (set), ...".
  std::string Text() const;
};

// The frame after the reference, read only when a decision needs it (empty function or Mat:
// none).
using NextFrame = std::function<cv::Mat()>;

// Measures the reference (over `roi`, empty: all of it; none given: not measured) and decides;
// in mode auto with the bias figure above the threshold, the next frame and the subset size,
// weighs the bias against the random error (MeasurePrefilterTrade).
GaussianDecision DecideGaussian(const GaussianBlurOptions& options, const cv::Mat& reference,
                                cv::Rect roi = {}, const NextFrame& next = {}, int subset_size = 0);

// The decision as attributes of the results' /dic group (`correlate` and `run` alike): text
// `prefilter` (GaussianDecision::Text), numbers `prefilter_applied` (0 or 1),
// `nyquist_bias_px` (the figure; NaN when not measured) and `prefilter_threshold_px`.
void PrefilterAttributes(const GaussianDecision& decision,
                         std::map<std::string, std::string>* text_attributes,
                         std::map<std::string, double>* number_attributes);

// The blur itself (whatever the mode): cv::GaussianBlur with the options' sigma and kernel,
// borders mirrored (BORDER_REFLECT_101); same size and type.
cv::Mat GaussianBlurFrame(const GaussianBlurOptions& options, const cv::Mat& frame);

struct ClaheOptions {
  bool enabled = false;
  double clip_limit = 2.0;  // Contrast limit (OpenCV's clipLimit, relative to a flat
                            // histogram), kClaheClipLimitRange.
  int tile_grid = 8;        // Tiles per side of the image, kClaheTileGridRange.
  void Check() const;
};

struct PreprocessOptions {
  bool undistort = true;  // Undistort when a calibration is given and the skip rule allows.
  cv::Rect roi;  // Where the auto Gaussian measures the reference [px]; empty = the whole frame.
  // The correlation's subset side [px] (the DIC options'), for the auto Gaussian's random error;
  // 0: unknown (the bias figure alone decides).
  int subset_size = 0;
  UndistortOptions undistortion;
  GaussianBlurOptions gaussian;
  ClaheOptions clahe;
  void Check() const;
};

struct PreprocessStep {
  std::string name;  // "undistort", "gaussian", "clahe"
  bool applied = false;
  std::string reason;  // Why applied or skipped, with the settings.
};

struct PreprocessSummary {
  std::vector<PreprocessStep> steps;  // In the order they run.
  int frames = 0;
  double seconds = 0;            // Total time spent in Apply().
  double setup_seconds = 0;      // Map precomputation.
  double max_distortion_px = 0;  // Largest lens shift in the ROI (0 without calibration).
  GaussianDecision gaussian;     // The Gaussian step's decision (after DecideFrom or a frame).
  std::string BriefReport() const;
  std::string FullReport() const;
};

class Preprocessor {
 public:
  // `calibration` may be null (no undistortion). When given, frame_size must equal its image
  // size (CheckFrameSize). Precomputes the undistortion maps once.
  Preprocessor(const PreprocessOptions& options, const CameraCalibration* calibration,
               cv::Size frame_size);
  ~Preprocessor();
  Preprocessor(Preprocessor&&) noexcept;
  Preprocessor& operator=(Preprocessor&&) noexcept;

  // Measures the raw first reference frame of frame_size (undistorted first when undistortion
  // is on) and, in mode auto, decides the Gaussian step from it (summary().gaussian, logged):
  // every frame is then filtered alike. Without it, the first frame passed to Apply is that
  // reference. Later calls change nothing.
  // `next_frame` (raw, optional, called only when needed): the frame after the reference, for the
  // filter's random error.
  void DecideFrom(const cv::Mat& reference_frame, const NextFrame& next_frame = {});

  // Runs the enabled steps on one single-channel 8- or 16-bit frame of frame_size; returns a
  // frame of the same size and type (the input itself when every step is skipped).
  cv::Mat Apply(const cv::Mat& frame);

  // True if at least one step changes the frames.
  bool active() const;
  const PreprocessSummary& summary() const { return summary_; }

 private:
  void Decide(const cv::Mat& undistorted_reference, const NextFrame& undistorted_next);
  void CheckFrame(const cv::Mat& frame) const;

  PreprocessOptions options_;
  cv::Size frame_size_;
  bool decided_ = false;  // The reference is measured and the Gaussian step decided.
  bool blur_ = false;     // The Gaussian step blurs.
  std::unique_ptr<Undistorter> undistorter_;  // null when undistortion is off or skipped
  PreprocessSummary summary_;
};

}  // namespace impactdic

#endif  // IMPACTDIC_PREPROCESS_PREPROCESS_H_
