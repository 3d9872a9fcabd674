#include "impactdic/preprocess/preprocess.h"

#include <fmt/format.h>

#include <opencv2/imgproc.hpp>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/timer.h"

namespace impactdic {

void GaussianBlurOptions::Check() const {
  CheckValue(kGaussianSigmaRange.Contains(sigma_px), "preprocess.gaussian_sigma",
             fmt::format("{}", sigma_px), "in " + kGaussianSigmaRange.Text());
  CheckValue(kGaussianKernelRange.Contains(kernel_size) && kernel_size % 2 == 1,
             "preprocess.gaussian_kernel", std::to_string(kernel_size),
             "an odd size in " + kGaussianKernelRange.Text());
}

void ClaheOptions::Check() const {
  CheckValue(kClaheClipLimitRange.Contains(clip_limit), "preprocess.clahe_clip_limit",
             fmt::format("{}", clip_limit), "in " + kClaheClipLimitRange.Text());
  CheckValue(kClaheTileGridRange.Contains(tile_grid), "preprocess.clahe_tile_grid",
             std::to_string(tile_grid), "in " + kClaheTileGridRange.Text() + " tiles per side");
}

void PreprocessOptions::Check() const {
  undistortion.Check();
  if (gaussian.enabled) gaussian.Check();
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
  summary_.steps.push_back(
      {"gaussian", options.gaussian.enabled,
       options.gaussian.enabled
           ? fmt::format("sigma {} px, kernel {}x{}", options.gaussian.sigma_px,
                         options.gaussian.kernel_size, options.gaussian.kernel_size)
           : "off in the options"});
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

cv::Mat Preprocessor::Apply(const cv::Mat& frame) {
  CheckValue(frame.channels() == 1 && (frame.depth() == CV_8U || frame.depth() == CV_16U),
             "frame type",
             fmt::format("{} channel(s), depth code {}", frame.channels(), frame.depth()),
             "a single-channel 8- or 16-bit frame");
  if (frame.size() != frame_size_)
    throw Error(ErrorKind::kInvalidValue,
                fmt::format("frame has size {}x{} but the sequence's frames are {}x{}", frame.cols,
                            frame.rows, frame_size_.width, frame_size_.height));
  WallTimer timer;
  cv::Mat out = frame;
  if (undistorter_) out = undistorter_->Apply(out);
  if (options_.gaussian.enabled) {
    cv::Mat blurred;
    const int k = options_.gaussian.kernel_size;
    cv::GaussianBlur(out, blurred, cv::Size(k, k), options_.gaussian.sigma_px,
                     options_.gaussian.sigma_px, cv::BORDER_REFLECT_101);
    out = blurred;
  }
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
