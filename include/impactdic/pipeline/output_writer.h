// The outputs of a run as writers: results.h5, the figures and animation, summary.json,
// summary.csv, timing.json. A writer is one class in one file; the run calls every registered
// writer in turn on the finished run (after ThrowIfFailed), each writing into the staging folder of
// the run's output generation (io/output_generation.h), so a failing writer leaves the previous
// outputs.
//
// Adding an output format (docs/architecture.md, "How to add an output format"): write a class
// deriving from OutputWriter in a new file src/pipeline/outputs/NAME_writer.cc with a factory
// function, and add one line naming the factory and the file to the registration list
// src/pipeline/outputs/output_writers.def, which declares the factory, puts it in
// BuiltInOutputWriters() and has the file compiled. A caller can also pass writers of its own in
// PipelineOptions::extra_output_writers (tests/pipeline/output_writer_test.cc does).
//
//   class FrameTimesCsvWriter : public OutputWriter {
//    public:
//     std::string name() const override { return "frame_times.csv"; }
//     std::vector<std::string> FileNames() const override { return {"frame_times.csv"}; }
//     std::string SkipReason(const Scene&, const SceneRunData& d) const override {
//       return d.timeline.OnDaqClock() ? "" : "no DAQ frame times";
//     }
//     void Write(OutputContext& c) const override {
//       WriteCsv(c.Path("frame_times.csv"), {"t_s"}, {c.data.timeline.daq_time_s});
//       c.summary.outputs.push_back(c.Path("frame_times.csv"));
//     }
//   };
#ifndef IMPACTDIC_PIPELINE_OUTPUT_WRITER_H_
#define IMPACTDIC_PIPELINE_OUTPUT_WRITER_H_

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic {

struct PipelineOptions;
struct PipelineSummary;

// What a writer sees: the scene, the run's data and summary, and where to write.
struct OutputContext {
  const Scene& scene;
  const PipelineOptions& options;
  const SceneRunData& data;
  // The figures, stages, failures and warnings so far. A writer appends every file it wrote to
  // summary.outputs (staging paths; the run renames them to their final paths) and its warnings.
  PipelineSummary& summary;
  std::string folder;  // The staging folder of the output generation: write here.
  // results.h5 as the results writer left it for the writers after it: its path in `folder` and,
  // when outputs.hdf5 is false (the file is not kept), its bytes (H5Reader(results_path, bytes)).
  std::string results_path;
  std::vector<char> results_in_memory;

  std::string Path(const std::string& name) const;  // folder/name
};

class OutputWriter {
 public:
  virtual ~OutputWriter() = default;
  // For logs and messages.
  virtual std::string name() const = 0;
  // Every file or folder name it may write into the output folder (the generation's own names:
  // a later run replaces them, and they are not mistaken for foreign files).
  virtual std::vector<std::string> FileNames() const = 0;
  // Called before any stage runs: Error when the writer cannot work (e.g. no gnuplot), so a run
  // does not fail after its correlation. Default: nothing to check.
  virtual void CheckBeforeRun(const Scene& /*scene*/) const {}
  // Why it writes nothing for this scene and run ("" = it writes). Asked of every writer before any
  // of them writes, on the whole run's data (results.h5's writer releases rows after it).
  virtual std::string SkipReason(const Scene& scene, const SceneRunData& data) const = 0;
  virtual void Write(OutputContext& context) const = 0;
};

using OutputWriters = std::vector<std::shared_ptr<const OutputWriter>>;

// results.h5, figures + animation, summary.json, summary.csv, timing.json: in this order (the
// figures are drawn from results.h5; summary.json holds the figures' warnings).
OutputWriters BuiltInOutputWriters();

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_OUTPUT_WRITER_H_
