// results.h5: everything the run measured and modelled (layout: io/results_layout.h and the
// groups' owners it lists, docs/results.md): each group written by its owner. Without
// outputs.hdf5 it is still built, in memory, when the figures or the animation need it
// (OutputContext::results_in_memory), and not kept.
#include <algorithm>
#include <cstddef>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>
#include <vector>

#include "impactdic/io/dic_results.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/kinematics/kinematics_results.h"
#include "impactdic/model/model_results.h"
#include "impactdic/momentum/momentum_results.h"
#include "impactdic/pipeline/frame_stream.h"
#include "impactdic/pipeline/output_writer.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/sensor/frame_timeline.h"
#include "impactdic/sensor/sensor_results.h"
#include "impactdic/sensor/wave_results.h"
#include "impactdic/strain/strain_results.h"
#include "writers.h"

namespace impactdic::outputs {
namespace L = results_layout;
namespace {

// /frames/images: the analysed frames after preprocessing (outputs.frames: a preview, or all),
// with their own depth (8 or 16 bit), re-read from their source one at a time; /frames/row: the
// analysed row (index in /time) of each stored frame, and the preview's downsampling factor.
void WriteFrames(H5Writer& out, FrameStream& frames, FrameStorage storage) {
  const cv::Mat first = frames.Read(0);
  FramePreviewPlan plan;
  if (storage == FrameStorage::kPreview) {
    plan = PlanFramePreview(frames.count(), first.size());
  } else {
    for (int k = 0; k < frames.count(); ++k) plan.rows.push_back(k);
  }
  const cv::Size size = plan.ImageSize(first.size());
  const int bits = first.depth() == CV_16U ? 16 : 8;
  auto fill = [&](std::size_t i, void* buffer) {
    const int row = plan.rows[i];
    const cv::Mat image = row == 0 ? first : frames.Read(row);
    cv::Mat stored(size, image.type(), buffer);
    if (plan.downsample == 1) {
      image.copyTo(stored);
    } else {
      cv::resize(image, stored, size, 0, 0, cv::INTER_AREA);
    }
  };
  out.WriteStack(L::kFrameImages,
                 {plan.rows.size(), static_cast<std::size_t>(size.height),
                  static_cast<std::size_t>(size.width)},
                 bits, fill, "grey level",
                 storage == FrameStorage::kPreview
                     ? "preview of the analysed camera frames after preprocessing"
                     : "analysed camera frames after preprocessing");
  std::vector<double> rows(plan.rows.begin(), plan.rows.end());
  out.Write(L::kFrameRows, rows, "1", "row of /time and /dic of each stored frame");
  out.SetAttribute(L::kFramesGroup, L::kBitDepthAttr, static_cast<double>(bits));
  out.SetAttribute(L::kFramesGroup, L::kDownsampleAttr, static_cast<double>(plan.downsample));
  out.SetAttribute(L::kFramesGroup, L::kFrameWidthAttr, static_cast<double>(first.cols));
  out.SetAttribute(L::kFramesGroup, L::kFrameHeightAttr, static_cast<double>(first.rows));
}

// /sensor, /wave, /kinematics, /momentum, each by its owner's writer.
void WriteMotion(H5Writer& out, const SceneRunData& d) {
  if (d.sensor) WriteSensorResults(out, *d.sensor);
  if (d.wave) {
    WriteWaveResults(out, *d.sensor, *d.wave);  // Only with base force channels.
  } else {
    out.Remove(L::kWaveGroup);  // An earlier analysis' (analyze SCENE), when the scene has none.
  }
  if (d.kinematics) WriteKinematicsResults(out, *d.kinematics, d.timeline.daq_time_s, d.mm_per_px);
  if (d.momentum) WriteMomentumResults(out, *d.momentum, d.sensor->summary.impact_time_s);
}

// /, /stages and /summary attributes: the scene, what each stage did, the key figures.
void WriteRunAttributes(H5Writer& out, const Scene& scene, const PipelineSummary& summary) {
  out.WriteProvenance(scene.yaml_text);
  out.SetAttribute("/", "scene_name", scene.name);
  out.SetAttribute("/", "scene_path", scene.path);
  for (const auto& s : summary.stages)
    out.SetAttribute("/stages", s.name, s.ran ? "ran: " + s.note : "skipped: " + s.note);
}

void WriteSummaryGroup(H5Writer& out, const PipelineSummary& summary) {
  const auto names = summary.figures.CsvNames();
  const auto values = summary.figures.CsvValues();
  out.CreateGroup("/summary");
  for (std::size_t i = 0; i < names.size(); ++i) out.SetAttribute("/summary", names[i], values[i]);
  out.SetAttribute("/summary", "failures",
                   summary.failures.empty() ? std::string("none") : summary.FailureText());
}

class ResultsFileWriter : public OutputWriter {
 public:
  std::string name() const override { return L::kResultsFile; }
  std::vector<std::string> FileNames() const override { return {L::kResultsFile}; }
  std::string SkipReason(const Scene& scene, const SceneRunData&) const override {
    const auto& o = scene.outputs;
    return o.hdf5 || o.figures || o.animation ? ""
                                              : "outputs.hdf5, figures and animation are false";
  }
  void Write(OutputContext& c) const override {
    const SceneRunData& d = c.data;
    c.results_path = c.Path(L::kResultsFile);
    // Without outputs.hdf5 the file is only read by the other writers: in memory, so that it
    // needs no room on the disk.
    H5Writer out(c.results_path, H5Writer::Mode::kCreate, "",
                 c.scene.outputs.hdf5 ? H5Writer::Backing::kFile : H5Writer::Backing::kMemory);
    WriteRunAttributes(out, c.scene, c.summary);
    if (d.dic) WriteDicResults(out, *d.dic);
    if (d.frames && c.scene.outputs.frames != FrameStorage::kNone)
      WriteFrames(out, *d.frames, c.scene.outputs.frames);
    WriteAnalysisResults(out, d);
    if (c.scene.outputs.hdf5 && c.scene.outputs.xdmf) WriteXdmfViews(out);
    WriteSummaryGroup(out, c.summary);
    if (c.scene.outputs.hdf5) {
      out.Commit();
      c.summary.outputs.push_back(c.results_path);
    } else {
      c.results_in_memory = out.CommitToMemory();
    }
  }
};

}  // namespace

void WriteAnalysisResults(H5Writer& out, const SceneRunData& d) {
  if (d.dic) WriteFrameTimeline(out, d.timeline);  // Replaces an earlier analysis' /time.
  WriteMotion(out, d);
  if (d.model) {
    out.Remove(L::kModelGroup);  // An earlier analysis' (analyze SCENE).
    WriteModelResults(out, d.model_parameters, *d.model);
  }
  if (d.strain) WriteStrainResults(out, *d.strain);  // Nothing without the strain stage.
}

std::shared_ptr<const OutputWriter> MakeResultsFileWriter() {
  return std::make_shared<ResultsFileWriter>();
}

}  // namespace impactdic::outputs
