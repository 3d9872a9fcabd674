// load_dic: the correlation results of a results file (its /dic group, io ReadDicResults) in place
// of the frames and correlate stages, for `impactdic analyze SCENE` (pipeline/scene_analysis.h):
// the rows, the source frames they are (a run's first_frame attribute, else their frame numbers
// found in the scene's frames), and their timeline built as the frames stage builds it (stages
// TimeSceneFrames), so that the stages after it see what they see in `run`.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/io/dic_results.h"
#include "impactdic/io/frame_source.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/pipeline/frame_stream.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/sensor/frame_timeline.h"
#include "stage.h"

namespace impactdic::stages {
namespace {

constexpr const char* kValidFractionAttr = "valid_fraction";

// A row's frame number in messages.
std::string RowName(std::size_t row, const std::string& file) {
  return fmt::format("{}[{}] in {}", results_layout::kDicFrameNumber, row, file);
}

// The position in the scene's frame source of the results' row 0, after checking that the rows
// are consecutive frames. A run's results say it (first_frame attribute, or version 1 of the
// layout, and /dic/frame holds the positions); `correlate` numbers its rows from the reference, so
// its rows' frame numbers are found in the scene's frames (inputs.frames): Error naming the number
// and the frames when one is not there, or when the file has neither.
int SourceIndexOfFirstRow(const Scene& scene, const DicResultsTable& dic, const std::string& file) {
  // Version 1 was written by `run` alone: its /dic/frame holds the positions.
  const bool v1_positions = dic.layout_version == 1 && !dic.frame.empty();
  if (dic.first_frame >= 0 || v1_positions) {
    const long first = dic.first_frame >= 0 ? dic.first_frame : dic.frame.front();
    for (std::size_t r = 0; r < dic.frame.size(); ++r) {
      if (dic.frame[r] == first + static_cast<long>(r)) continue;
      throw Error(ErrorKind::kFileFormat, results_layout::kDicFrame,
                  fmt::format("frame {} in row {}", dic.frame[r], r),
                  fmt::format("the frames from {} on, one per row", first))
          .WithFile(file);
    }
    return static_cast<int>(first);
  }
  const bool numbered =
      !dic.frame_number.empty() && std::all_of(dic.frame_number.begin(), dic.frame_number.end(),
                                               [](double n) { return std::isfinite(n); });
  if (!numbered || scene.inputs.frames.empty()) {
    throw Error(ErrorKind::kFileFormat, results_layout::kDicGroup,
                !numbered ? "rows without frame numbers or a first_frame attribute"
                          : "rows numbered by their frames, no first_frame",
                "the frames of the scene (inputs.frames) to find the rows' frame numbers in, or "
                "the results of `impactdic run` (they say which frames their rows are)")
        .WithFile(file);
  }
  const std::unique_ptr<FrameSource> source = OpenFrameSource(scene.inputs.frames);
  const int first = FrameIndexOf(*source, std::llround(dic.frame_number[0]), RowName(0, file));
  for (std::size_t r = 1; r < dic.rows; ++r) {
    const int k = first + static_cast<int>(r);
    const long long number = std::llround(dic.frame_number[r]);
    if (k < source->frame_count() && source->FrameNumber(k) == number) continue;
    throw Error(ErrorKind::kFileFormat, RowName(r, file), std::to_string(number),
                fmt::format("frame {} of {}, the frame after row {}'s: the rows are consecutive "
                            "frames of inputs.frames",
                            k < source->frame_count() ? std::to_string(source->FrameNumber(k))
                                                      : std::string("(none)"),
                            source->description(), r - 1))
        .WithFile(scene.path);
  }
  return first;
}

// The time stamps a results file stores (/dic/time_s, a camera file's) against the timeline's:
// the same frames on the same camera clock, else Error naming both.
void CheckTimeStamps(const DicResultsTable& dic, const FrameTimeline& timeline, const Scene& scene,
                     const std::string& file) {
  if (dic.time_s.empty() || !timeline.camera_stamps) return;
  for (std::size_t r = 0; r < dic.rows; ++r) {
    const double a = dic.time_s[r], b = timeline.camera_time_s[r];
    if (std::abs(a - b) <= 1e-9 * std::max(1.0, std::abs(b))) continue;
    throw Error(ErrorKind::kInvalidValue, fmt::format("{}[{}]", results_layout::kDicTimeS, r),
                fmt::format("{:.9g} s in {}", a, file),
                fmt::format("the time stamp of frame {} in {}, {:.9g} s: the results are of "
                            "other frames than the scene's",
                            timeline.number[r], scene.inputs.frames, b))
        .WithFile(file);
  }
}

class LoadDicStage : public Stage {
 public:
  explicit LoadDicStage(std::string file) : file_(std::move(file)) {}

  const char* name() const override { return "load_dic"; }

  std::string SkipReason(const StageContext&) const override { return ""; }

  std::string Run(StageContext& c) const override {
    SceneRunData& d = c.data;
    if (!std::filesystem::exists(file_)) {
      throw Error(ErrorKind::kFileNotFound, "", "",
                  "the correlation results (run `impactdic correlate` or `impactdic run` first)")
          .WithFile(file_);
    }
    const H5Reader in(file_);
    const DicResultsTable& dic = d.dic.emplace(ReadDicResults(in, file_));
    d.dic_file = file_;
    d.first_frame = SourceIndexOfFirstRow(c.scene, dic, file_);
    d.last_frame = d.first_frame + static_cast<int>(dic.rows) - 1;
    d.source_frames = d.last_frame + 1;  // At least: the frames themselves are not read.
    std::vector<long long> numbers;
    for (std::size_t r = 0; r < dic.rows; ++r) {
      const bool numbered = !dic.frame_number.empty() && std::isfinite(dic.frame_number[r]);
      numbers.push_back(numbered ? std::llround(dic.frame_number[r])
                                 : d.first_frame + static_cast<long long>(r));
    }
    d.timeline = TimeSceneFrames(c, d.first_frame, std::move(numbers));
    CheckTimeStamps(dic, d.timeline, c.scene, file_);
    // The correlation's DicSummary::valid_fraction, as the correlate stage reports it (an
    // attribute of /dic written by dic MakeDicResultsTable; absent from older files: NaN).
    if (in.HasAttribute(results_layout::kDicGroup, kValidFractionAttr))
      c.summary.figures.dic_valid_fraction =
          in.ReadNumberAttribute(results_layout::kDicGroup, kValidFractionAttr);
    return fmt::format("{} rows x {} subsets of {} (frames {}..{}, numbered {}..{}; DAQ clock: {})",
                       dic.rows, dic.subsets, file_, d.first_frame, d.last_frame,
                       d.timeline.number.front(), d.timeline.number.back(),
                       d.timeline.OnDaqClock() ? d.timeline.daq_clock : "none");
  }

 private:
  std::string file_;
};

}  // namespace

std::unique_ptr<Stage> MakeLoadDicStage(const std::string& results_file) {
  return std::make_unique<LoadDicStage>(results_file);
}

}  // namespace impactdic::stages
