// summary.json and summary.csv: the key figures of the run (PipelineSummary::ToJson, SceneFigures);
// timing.json: its wall times and rates (PipelineSummary::TimingJson).
#include <memory>
#include <string>
#include <vector>

#include "impactdic/io/atomic_file.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/json.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/pipeline/output_writer.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "writers.h"

namespace impactdic::outputs {
namespace L = results_layout;
namespace {

class SummaryJsonWriter : public OutputWriter {
 public:
  std::string name() const override { return L::kSummaryJson; }
  std::vector<std::string> FileNames() const override { return {L::kSummaryJson}; }
  std::string SkipReason(const Scene&, const SceneRunData&) const override { return ""; }
  void Write(OutputContext& c) const override {
    const std::string path = c.Path(L::kSummaryJson);
    WriteTextFileAtomic(path, c.summary.ToJson().Dump() + "\n");
    c.summary.outputs.push_back(path);
  }
};

class SummaryCsvWriter : public OutputWriter {
 public:
  std::string name() const override { return L::kSummaryCsv; }
  std::vector<std::string> FileNames() const override { return {L::kSummaryCsv}; }
  std::string SkipReason(const Scene& scene, const SceneRunData&) const override {
    return scene.outputs.csv ? "" : "outputs.csv is false";
  }
  void Write(OutputContext& c) const override {
    const std::string path = c.Path(L::kSummaryCsv);
    std::vector<std::string> names = c.summary.figures.CsvNames();
    std::vector<double> values = c.summary.figures.CsvValues();
    if (c.summary.strain) {  // The strain stage's columns, only when it ran.
      for (const std::string& n : c.summary.strain->CsvNames()) names.push_back(n);
      for (double v : c.summary.strain->CsvValues()) values.push_back(v);
    }
    std::vector<std::vector<double>> columns;
    for (double v : values) columns.push_back({v});
    WriteCsv(path, names, columns);
    c.summary.outputs.push_back(path);
  }
};

class TimingJsonWriter : public OutputWriter {
 public:
  std::string name() const override { return L::kTimingJson; }
  std::vector<std::string> FileNames() const override { return {L::kTimingJson}; }
  std::string SkipReason(const Scene&, const SceneRunData&) const override { return ""; }
  void Write(OutputContext& c) const override {
    const std::string path = c.Path(L::kTimingJson);
    WriteTextFileAtomic(path, c.summary.TimingJson().Dump() + "\n");
    c.summary.outputs.push_back(path);
  }
};

}  // namespace

std::shared_ptr<const OutputWriter> MakeTimingJsonWriter() {
  return std::make_shared<TimingJsonWriter>();
}
std::shared_ptr<const OutputWriter> MakeSummaryJsonWriter() {
  return std::make_shared<SummaryJsonWriter>();
}
std::shared_ptr<const OutputWriter> MakeSummaryCsvWriter() {
  return std::make_shared<SummaryCsvWriter>();
}

}  // namespace impactdic::outputs
