#include "impactdic/pipeline/frame_stream.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <string>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/io/camera_file.h"

namespace impactdic {

FramePreviewPlan PlanFramePreview(int count, cv::Size frame_size) {
  FramePreviewPlan plan;
  const int stride = std::max(1, (count + kPreviewFrames - 1) / kPreviewFrames);
  for (int k = 0; k < count; k += stride) plan.rows.push_back(k);
  const int longer = std::max(frame_size.width, frame_size.height);
  plan.downsample = std::max(1, (longer + kPreviewLongSidePx - 1) / kPreviewLongSidePx);
  return plan;
}

FrameStream::FrameStream(std::unique_ptr<FrameSource> source, const PreprocessOptions& preprocess,
                         const CameraCalibration* calibration)
    : source_(std::move(source)), options_(preprocess), calibration_(calibration) {
  last_ = source_->frame_count() - 1;
}

FrameStream::FrameStream(const std::string& frames, const PreprocessOptions& preprocess,
                         const CameraCalibration* calibration)
    : FrameStream(OpenFrameSource(frames), preprocess, calibration) {}

FrameStream::~FrameStream() = default;

void FrameStream::SetRange(int first, int last) {
  CheckValue(first >= 0 && first <= last && last < source_frames(), "analysed frames",
             fmt::format("{}..{}", first, last),
             fmt::format("a range inside 0..{}", source_frames() - 1));
  first_ = first;
  last_ = last;
}

cv::Mat FrameStream::ReadRaw(int k) {
  CheckValue(k >= 0 && k < count(), "analysed frame", std::to_string(k),
             fmt::format("0..{}", count() - 1));
  // The first frame read is kept (the checks of the first frame, the pre-filter's decision and
  // the correlation's reference all read it): decoded once, a copy of it for each reader.
  if (first_ + k == first_index_) return first_raw_.clone();
  cv::Mat image;
  if (k == 1 && !next_raw_.empty()) {
    std::swap(image, next_raw_);  // Read for the pre-filter's decision: decoded once.
  } else {
    // The frame after the first one read is decoded meanwhile (on another thread, where the
    // source can): a pair's two images decode in parallel.
    if (first_raw_.empty() && k + 1 < count()) source_->ReadAhead(first_ + k + 1);
    image = source_->Read(first_ + k);
  }
  if (first_raw_.empty()) {
    first_raw_ = image.clone();
    first_name_ = Name(k);
    first_index_ = first_ + k;
  }
  CheckSameSize({first_raw_, image}, {first_name_, Name(k)});
  return image;
}

cv::Mat FrameStream::Read(int k) {
  const cv::Mat image = ReadRaw(k);
  if (!pre_) {
    if (calibration_) CheckFrameSize(*calibration_, image.size(), Name(k));
    pre_.emplace(options_, calibration_, image.size());
    // The first analysed frame (the correlation's first reference) and the one after it decide
    // the automatic pre-filter for every frame (the pair's noise against the bias).
    const cv::Mat first = k == 0 ? image : ReadRaw(0);
    NextFrame next;
    if (count() > 1) {
      next = [this, k, &image] {
        if (k == 1) return cv::Mat(image);  // The frame being read is the next one.
        next_raw_ = ReadRaw(1);             // Kept for Read(1): decoded once.
        return next_raw_;
      };
    }
    pre_->DecideFrom(first, next);
  }
  return pre_->Apply(image);
}

const PreprocessSummary* FrameStream::preprocess_summary() const {
  return pre_ ? &pre_->summary() : nullptr;
}

std::string FrameStream::PreprocessNote() const {
  return pre_ ? pre_->summary().BriefReport() : "";
}

CameraClock SceneFrameClock(const Scene& scene) {
  CameraClock clock;
  clock.fps = scene.inputs.fps;
  clock.offset_s = scene.sensor.frame_time_offset_s;
  if (!IsCameraFile(scene.inputs.frames)) return clock;
  const CameraFileInfo info = OpenCameraFile(scene.inputs.frames)->info();
  const double fps = info.fps;
  if (scene.inputs.fps_given && std::abs(scene.inputs.fps / fps - 1) > kFrameRateTolerance) {
    throw Error(ErrorKind::kInvalidValue, "inputs.fps", fmt::format("{:.6g} 1/s", scene.inputs.fps),
                fmt::format("the frame rate {} states, {:.6g} 1/s, within {:.2g} %; or no "
                            "inputs.fps (the file's rate is used)",
                            info.path, fps, 100 * kFrameRateTolerance))
        .WithFile(scene.path);
  }
  clock.fps = fps;
  clock.fps_name = "the frame rate of " + info.path;
  for (std::size_t k = 1; k < info.time_s.size(); ++k) {
    const double dt = info.time_s[k] - info.time_s[k - 1];
    if (std::abs(dt * fps - 1) <= kFrameRateTolerance) continue;
    const long long number = info.FrameNumber(static_cast<long long>(k));
    throw Error(ErrorKind::kFileFormat, "time stamps",
                fmt::format("frames {} and {} {:.6g} s apart",
                            info.FrameNumber(static_cast<long long>(k) - 1), number, dt),
                fmt::format("frames 1 / {:.6g} = {:.6g} s apart within {:.2g} % (a dropped or "
                            "repeated frame would make the velocities wrong): analyse the frames "
                            "on either side as separate recordings",
                            fps, 1 / fps, 100 * kFrameRateTolerance))
        .WithFile(info.path);
  }
  clock.time_s = info.time_s;
  return clock;
}

}  // namespace impactdic
