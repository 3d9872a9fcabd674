#include "impactdic/render/animation.h"

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/videoio.hpp>  // ids only: the video code is in the plugin (io/opencv_codecs.h)
#include <system_error>

#include "impactdic/core/error.h"
#include "impactdic/core/interrupt.h"
#include "impactdic/core/log.h"
#include "impactdic/core/progress.h"
#include "impactdic/core/timer.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/image_io.h"
#include "impactdic/io/opencv_codecs.h"
#include "impactdic/io/output_generation.h"
#include "subprocess.h"

namespace impactdic {
namespace fs = std::filesystem;

const char* ToString(VideoCodec codec) { return kVideoCodecNames.Name(codec); }

VideoCodec VideoCodecFromString(const std::string& text) {
  return kVideoCodecNames.Parse(text, "video codec");
}

void AnimationOptions::Check() const {
  CheckRange(fps, kFpsRange, "AnimationOptions.fps", "a playback frame rate");
  for (const auto& f : h264_fourccs) {
    CheckValue(f.size() == 4, "AnimationOptions.h264_fourccs", "'" + f + "'",
               "four-character codes such as avc1");
  }
  CheckValue(codec == VideoCodec::kMjpg || !h264_fourccs.empty(), "AnimationOptions.h264_fourccs",
             "empty", "at least one fourcc unless codec is mjpg");
  overlay.Check();
}

std::string AnimationSummary::BriefReport() const {
  char buf[512];
  // Named as the user will find it (never a staging folder that is gone by then).
  const std::string shown = OutputPathForMessages(path);
  std::snprintf(buf, sizeof buf, "%s: %zu frames (%zu read back), %s (%s), %dx%d at %.3g fps",
                shown.c_str(), frames, frames_read_back, codec.c_str(), fourcc.c_str(), size.width,
                size.height, fps);
  std::string text = buf;
  if (fell_back) text += "; fell back to MJPG AVI because " + fallback_reason;
  if (png_frames > 0)
    text += "; " + std::to_string(png_frames) + " PNG frames in " +
            OutputPathForMessages(png_frames_dir);
  return text;
}

std::size_t CountVideoFrames(const std::string& path) {
  opencv_codecs::VideoCapture capture;
  try {
    capture.Open(path, cv::CAP_FFMPEG);
    if (!capture.IsOpened()) capture.Open(path, cv::CAP_ANY);
  } catch (const cv::Exception&) {
    return 0;
  }
  if (!capture.IsOpened()) return 0;
  std::size_t count = 0;
  while (capture.Grab()) ++count;
  return count;
}

namespace {

struct Attempt {
  std::string container;  // ".mp4" / ".avi"
  std::string codec;      // "H.264" / "MJPG"
  std::string fourcc;
};

// Result of one encoding attempt: empty reason = success.
struct AttemptResult {
  bool opened = false;
  std::string failure;
  std::size_t read_back = 0;
};

int Fourcc(const std::string& f) {
  return opencv_codecs::VideoWriter::Fourcc(f[0], f[1], f[2], f[3]);
}

std::uint64_t BigEndian(const unsigned char* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

// Whether the container of a written video is whole, judged from its structure alone (reading it
// back through FFmpeg prints FFmpeg's complaints about a cut-short file): MP4, top-level boxes
// that end exactly at the end of the file and include the index ("moov", written last); AVI,
// the RIFF size (patched at the end) matching the file size.
bool ContainerComplete(const std::string& path, const std::string& container) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return false;
  const std::uint64_t size = static_cast<std::uint64_t>(in.tellg());
  unsigned char head[16] = {};
  if (container == ".avi") {
    in.seekg(0);
    in.read(reinterpret_cast<char*>(head), 8);
    const std::uint64_t riff =
        head[4] | head[5] << 8 | head[6] << 16 | static_cast<std::uint64_t>(head[7]) << 24;
    return in.good() && std::memcmp(head, "RIFF", 4) == 0 && riff + 8 == size;
  }
  bool has_index = false;
  std::uint64_t at = 0;
  while (at + 8 <= size) {
    in.seekg(static_cast<std::streamoff>(at));
    in.read(reinterpret_cast<char*>(head), 16);
    if (in.gcount() < 8) return false;
    in.clear();
    std::uint64_t box = BigEndian(head, 4);
    if (box == 1) box = BigEndian(head + 8, 8);  // 64-bit size
    if (box == 0) box = size - at;               // to the end of the file
    if (box < 8) return false;
    has_index = has_index || std::memcmp(head + 4, "moov", 4) == 0;
    at += box;
  }
  return has_index && at == size;
}

// One encoding attempt: every frame rendered and written into `temp` with `attempt`'s codec (and
// as PNG frames the first time, when asked), then the video read back. The result says what
// failed; a full disk throws WriteError naming `final_path`. Adds the frame and timing counts
// to `summary`.
AttemptResult EncodeAttempt(const VideoFrameSource& source, const Attempt& attempt,
                            const std::string& temp, const std::string& final_path,
                            const AnimationOptions& options, bool* png_done,
                            AnimationSummary* summary) {
  const std::size_t frames = summary->frames;
  AttemptResult result;
  opencv_codecs::VideoWriter writer;
  try {
    result.opened = writer.Open(temp, cv::CAP_FFMPEG, Fourcc(attempt.fourcc), options.fps,
                                source.size, /*is_color=*/true);
  } catch (const cv::Exception& e) {
    result.failure = e.what();
  }
  if (!result.opened) {
    if (result.failure.empty()) result.failure = "the OpenCV video writer did not open";
    return result;
  }
  ProgressBar bar("animation", frames);
  for (std::size_t i = 0; i < frames; ++i) {
    WallTimer t;
    const cv::Mat image = source.render(i);
    CheckValue(image.size() == source.size && image.type() == CV_8UC3,
               "animation frame " + std::to_string(i),
               std::to_string(image.cols) + "x" + std::to_string(image.rows),
               "a BGR image of the first frame's size");
    summary->render_s += t.ElapsedSeconds();
    if (!*png_done) {
      char name[32];
      std::snprintf(name, sizeof name, "frame_%05zu.png", i);
      WriteImage((fs::path(options.png_frames_dir) / name).string(), image);
      ++summary->png_frames;
    }
    t.Restart();
    writer.Write(image);
    summary->encode_s += t.ElapsedSeconds();
    bar.Advance();
  }
  bar.Finish();
  *png_done = true;
  WallTimer t;
  writer.Release();
  // The writer does not report failed writes: a video cut short on a disk with no block left
  // failed for want of space, and every other codec would fail alike.
  if (DiskFull(temp) && !ContainerComplete(temp, attempt.container))
    throw WriteError(final_path, ENOSPC);
  result.read_back = CountVideoFrames(temp);
  summary->encode_s += t.ElapsedSeconds();
  if (result.read_back != frames) {
    result.failure = "the written file reads back with " + std::to_string(result.read_back) +
                     " frames instead of " + std::to_string(frames);
  }
  return result;
}

}  // namespace

AnimationSummary WriteAnimation(const VideoFrameSource& source, const std::string& output_path,
                                const AnimationOptions& options) {
  WallTimer wall;
  options.Check();
  CheckValue(source.count > 0 && static_cast<bool>(source.render), "animation frames", "none",
             "at least one frame");
  CheckValue(source.size.width > 0 && source.size.height > 0 && source.size.width % 2 == 0 &&
                 source.size.height % 2 == 0,
             "animation frame size",
             std::to_string(source.size.width) + "x" + std::to_string(source.size.height),
             "even width and height");
  CheckValue(!output_path.empty(), "animation output path", "empty", "a file name");
  CheckOutputLocation(output_path);
  const std::size_t frames = source.count;

  AnimationSummary summary;
  summary.frames = frames;
  summary.size = source.size;
  summary.fps = options.fps;

  if (!options.png_frames_dir.empty()) {
    std::error_code ec;
    MakeFolders(options.png_frames_dir, ec);
    if (ec || !fs::is_directory(options.png_frames_dir)) {
      throw Error(ErrorKind::kIo, "png_frames_dir", options.png_frames_dir,
                  "a folder that can be created: " + ec.message());
    }
    summary.png_frames_dir = options.png_frames_dir;
  }

  std::vector<Attempt> attempts;
  if (options.codec != VideoCodec::kMjpg) {
    for (const auto& f : options.h264_fourccs) attempts.push_back({".mp4", "H.264", f});
  }
  if (options.codec != VideoCodec::kH264) attempts.push_back({".avi", "MJPG", "MJPG"});

  const fs::path stem = fs::path(output_path).replace_extension();
  std::string h264_failures;
  bool png_done = options.png_frames_dir.empty();

  for (const auto& attempt : attempts) {
    const std::string final_path = stem.string() + attempt.container;
    const std::string temp = render_internal::TempSiblingPath(final_path, attempt.container);
    struct Cleanup {
      std::string path;
      ~Cleanup() {
        std::error_code ec;
        fs::remove(path, ec);
      }
    } cleanup{temp};
    const RemoveOnInterrupt video_on_interrupt(temp);

    const AttemptResult result =
        EncodeAttempt(source, attempt, temp, final_path, options, &png_done, &summary);
    if (result.failure.empty()) {
      std::error_code ec;
      fs::rename(temp, final_path, ec);
      if (ec) {
        throw Error(ErrorKind::kIo, OutputPathForMessages(final_path),
                    "cannot rename the temporary video: " + ec.message(),
                    "a writable output location");
      }
      cleanup.path.clear();
      summary.path = final_path;
      summary.codec = attempt.codec;
      summary.fourcc = attempt.fourcc;
      summary.frames_read_back = result.read_back;
      if (attempt.codec == "MJPG" && options.codec == VideoCodec::kAuto) {
        summary.fell_back = true;
        summary.fallback_reason =
            h264_failures.empty() ? "no H.264 fourcc was tried" : h264_failures;
        LogWarning("animation: H.264 did not work ({}); wrote Motion-JPEG AVI {} instead",
                   summary.fallback_reason, OutputPathForMessages(final_path));
      }
      break;
    }
    LogDebug("animation: {} ({}) failed: {}", attempt.codec, attempt.fourcc, result.failure);
    if (attempt.codec == "H.264") {
      h264_failures += (h264_failures.empty() ? "" : "; ") + attempt.fourcc + ": " + result.failure;
    } else {
      h264_failures += (h264_failures.empty() ? "" : "; ") + std::string("MJPG: ") + result.failure;
    }
  }
  if (summary.path.empty()) {
    throw Error(ErrorKind::kIo, "animation " + OutputPathForMessages(output_path),
                "no video could be written and read back (" + h264_failures + ")",
                options.codec == VideoCodec::kH264 ? "an OpenCV build with an H.264 encoder"
                                                   : "an OpenCV build with FFmpeg video writing");
  }
  summary.wall_s = wall.ElapsedSeconds();
  LogInfo("animation: {}", summary.BriefReport());
  return summary;
}

AnimationSummary WriteVelocityAnimation(const VelocityFieldSequence& sequence,
                                        const std::string& output_path,
                                        const AnimationOptions& options) {
  options.Check();
  sequence.Check();
  const VelocityFieldRenderer renderer(sequence, options.overlay);
  VideoFrameSource source;
  source.count = sequence.num_frames();
  source.size = renderer.canvas_size();
  source.render = [&renderer](std::size_t i) { return renderer.RenderFrame(i); };
  AnimationSummary summary = WriteAnimation(source, output_path, options);
  summary.color_max_mm_s = renderer.color_max_mm_s();
  return summary;
}

}  // namespace impactdic
