// load_dic: the correlation results of a results file (its /dic group, io ReadDicResults) in place
// of the frames and correlate stages, for `impactdic analyze SCENE` (pipeline/scene_analysis.h):
// the rows, the frame range they cover, and the frames timed on the DAQ clock as the frames stage
// times them (sensor FrameTimes on the scene's clock), so that the stages after it see what they
// see in `run`.
#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <string>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/io/dic_results.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/pipeline/frame_stream.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/sensor/sensor.h"
#include "stage.h"

namespace impactdic::stages {
namespace {

constexpr const char* kValidFractionAttr = "valid_fraction";

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
    d.first_frame =
        dic.first_frame >= 0 ? static_cast<int>(dic.first_frame) : c.scene.dic.first_frame;
    d.last_frame = d.first_frame + static_cast<int>(dic.rows) - 1;
    d.source_frames = d.last_frame + 1;  // At least: the frames themselves are not read.
    d.clock = SceneFrameClock(c.scene);
    if (d.sensor) TimeFrames(c);
    // The correlation's DicSummary::valid_fraction, as the correlate stage reports it (an
    // attribute of /dic written by dic MakeDicResultsTable; absent from older files: NaN).
    if (in.HasAttribute(results_layout::kDicGroup, kValidFractionAttr))
      c.summary.figures.dic_valid_fraction =
          in.ReadNumberAttribute(results_layout::kDicGroup, kValidFractionAttr);
    return fmt::format("{} rows x {} subsets of {} (frames {}..{})", dic.rows, dic.subsets, file_,
                       d.first_frame, d.last_frame);
  }

 private:
  // The DAQ time of every frame up to the last analysed one.
  static void TimeFrames(StageContext& c) {
    SceneRunData& d = c.data;
    RequireExposureChannel(*d.sensor, c.scene.sensor.options.columns.exposure);
    try {
      d.frame_times_s = FrameTimes(*d.sensor, d.source_frames, d.clock);
    } catch (Error& e) {
      NameFileToFix(c, e);
      throw;
    }
  }

  std::string file_;
};

}  // namespace

std::unique_ptr<Stage> MakeLoadDicStage(const std::string& results_file) {
  return std::make_unique<LoadDicStage>(results_file);
}

}  // namespace impactdic::stages
