#include "impactdic/pipeline/frame_stream.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstddef>

#include "impactdic/core/error.h"

namespace impactdic {

FramePreviewPlan PlanFramePreview(int count, cv::Size frame_size) {
  FramePreviewPlan plan;
  const int stride = std::max(1, (count + kPreviewFrames - 1) / kPreviewFrames);
  for (int k = 0; k < count; k += stride) plan.rows.push_back(k);
  const int longer = std::max(frame_size.width, frame_size.height);
  plan.downsample = std::max(1, (longer + kPreviewLongSidePx - 1) / kPreviewLongSidePx);
  return plan;
}

FrameStream::FrameStream(const std::string& source, const PreprocessOptions& preprocess,
                         const CameraCalibration* calibration)
    : source_(source), options_(preprocess), calibration_(calibration) {
  if (!IsVideoFile(source)) {
    files_ = ListFrameSequence(source);  // A gap in the numbering is an error.
    source_frames_ = static_cast<int>(files_.size());
  } else {
    // The container's frame count is not to be trusted (a truncated recording): count the frames
    // that decode, one at a time.
    VideoReader video(source);
    cv::Mat frame;
    while (video.Read(&frame)) {
    }
    source_frames_ = static_cast<int>(video.frames_read());
    const std::string truncated = video.Finish();
    if (!truncated.empty()) warnings_.push_back(truncated);
  }
  last_ = source_frames_ - 1;
}

FrameStream::~FrameStream() = default;

void FrameStream::SetRange(int first, int last) {
  CheckValue(first >= 0 && first <= last && last < source_frames_, "analysed frames",
             fmt::format("{}..{}", first, last),
             fmt::format("a range inside 0..{}", source_frames_ - 1));
  first_ = first;
  last_ = last;
}

std::string FrameStream::Name(int k) const {
  const int index = first_ + k;
  return files_.empty() ? fmt::format("{} frame {}", source_, index)
                        : files_[static_cast<std::size_t>(index)];
}

cv::Mat FrameStream::ReadSource(int index) {
  if (!files_.empty()) {
    const std::string& path = files_[static_cast<std::size_t>(index)];
    int channels = 1;
    cv::Mat image = ReadGreyImage(path, &channels);
    if (index > colour_checked_) {  // Each file's warning once, in the order of the files.
      const std::string warning = colour_.Check(path, channels);
      if (!warning.empty()) warnings_.push_back(warning);
      colour_checked_ = index;
    }
    return image;
  }
  if (!video_ || index < video_next_) {  // Going back: decode from the start again.
    video_ = std::make_unique<VideoReader>(source_);
    video_next_ = 0;
  }
  cv::Mat frame;
  while (video_next_ <= index) {
    if (!video_->Read(&frame)) {
      throw Error(
          ErrorKind::kFileFormat, "video frame", std::to_string(index),
          fmt::format("a frame that decodes ({} decoded when the run started)", source_frames_))
          .WithFile(source_);
    }
    ++video_next_;
  }
  return frame;
}

cv::Mat FrameStream::ReadRaw(int k) {
  CheckValue(k >= 0 && k < count(), "analysed frame", std::to_string(k),
             fmt::format("0..{}", count() - 1));
  cv::Mat image = ReadSource(first_ + k);
  if (first_raw_.empty()) {
    first_raw_ = image.clone();
    first_name_ = Name(k);
  }
  CheckSameSize({first_raw_, image}, {first_name_, Name(k)});
  return image;
}

cv::Mat FrameStream::Read(int k) {
  const cv::Mat image = ReadRaw(k);
  if (!pre_) {
    if (calibration_) CheckFrameSize(*calibration_, image.size(), Name(k));
    pre_.emplace(options_, calibration_, image.size());
    // The first analysed frame (the correlation's first reference) decides the automatic
    // pre-filter for every frame.
    pre_->DecideFrom(k == 0 ? image : ReadRaw(0));
  }
  return pre_->Apply(image);
}

const PreprocessSummary* FrameStream::preprocess_summary() const {
  return pre_ ? &pre_->summary() : nullptr;
}

std::string FrameStream::PreprocessNote() const {
  return pre_ ? pre_->summary().BriefReport() : "";
}

}  // namespace impactdic
