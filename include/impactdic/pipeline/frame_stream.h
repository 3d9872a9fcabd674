// The analysed frames of a scene, read on demand from their source (numbered image files or a
// video) and preprocessed, so a run holds one frame at a time whatever the length of the
// recording (docs/architecture.md, "Memory"):
//
//   FrameStream frames(scene.inputs.frames, preprocess_options, calibration);
//   frames.SetRange(first, last);           // analysed frames first..last of the source
//   for (int k = 0; k < frames.count(); ++k) Use(frames.Read(k));  // k = 0: frame `first`
//
// Reading in increasing order decodes each frame once; going back re-opens a video and decodes it
// from its start (image files are read directly).
#ifndef IMPACTDIC_PIPELINE_FRAME_STREAM_H_
#define IMPACTDIC_PIPELINE_FRAME_STREAM_H_

#include <algorithm>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "impactdic/calib/calibration.h"
#include "impactdic/io/image_io.h"
#include "impactdic/preprocess/preprocess.h"

namespace impactdic {

// The preview of the analysed frames that results.h5 stores by default (outputs.frames: preview):
// at most kPreviewFrames frames, every stride-th from the first (stride = ceil(count /
// kPreviewFrames)), each shrunk by the smallest integer factor that brings its longer side to at
// most kPreviewLongSidePx (cv::INTER_AREA). 16 frames of 640 x 480 8-bit: 4.9 MB before
// compression, whatever the length of the recording.
inline constexpr int kPreviewFrames = 16;
inline constexpr int kPreviewLongSidePx = 640;
struct FramePreviewPlan {
  std::vector<int> rows;  // Analysed frames stored, increasing.
  int downsample = 1;     // Integer shrink factor.
  // The stored size of a frame of `full` size (rounded up).
  cv::Size ImageSize(cv::Size full) const {
    return {(full.width + downsample - 1) / downsample,
            (full.height + downsample - 1) / downsample};
  }
};
FramePreviewPlan PlanFramePreview(int count, cv::Size frame_size);

class FrameStream {
 public:
  // Lists the image sequence (a gap in its numbering is an Error) or counts the decodable frames
  // of a video (decoding it once, one frame at a time). `calibration` may be null; it must
  // outlive the stream.
  FrameStream(const std::string& source, const PreprocessOptions& preprocess,
              const CameraCalibration* calibration);
  ~FrameStream();
  FrameStream(const FrameStream&) = delete;
  FrameStream& operator=(const FrameStream&) = delete;

  int source_frames() const { return source_frames_; }
  // The analysed frames: first..last of the source (0 <= first <= last < source_frames()).
  void SetRange(int first, int last);
  int count() const { return last_ - first_ + 1; }

  // Analysed frame k (0 = the first analysed frame) after preprocessing, in a buffer of its own.
  // Every frame is checked against the first one read (size and depth: Error naming the file).
  cv::Mat Read(int k);
  // The raw frame k, before preprocessing (for the checks of the first frame).
  cv::Mat ReadRaw(int k);
  // "frame_0012.png" or "video.mp4 frame 12" for analysed frame k.
  std::string Name(int k) const;

  // What the reading found once (a colour image in a grey sequence, a truncated video), each
  // reported once however often a frame is re-read.
  const std::vector<std::string>& warnings() const { return warnings_; }
  // The preprocessing applied (one line; its frame count includes re-reads).
  std::string PreprocessNote() const;
  // The preprocessing's summary (its Gaussian decision made from the first analysed frame);
  // null before the first Read.
  const PreprocessSummary* preprocess_summary() const;

 private:
  cv::Mat ReadSource(int source_index);

  std::string source_;
  PreprocessOptions options_;
  const CameraCalibration* calibration_;
  std::vector<std::string> files_;  // Empty for a video.
  int source_frames_ = 0;
  int first_ = 0, last_ = -1;
  std::unique_ptr<VideoReader> video_;
  int video_next_ = 0;  // Index of the frame video_ decodes next.
  SequenceColourCheck colour_;
  int colour_checked_ = -1;  // Highest source index whose colour was checked.
  std::vector<std::string> warnings_;
  std::optional<Preprocessor> pre_;
  cv::Mat first_raw_;  // The first frame read: the size and depth every frame must have.
  std::string first_name_;
};

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_FRAME_STREAM_H_
