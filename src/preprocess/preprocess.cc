#include "impactdic/preprocess/preprocess.h"

#include <fmt/format.h>

#include <cmath>
#include <cstddef>
#include <map>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/strings.h"
#include "impactdic/core/timer.h"

namespace impactdic {

const char* ToString(GaussianMode mode) { return kGaussianModeNames.Name(mode); }

GaussianMode GaussianModeFromString(const std::string& text, const std::string& where) {
  return kGaussianModeNames.Parse(text, where);
}

void GaussianBlurOptions::Check() const {
  CheckValue(kGaussianSigmaRange.Contains(sigma_px), "preprocess.gaussian_sigma",
             fmt::format("{}", sigma_px), "in " + kGaussianSigmaRange.Text());
  CheckValue(kGaussianKernelRange.Contains(kernel_size) && kernel_size % 2 == 1,
             "preprocess.gaussian_kernel", std::to_string(kernel_size),
             "an odd size in " + kGaussianKernelRange.Text());
  CheckValue(kNyquistBiasThresholdRange.Contains(auto_threshold_px),
             "preprocess.gaussian_auto_threshold_px", fmt::format("{}", auto_threshold_px),
             "in " + kNyquistBiasThresholdRange.Text());
}

GaussianBlurOptions GaussianFromString(const std::string& text, const std::string& where) {
  GaussianBlurOptions g;
  const std::string expected = fmt::format(
      "auto, none (no pre-filter), on (sigma {} px) or SIGMA[,KERNEL]: sigma in {}, kernel an "
      "odd size in {} (default {})",
      g.sigma_px, kGaussianSigmaRange.Text(), kGaussianKernelRange.Text(), g.kernel_size);
  try {
    g.mode = GaussianModeFromString(text, where);
    return g;
  } catch (const Error&) {  // Not a word: a number.
  }
  g.mode = GaussianMode::kOn;
  const std::size_t comma = text.find(',');
  const std::optional<double> sigma_px = ParseNumber(text.substr(0, comma));
  bool ok = sigma_px && std::isfinite(*sigma_px);
  if (ok) g.sigma_px = *sigma_px;
  if (ok && comma != std::string::npos) {
    const std::optional<double> kernel = ParseNumber(text.substr(comma + 1));
    ok = kernel && std::abs(*kernel) < 1e6 && *kernel == std::floor(*kernel);
    if (ok) g.kernel_size = static_cast<int>(*kernel);
  }
  CheckValue(ok, where, text, expected);
  try {
    g.Check();
  } catch (const Error&) {
    throw Error(ErrorKind::kInvalidValue, where, text, expected);
  }
  return g;
}

std::string GaussianDecision::Text() const {
  const std::string measured =
      figure.measured() ? fmt::format("near-Nyquist bias figure {:.4f} px", figure.bias_px)
                        : std::string("near-Nyquist bias figure not measured");
  const std::string blur =
      fmt::format("Gaussian sigma {} px (kernel {}x{})", sigma_px, kernel_size, kernel_size);
  switch (mode) {
    case GaussianMode::kOn: return fmt::format("on (set), {} applied; {}", blur, measured);
    case GaussianMode::kOff: return fmt::format("off (set), skipped; {}", measured);
    case GaussianMode::kAuto: break;
  }
  if (!figure.measured()) return fmt::format("auto, skipped: {} (region too small)", measured);
  if (trade.measured() && figure.bias_px > threshold_px) {
    const std::string errors = fmt::format(
        "expected error per subset {:.4f} -> {:.4f} px (bias {:.4f} -> {:.4f}, random {:.4f} -> "
        "{:.4f} px, noise {:.2f} grey levels)",
        trade.Error(false), trade.Error(true), trade.bias_px, trade.bias_filtered_px,
        trade.random_px, trade.random_filtered_px, trade.noise_grey);
    return applied ? fmt::format("auto, {} applied: {} above {} px; {}", blur, measured,
                                 threshold_px, errors)
                   : fmt::format("auto, skipped: {} above {} px, but noise-limited: {}", measured,
                                 threshold_px, errors);
  }
  return applied ? fmt::format("auto, {} applied: {} above {} px", blur, measured, threshold_px)
                 : fmt::format("auto, skipped: {} not above {} px", measured, threshold_px);
}

GaussianDecision DecideGaussian(const GaussianBlurOptions& options, const cv::Mat& reference,
                                cv::Rect roi, const NextFrame& next, int subset_size) {
  GaussianDecision d;
  d.mode = options.mode;
  d.sigma_px = options.sigma_px;
  d.kernel_size = options.kernel_size;
  d.threshold_px = options.auto_threshold_px;
  if (!reference.empty()) d.figure = MeasureNyquistBias(reference, roi);
  const bool biased = d.figure.measured() && d.figure.bias_px > options.auto_threshold_px;
  if (options.mode == GaussianMode::kAuto && biased && next && subset_size > 0) {
    const cv::Mat next_frame = next();
    d.trade = MeasurePrefilterTrade(
        reference, next_frame, roi,
        cv::getGaussianKernel(options.kernel_size, options.sigma_px, CV_64F), subset_size);
  }
  d.applied = options.mode == GaussianMode::kOn ||
              (options.mode == GaussianMode::kAuto && biased &&
               (!d.trade.measured() || d.trade.Error(true) < d.trade.Error(false)));
  return d;
}

void ClaheOptions::Check() const {
  CheckValue(kClaheClipLimitRange.Contains(clip_limit), "preprocess.clahe_clip_limit",
             fmt::format("{}", clip_limit), "in " + kClaheClipLimitRange.Text());
  CheckValue(kClaheTileGridRange.Contains(tile_grid), "preprocess.clahe_tile_grid",
             std::to_string(tile_grid), "in " + kClaheTileGridRange.Text() + " tiles per side");
}

void PreprocessOptions::Check() const {
  undistortion.Check();
  if (gaussian.mode != GaussianMode::kOff) gaussian.Check();
  if (clahe.enabled) clahe.Check();
}

std::string PreprocessSummary::BriefReport() const {
  std::string applied, skipped;
  for (const PreprocessStep& s : steps) {
    std::string& list = s.applied ? applied : skipped;
    list += (list.empty() ? "" : ", ") + s.name;
  }
  return fmt::format("preprocess: {} frames in {:.2f} s (setup {:.2f} s); applied: {}; skipped: {}",
                     frames, seconds, setup_seconds, applied.empty() ? "none" : applied,
                     skipped.empty() ? "none" : skipped);
}

std::string PreprocessSummary::FullReport() const {
  std::string out = BriefReport() + "\n";
  for (const PreprocessStep& s : steps)
    out += fmt::format("  {:<9} {}: {}\n", s.name, s.applied ? "applied" : "skipped", s.reason);
  return out;
}

Preprocessor::Preprocessor(const PreprocessOptions& options, const CameraCalibration* calibration,
                           cv::Size frame_size)
    : options_(options), frame_size_(frame_size) {
  options.Check();
  CheckValue(frame_size.width > 0 && frame_size.height > 0, "frame size",
             fmt::format("{}x{}", frame_size.width, frame_size.height), "a positive size");
  WallTimer timer;
  PreprocessStep undistort{"undistort", false, ""};
  if (!options.undistort) {
    undistort.reason = "off in the options";
  } else if (!calibration) {
    undistort.reason = "no calibration given";
  } else {
    CheckFrameSize(*calibration, frame_size, "the frames");
    auto undistorter = std::make_unique<Undistorter>(*calibration, options.undistortion);
    summary_.max_distortion_px = undistorter->max_shift_px();
    undistort.applied = undistorter->active();
    undistort.reason = undistorter->reason();
    if (undistorter->active()) undistorter_ = std::move(undistorter);
  }
  summary_.steps.push_back(undistort);
  // The Gaussian step: on and off are known now, auto waits for the reference (DecideFrom or
  // the first frame), which is measured in every mode.
  summary_.gaussian = DecideGaussian(options.gaussian, cv::Mat());
  blur_ = summary_.gaussian.applied;
  summary_.steps.push_back(
      {"gaussian", blur_,
       options.gaussian.mode == GaussianMode::kOn
           ? fmt::format("sigma {} px, kernel {}x{}", options.gaussian.sigma_px,
                         options.gaussian.kernel_size, options.gaussian.kernel_size)
       : options.gaussian.mode == GaussianMode::kOff ? "off in the options"
                                                     : "auto, no frame seen yet"});
  summary_.steps.push_back(
      {"clahe", options.clahe.enabled,
       options.clahe.enabled ? fmt::format("clip limit {}, {}x{} tiles", options.clahe.clip_limit,
                                           options.clahe.tile_grid, options.clahe.tile_grid)
                             : "off in the options"});
  summary_.setup_seconds = timer.ElapsedSeconds();
  for (const PreprocessStep& s : summary_.steps)
    LogDebug("preprocess {}: {} ({})", s.name, s.applied ? "applied" : "skipped", s.reason);
}

Preprocessor::~Preprocessor() = default;
Preprocessor::Preprocessor(Preprocessor&&) noexcept = default;
Preprocessor& Preprocessor::operator=(Preprocessor&&) noexcept = default;

bool Preprocessor::active() const {
  for (const PreprocessStep& s : summary_.steps)
    if (s.applied) return true;
  return false;
}

void PrefilterAttributes(const GaussianDecision& decision,
                         std::map<std::string, std::string>* text_attributes,
                         std::map<std::string, double>* number_attributes) {
  (*text_attributes)["prefilter"] = decision.Text();
  (*number_attributes)["prefilter_applied"] = decision.applied ? 1.0 : 0.0;
  (*number_attributes)["nyquist_bias_px"] = decision.figure.bias_px;
  (*number_attributes)["prefilter_threshold_px"] = decision.threshold_px;
  (*number_attributes)["prefilter_error_px"] = decision.trade.Error(false);
  (*number_attributes)["prefilter_error_filtered_px"] = decision.trade.Error(true);
}

cv::Mat GaussianBlurFrame(const GaussianBlurOptions& options, const cv::Mat& frame) {
  cv::Mat blurred;
  const int k = options.kernel_size;
  cv::GaussianBlur(frame, blurred, cv::Size(k, k), options.sigma_px, options.sigma_px,
                   cv::BORDER_REFLECT_101);
  return blurred;
}

void Preprocessor::CheckFrame(const cv::Mat& frame) const {
  const int depth = frame.depth();
  CheckValue(frame.channels() == 1 && (depth == CV_8U || depth == CV_16U || depth == CV_32F),
             "frame type", fmt::format("{} channel(s), depth code {}", frame.channels(), depth),
             "a single-channel 8- or 16-bit or 32-bit float frame");
  // OpenCV's CLAHE equalises 8- and 16-bit images only (float frames come from memory: Python).
  CheckValue(!options_.clahe.enabled || depth != CV_32F, "preprocess.clahe.enabled",
             "true with 32-bit float frames", "false (CLAHE takes 8- or 16-bit frames)");
  if (frame.size() != frame_size_)
    throw Error(ErrorKind::kInvalidValue,
                fmt::format("frame has size {}x{} but the sequence's frames are {}x{}", frame.cols,
                            frame.rows, frame_size_.width, frame_size_.height));
}

void Preprocessor::Decide(const cv::Mat& undistorted_reference, const NextFrame& undistorted_next) {
  WallTimer timer;
  const GaussianMode mode = options_.gaussian.mode;
  summary_.gaussian = DecideGaussian(options_.gaussian, undistorted_reference, options_.roi,
                                     undistorted_next, options_.subset_size);
  decided_ = true;
  blur_ = summary_.gaussian.applied;
  PreprocessStep& step = summary_.steps[1];
  step.applied = blur_;
  if (mode == GaussianMode::kAuto) step.reason = summary_.gaussian.Text();
  summary_.setup_seconds += timer.ElapsedSeconds();
  LogInfo("pre-filter: {}", summary_.gaussian.Text());
}

void Preprocessor::DecideFrom(const cv::Mat& reference_frame, const NextFrame& next_frame) {
  if (decided_) return;
  CheckFrame(reference_frame);
  NextFrame next;
  if (next_frame) {
    next = [this, &next_frame] {
      cv::Mat f = next_frame();
      if (f.empty()) return f;
      CheckFrame(f);
      return undistorter_ ? undistorter_->Apply(f) : f;
    };
  }
  Decide(undistorter_ ? undistorter_->Apply(reference_frame) : reference_frame, next);
}

cv::Mat Preprocessor::Apply(const cv::Mat& frame) {
  CheckFrame(frame);
  WallTimer timer;
  cv::Mat out = frame;
  if (undistorter_) out = undistorter_->Apply(out);
  if (!decided_) Decide(out, {});
  if (blur_) out = GaussianBlurFrame(options_.gaussian, out);
  if (options_.clahe.enabled) {
    // A CLAHE object per call: cv::CLAHE keeps scratch buffers, so sharing one across threads
    // would race; its construction is cheap next to the equalisation.
    const int t = options_.clahe.tile_grid;
    cv::Ptr<cv::CLAHE> clahe = cv::createCLAHE(options_.clahe.clip_limit, cv::Size(t, t));
    cv::Mat equalised;
    clahe->apply(out, equalised);
    out = equalised;
  }
  summary_.seconds += timer.ElapsedSeconds();
  ++summary_.frames;
  return out;
}

}  // namespace impactdic
