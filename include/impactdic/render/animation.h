// The field animations: one video frame per analysed camera frame, rendered off-screen (the
// velocity field by VelocityFieldRenderer, the strain fields by StrainFieldRenderer,
// strain_field.h) and written with cv::VideoWriter. H.264 in MP4 is tried first (fourccs
// avc1, H264, X264); the writer must open AND the written file must read back with exactly one
// video frame per camera frame. Otherwise the animation falls back to Motion-JPEG in AVI, and the
// log and the summary say so. The video is written under a temporary name and renamed when
// complete and verified, so a failed run never leaves a file that looks finished.
//
//   AnimationOptions options;
//   options.png_frames_dir = "out/velocity_frames";   // optional PNG of every frame
//   AnimationSummary s = WriteVelocityAnimation(sequence, "out/velocity.mp4", options);
//   LogInfo("{}", s.BriefReport());   // "velocity.mp4: 120 frames, H.264 (avc1) ..."
#ifndef IMPACTDIC_RENDER_ANIMATION_H_
#define IMPACTDIC_RENDER_ANIMATION_H_

#include <algorithm>
#include <cstddef>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/core/enum_names.h"
#include "impactdic/core/range.h"
#include "impactdic/render/velocity_field.h"

namespace impactdic {

enum class VideoCodec {
  kAuto,  // H.264 MP4 if it works, else MJPG AVI
  kH264,  // H.264 MP4 or an error
  kMjpg,  // MJPG AVI
};
inline constexpr EnumNames<VideoCodec, 3> kVideoCodecNames{
    {{{VideoCodec::kAuto, "auto"}, {VideoCodec::kH264, "h264"}, {VideoCodec::kMjpg, "mjpg"}}}};
const char* ToString(VideoCodec codec);
VideoCodec VideoCodecFromString(const std::string& text);

struct AnimationOptions {
  // Playback rate of the video [frames/s], in kFpsRange; 1600 fps footage is slow motion. Below
  // 0.1 (10 s per frame) is no animation, and the encoders fail near 0.001.
  double fps = 25.0;
  static constexpr ValueRange kFpsRange{0.1, 240, "1/s"};
  VideoCodec codec = VideoCodec::kAuto;
  // The H.264 fourccs tried in order (each 4 characters).
  std::vector<std::string> h264_fourccs = {"avc1", "H264", "X264"};
  // When not empty, every frame is also written as <dir>/frame_00000.png ... (folder created).
  std::string png_frames_dir;
  VelocityOverlayOptions overlay;  // the velocity animation's drawing (WriteVelocityAnimation)

  void Check() const;  // Error kInvalidValue naming the field
};

struct AnimationSummary {
  std::string path;                  // the video written (.mp4 or .avi)
  std::string codec;                 // "H.264" or "MJPG"
  std::string fourcc;                // the fourcc that worked, e.g. "avc1"
  bool fell_back = false;            // MJPG AVI because H.264 did not work
  std::string fallback_reason;       // why (empty if no fallback)
  std::size_t frames = 0;            // video frames written (= camera frames)
  std::size_t frames_read_back = 0;  // counted by reading the file back with cv::VideoCapture
  std::size_t png_frames = 0;
  std::string png_frames_dir;
  cv::Size size;
  double fps = 0.0;
  double color_max_mm_s = 0.0;  // top of the colour scale (velocity animation)
  double render_s = 0.0;        // drawing the frames (all attempts)
  double encode_s = 0.0;        // encoding and verifying
  double wall_s = 0.0;

  std::string BriefReport() const;  // one line: file, codec, frames, size, fallback
};

// Video frames drawn on demand: `count` BGR 8-bit images of `size` (even width and height),
// frame i drawn by render(i).
struct VideoFrameSource {
  std::size_t count = 0;
  cv::Size size;
  std::function<cv::Mat(std::size_t)> render;
};

// Writes the frames of `source` as a video, with the codec fallbacks and checks above (every
// animation goes through here). `output_path` names the video; its extension is replaced by .mp4
// for H.264 and .avi for MJPG (the summary has the real path). Errors: kInvalidValue for
// inconsistent frames or options, kIo for an unwritable folder or when no codec produces a file
// that reads back with the right frame count (then no video file is left behind).
AnimationSummary WriteAnimation(const VideoFrameSource& source, const std::string& output_path,
                                const AnimationOptions& options);

// Writes the velocity animation of `sequence`: WriteAnimation of its VelocityFieldRenderer frames
// (options.overlay), with the same path rules and errors.
AnimationSummary WriteVelocityAnimation(const VelocityFieldSequence& sequence,
                                        const std::string& output_path,
                                        const AnimationOptions& options = {});

// Number of frames in a video file, counted by decoding it (not the container's header); 0 if it
// cannot be opened.
std::size_t CountVideoFrames(const std::string& path);

}  // namespace impactdic

#endif  // IMPACTDIC_RENDER_ANIMATION_H_
