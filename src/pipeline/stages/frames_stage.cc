// frames: the images of the scene (an image sequence or a video), checked, timed on the DAQ clock
// and preprocessed; with a sensor record the first frame is the last one before the impact.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "impactdic/calib/calibration.h"
#include "impactdic/calib/undistort.h"
#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/progress.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/frame_source.h"
#include "impactdic/io/image_io.h"
#include "impactdic/momentum/wave_front.h"
#include "impactdic/pipeline/frame_stream.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/preprocess/preprocess.h"
#include "impactdic/sensor/sensor.h"
#include "stage.h"

namespace impactdic::stages {
namespace {

// The fewest analysed frames: a reference and one deformed frame, and a third for the kinematics'
// derivatives when the scene lists them.
int MinFrames(const Scene& scene) { return scene.HasStage("kinematics") ? 3 : 2; }

// dic.first_frame and dic.last_frame against the n frames of the source: Error naming the key,
// its value and the allowed range.
void CheckFrameRange(const Scene& scene, int n) {
  const int last = scene.dic.last_frame < 0 ? n - 1 : scene.dic.last_frame;
  if (last >= n) {
    throw Error(ErrorKind::kInvalidValue, "dic.last_frame", std::to_string(last),
                fmt::format("< the number of frames ({}) in {}", n, scene.inputs.frames))
        .WithFile(scene.path);
  }
  const int first = scene.dic.first_frame, min = MinFrames(scene);
  if (first > 0 && last - first < min - 1) {
    throw Error(ErrorKind::kInvalidValue, "dic.first_frame", std::to_string(first),
                fmt::format("a frame index <= {}: {} holds {} frames (0..{}){}, and at least {} "
                            "from dic.first_frame on are correlated",
                            std::max(0, last - min + 1), scene.inputs.frames, n, n - 1,
                            scene.dic.last_frame < 0
                                ? ""
                                : fmt::format(", dic.last_frame is {}", scene.dic.last_frame),
                            min))
        .WithFile(scene.path);
  }
}

// The analysed frames, as source indices into d.first_frame..d.last_frame: dic.first_frame and
// dic.last_frame, or the frames numbered dic.first_frame_number / last_frame_number (Error naming
// the field, the number and the source's span when no frame has it; at least two frames).
void SelectFrameRange(const Scene& scene, SceneRunData& d) {
  const SceneDic& dic = scene.dic;
  // One selection per end: by index or by number, never both (one would silently win).
  for (const auto& [index_key, by_index, number_key, by_number] :
       {std::tuple{"dic.first_frame", dic.first_frame != 0, "dic.first_frame_number",
                   dic.first_frame_number.has_value()},
        std::tuple{"dic.last_frame", dic.last_frame != -1, "dic.last_frame_number",
                   dic.last_frame_number.has_value()}}) {
    if (!by_index || !by_number) continue;
    throw Error(ErrorKind::kInvalidValue, std::string(index_key) + " / " + number_key, "both given",
                std::string("one of them: the frame's index in the source (") + index_key +
                    ") or its own number (" + number_key + ")")
        .WithFile(scene.path);
  }
  CheckFrameRange(scene, d.source_frames);
  d.first_frame = dic.first_frame;
  d.last_frame = dic.last_frame < 0 ? d.source_frames - 1 : dic.last_frame;
  if (!dic.first_frame_number && !dic.last_frame_number) return;
  const FrameSource& source = d.frames->source();
  const std::string both = "dic.first_frame_number..last_frame_number";
  if (dic.first_frame_number && dic.last_frame_number &&
      *dic.first_frame_number > *dic.last_frame_number) {
    throw Error(ErrorKind::kInvalidValue, both,
                fmt::format("{} > {}", *dic.first_frame_number, *dic.last_frame_number),
                "first <= last");
  }
  if (dic.first_frame_number)
    d.first_frame = FrameIndexOf(source, *dic.first_frame_number, "dic.first_frame_number");
  if (dic.last_frame_number)
    d.last_frame = FrameIndexOf(source, *dic.last_frame_number, "dic.last_frame_number");
  if (d.last_frame - d.first_frame < 1) {
    throw Error(ErrorKind::kInvalidValue, both,
                fmt::format("frames {}..{} of {} (one frame)", source.FrameNumber(d.first_frame),
                            source.FrameNumber(d.last_frame), source.description()),
                "at least two frames (the first is the reference)");
  }
}

// dic.roi against the frame size: the correlator needs it inside the frame. Error naming the key,
// its value and the frame size.
void CheckSceneRoi(const Scene& scene, cv::Size frame) {
  const auto& r = scene.dic.roi;
  if (!(r[2] > r[0] && r[3] > r[1])) return;  // Not set: the whole frame.
  if (r[2] <= frame.width && r[3] <= frame.height) return;
  throw Error(
      ErrorKind::kInvalidValue, "dic.roi",
      fmt::format("[{}, {}, {}, {}]{}", r[0], r[1], r[2], r[3],
                  r[0] >= frame.width || r[1] >= frame.height ? ", entirely outside the frames"
                                                              : ", partly outside the frames"),
      fmt::format("a rectangle (ROI) [x0, y0, x1, y1] inside the {}x{} frames (x1 <= {}, "
                  "y1 <= {})",
                  frame.width, frame.height, frame.width, frame.height))
      .WithFile(scene.path);
}

// The timeline of every frame of the source (stages TimeSceneFrames) and, with a sensor record,
// the first frame to correlate: the last one exposed before the impact (sensor
// ReferenceFrameForImpact) unless the scene selects it (dic.first_frame or
// dic.first_frame_number). Returns a note on the frames left out ("" if none).
std::string TimeFrames(StageContext& c, FrameTimeline* all) {
  const Scene& scene = c.scene;
  SceneRunData& d = c.data;
  const FrameSource& source = d.frames->source();
  const int n = d.source_frames;
  std::vector<long long> numbers(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) numbers[static_cast<std::size_t>(k)] = source.FrameNumber(k);
  *all = TimeSceneFrames(c, /*first_index=*/0, std::move(numbers));
  if (!d.sensor) return "";
  const std::size_t edges = all->exposure_edges;
  if (edges > static_cast<std::size_t>(n)) {
    const std::string w = fmt::format(
        "{} exposure edges in {} for {} frames: frame k is timed by edge k, the last {} "
        "edge(s) are unused; if frames are missing from the sequence, every later frame "
        "time is wrong",
        edges, scene.inputs.sensor, n, edges - static_cast<std::size_t>(n));
    LogWarning("{}", w);
    c.summary.warnings.push_back("sensor: " + w);
  }
  if (scene.dic.first_frame != 0 || scene.dic.first_frame_number) return "";
  const double impact_s = d.sensor->summary.impact_time_s;
  const std::vector<double>& t = all->daq_time_s;
  const int reference = ReferenceFrameForImpact(t, impact_s);
  // With base channels the run measures the front in the DIC field, whose noise is each subset's
  // velocity over kMinNoiseFrames frames before the impact (momentum/wave_front.h: frame f with
  // frame f + 2 before it): the run starts kMinNoiseFrames + 1 frames before the reference.
  const int front_frames =
      scene.sensor.options.columns.base_force.empty() ? 0 : kMinNoiseFrames + 1;
  d.first_frame = std::max(0, reference - front_frames);
  if (d.last_frame - reference < 2) {  // Was "frames: got 1 frames from 49 to 49".
    throw Error(ErrorKind::kInvalidValue, "frame times",
                fmt::format("frames {}..{} at {:.6g} s .. {:.6g} s on the DAQ clock (by {}), "
                            "fewer than 3 of them from the last one before the impact at "
                            "{:.6g} s on",
                            0, n - 1, t.front(), t.back(), all->daq_clock, impact_s),
                "frames that film the impact: check sensor.frame_time_offset_s, the exposure "
                "channel and dic.last_frame")
        .WithFile(scene.path);
  }
  std::string note;
  if (d.first_frame > 0)
    note = fmt::format("; frames 0..{} before the impact are not correlated", d.first_frame - 1);
  if (d.first_frame < reference)
    note += fmt::format(
        "; frames {}..{} before the impact are correlated for the wave front's noise (base "
        "channels)",
        d.first_frame, reference - 1);
  return note;
}

// Checks the first analysed frame (the roi, the calibration's size); without a correlation to
// stream them, reads and preprocesses every frame once for the checks of the sequence (size,
// depth, colour), keeping none.
cv::Mat CheckFrames(StageContext& c, FrameStream& frames) {
  cv::Mat first = frames.ReadRaw(0);  // Not const: returned (moved).
  CheckSceneRoi(c.scene, first.size());
  if (c.data.calibration) CheckFrameSize(*c.data.calibration, first.size(), frames.Name(0));
  const int checked = c.scene.HasStage("correlate") ? 1 : frames.count();
  ProgressBar bar("frames", static_cast<std::size_t>(checked));
  for (int k = 0; k < checked; ++k) {
    frames.Read(k);
    bar.Advance();
  }
  bar.Finish();
  return first;
}

class FramesStage : public Stage {
 public:
  const char* name() const override { return "frames"; }

