// Frame preprocessing (docs/calibration.md): undistortion (when the lens needs it), then the
// filters GeoPIV-RG users rely on, each optional: Gaussian blur (sigma, kernel) and CLAHE
// (contrast-limited adaptive histogram equalisation, Zuiderveld 1994, Graphics Gems IV
// pp. 474-485, doi:10.1016/B978-0-12-336156-1.50061-6), on 8- and 16-bit frames.
//
// Fixed order, with the reasons:
//   1. undistort  -- a geometric correction of the raw sensor image; filtering first would make
//                    the filter act on a warped pixel grid (a blur kernel stretched by the lens);
//   2. Gaussian   -- removes sensor noise before contrast is raised;
//   3. CLAHE      -- last, so it does not amplify the noise the blur removes, and its local
//                    histograms see the final geometry.
// Each step that is off, or that the skip rule leaves out, is an exact no-op (the frame's pixels
// are returned untouched) and the summary says what was skipped and why.
//
//   PreprocessOptions options;
//   options.gaussian.enabled = true;
//   Preprocessor pre(options, &calibration, frame_size);   // maps computed once here
//   for (...) cv::Mat f = pre.Apply(frame);
//   LogInfo("{}", pre.summary().BriefReport());
#ifndef IMPACTDIC_PREPROCESS_PREPROCESS_H_
#define IMPACTDIC_PREPROCESS_PREPROCESS_H_

#include <algorithm>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/calib/calibration.h"
#include "impactdic/calib/undistort.h"
#include "impactdic/core/range.h"

namespace impactdic {

// The allowed values, defined once: read by Check(), the scene keys (preprocess.gaussian.*,
// preprocess.clahe.*) and `correlate --gaussian`.
inline constexpr ValueRange kGaussianSigmaRange{0, 20, "px", /*min_open=*/true};
inline constexpr ValueRange kGaussianKernelRange{3, 201, "px"};  // And odd.
inline constexpr ValueRange kClaheClipLimitRange{0, 1000, "", /*min_open=*/true};
inline constexpr ValueRange kClaheTileGridRange{1, 64, ""};

struct GaussianBlurOptions {
  bool enabled = false;
  double sigma_px = 1.0;  // Standard deviation [px], kGaussianSigmaRange.
  int kernel_size = 5;    // Kernel side [px], odd, kGaussianKernelRange (the scene's kernel).
  void Check() const;
};

struct ClaheOptions {
  bool enabled = false;
  double clip_limit = 2.0;  // Contrast limit (OpenCV's clipLimit, relative to a flat
                            // histogram), kClaheClipLimitRange.
  int tile_grid = 8;        // Tiles per side of the image, kClaheTileGridRange.
  void Check() const;
};

struct PreprocessOptions {
  bool undistort = true;  // Undistort when a calibration is given and the skip rule allows.
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

  // Runs the enabled steps on one single-channel 8- or 16-bit frame of frame_size; returns a
  // frame of the same size and type (the input itself when every step is skipped).
  cv::Mat Apply(const cv::Mat& frame);

  // True if at least one step changes the frames.
  bool active() const;
  const PreprocessSummary& summary() const { return summary_; }

 private:
  PreprocessOptions options_;
  cv::Size frame_size_;
  std::unique_ptr<Undistorter> undistorter_;  // null when undistortion is off or skipped
  PreprocessSummary summary_;
};

}  // namespace impactdic

#endif  // IMPACTDIC_PREPROCESS_PREPROCESS_H_
