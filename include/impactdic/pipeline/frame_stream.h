// The analysed frames of a sequence, read on demand from their source (io/frame_source.h: image
// files, a video, a camera file, frames in memory) and preprocessed by the one preprocessing route
// (preprocess Preprocessor: undistortion, Gaussian pre-filter, CLAHE), so a run holds one frame at
// a time whatever the length of the recording (docs/development.md, "Memory"). `run` and
// `correlate` read their frames through it; it is itself a FrameSource of the analysed frames,
// which the correlation driver (dic CorrelateFrames) reads:
//
//   FrameStream frames(OpenFrameSource("rec.cine"), preprocess_options, calibration);
//   frames.SetRange(first, last);           // analysed frames first..last of the source
//   for (int k = 0; k < frames.count(); ++k) Use(frames.Read(k));  // k = 0: frame `first`
//
// Reading in increasing order decodes each frame once; going back re-opens a video and decodes it
// from its start (image and camera files are read directly).
#ifndef IMPACTDIC_PIPELINE_FRAME_STREAM_H_
#define IMPACTDIC_PIPELINE_FRAME_STREAM_H_

#include <algorithm>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "impactdic/calib/calibration.h"
#include "impactdic/io/frame_source.h"
#include "impactdic/io/image_io.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/preprocess/preprocess.h"
#include "impactdic/sensor/sensor.h"

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

// How a scene's frames are timed (sensor CameraClock: the frame rate, the DAQ time of frame 0
// without an exposure channel, the camera's time stamps). A camera file (.cine, .mraw) states
// its rate and time stamps: its rate is used (the scene needs no inputs.fps; one given must agree
// with it within sensor kFrameRateTolerance, else Error naming inputs.fps, both rates and the
// file), and its time stamps must be uniform at that rate (every interval within
// kFrameRateTolerance of 1 / fps, else Error naming the two frames: the kinematics difference
// frames 1 / fps apart, so a dropped or repeated frame would make velocities wrong). Any other
// source: inputs.fps and no time stamps. Reads only the camera file's header (and its time
// stamps), so `analyze` times the frames exactly as `run` did.
CameraClock SceneFrameClock(const Scene& scene);

class FrameStream : public FrameSource {
 public:
  // The analysed frames of `source` (all of them until SetRange). `calibration` may be null; it
  // must outlive the stream.
  FrameStream(std::unique_ptr<FrameSource> source, const PreprocessOptions& preprocess,
              const CameraCalibration* calibration);
  // The same on io OpenFrameSource(frames): a camera file, a video (its decodable frames counted
  // once, one at a time) or an image sequence (a gap in its numbering is an Error).
  FrameStream(const std::string& frames, const PreprocessOptions& preprocess,
              const CameraCalibration* calibration);
  ~FrameStream() override;
  FrameStream(const FrameStream&) = delete;
  FrameStream& operator=(const FrameStream&) = delete;

  FrameSource& source() { return *source_; }
  int source_frames() const { return source_->frame_count(); }
  // The analysed frames: first..last of the source, 0-based source indices
  // (0 <= first <= last < source_frames()).
  void SetRange(int first, int last);
  int first() const { return first_; }
  int count() const { return last_ - first_ + 1; }

  // Analysed frame k (0 = the first analysed frame) after preprocessing, in a buffer of its own.
  // Every frame is checked against the first one read (size and depth: Error naming the file).
  cv::Mat Read(int k) override;
  // The raw frame k, before preprocessing (for the checks of the first frame).
  cv::Mat ReadRaw(int k);

  // The analysed frames as a FrameSource: k = 0 .. count() - 1, named, numbered and timed as
  // the source's frame first + k.
  int frame_count() const override { return count(); }
  std::string Name(int k) const override { return source_->Name(first_ + k); }
  long long FrameNumber(int k) const override { return source_->FrameNumber(first_ + k); }
  double TimeS(int k) const override { return source_->TimeS(first_ + k); }
  double fps() const override { return source_->fps(); }
  // The first frame read's size (the source's before any).
  cv::Size frame_size() override {
    return first_raw_.empty() ? source_->frame_size() : first_raw_.size();
  }
  int data_bits() override { return source_->data_bits(); }
  bool StatesDataBits() const override { return source_->StatesDataBits(); }
  std::string description() const override { return source_->description(); }
  // The source's warnings (a colour image in a grey sequence, a truncated video), each reported
  // once however often a frame is re-read.
  const std::vector<std::string>& warnings() const override { return source_->warnings(); }

  // The preprocessing applied (one line; its frame count includes re-reads).
  std::string PreprocessNote() const;
  // The preprocessing's summary (its Gaussian decision made from the first analysed frame);
  // null before the first Read.
  const PreprocessSummary* preprocess_summary() const;

 private:
  std::unique_ptr<FrameSource> source_;
  PreprocessOptions options_;
  const CameraCalibration* calibration_;
  int first_ = 0, last_ = -1;
  std::optional<Preprocessor> pre_;
  cv::Mat first_raw_;  // The first frame read: the size and depth every frame must have.
  std::string first_name_;
  cv::Mat next_raw_;  // Analysed frame 1 (raw) when the pre-filter decision read it first.
};

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_FRAME_STREAM_H_