  std::string SkipReason(const StageContext& c) const override {
    return NotListed(c.scene, name());
  }

  std::string Run(StageContext& c) const override {
    const Scene& scene = c.scene;
    SceneRunData& d = c.data;
    const CameraCalibration* calibration = d.calibration ? &*d.calibration : nullptr;
    const std::vector<std::string>& files = scene.inputs.frame_files;
    const PreprocessOptions preprocess = MakePreprocessOptions(scene);  // Checked first.
    std::unique_ptr<FrameSource> source = std::move(d.given_frames);    // Frames in memory.
    if (!source)
      source = files.empty() ? OpenFrameSource(scene.inputs.frames) : MakeImageFileSource(files);
    d.frames = std::make_shared<FrameStream>(std::move(source), preprocess, calibration);
    d.source_frames = d.frames->source_frames();
    SelectFrameRange(scene, d);
    FrameTimeline all;
    const std::string skipped_note = TimeFrames(c, &all);
    if (const int min = MinFrames(scene); d.last_frame - d.first_frame < min - 1) {
      throw Error(
          ErrorKind::kInvalidValue, "frames",
          fmt::format("{} frames from {} to {}", std::max(0, d.last_frame - d.first_frame + 1),
                      d.first_frame, d.last_frame),
          min == 3 ? "at least 3 frames to correlate and differentiate"
                   : "at least two frames (the first is the reference)")
          .WithFile(files.empty() ? scene.inputs.frames : files.front());
    }
    d.frames->SetRange(d.first_frame, d.last_frame);
    d.timeline =
        all.Rows(static_cast<std::size_t>(d.first_frame), static_cast<std::size_t>(d.last_frame));
    const cv::Mat f0 = CheckFrames(c, *d.frames);
    d.preprocess_note = d.frames->PreprocessNote();
    if (!scene.HasStage("correlate")) {
      for (const auto& w : d.frames->warnings()) c.summary.warnings.push_back("frames: " + w);
    }
    const std::string rate =
        d.timeline.camera_stamps
            ? fmt::format(", {:.6g} fps and time stamps from the file", d.timeline.fps)
            : "";
    return fmt::format("{} of {} frames ({}x{}, {}{}){}; {}", d.frames->count(), d.source_frames,
                       f0.cols, f0.rows, DepthName(f0), rate, skipped_note, d.preprocess_note);
  }
};

}  // namespace

std::unique_ptr<Stage> MakeFramesStage() { return std::make_unique<FramesStage>(); }

}  // namespace impactdic::stages
