// strain.csv: the strain series of the strain stage (strain.enabled, outputs.csv), one row per
// analysed frame and subset, written row by row (io/csv.h CsvRowWriter): frame (index in the input
// sequence), t_ms (/time/t_ms), subset, x_px, y_px (reference centre), then the /strain measures
// under their /strain names (docs/strain.md).
#include <fmt/format.h>

#include <cmath>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "impactdic/io/csv.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/pipeline/output_writer.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/strain/strain_results.h"
#include "writers.h"

namespace impactdic::outputs {
namespace L = results_layout;
namespace {

std::string Cell(double v) {
  return std::isnan(v) ? std::string("nan") : fmt::format("{:.10g}", v);
}

class StrainCsvWriter : public OutputWriter {
 public:
  std::string name() const override { return L::kStrainCsv; }
  std::vector<std::string> FileNames() const override { return {L::kStrainCsv}; }
  std::string SkipReason(const Scene& scene, const SceneRunData& data) const override {
    if (!scene.outputs.csv) return "outputs.csv is false";
    return data.strain ? "" : "the strain stage did not run";
  }
  void Write(OutputContext& c) const override {
    const SceneRunData& d = c.data;
    const StrainResult& r = *d.strain;
    const std::vector<StrainMeasure> measures = StrainMeasures(r);
    std::vector<std::string> names = {"frame", "t_ms", "subset", "x_px", "y_px"};
    for (const StrainMeasure& m : measures) names.push_back(m.Name());
    names.emplace_back("shear_band");
    const std::vector<double> t_ms = d.timeline.MsSinceStart();
    const std::string path = c.Path(L::kStrainCsv);
    CsvRowWriter out(path, names);
    std::vector<std::string> row(names.size());
    const std::size_t ns = r.field.subsets;
    for (std::size_t f = 0; f < r.field.frames; ++f) {
      const std::string frame = std::to_string(d.timeline.index[f]);
      const std::string t = Cell(t_ms[f]);
      for (std::size_t i = 0; i < ns; ++i) {
        const std::size_t j = f * ns + i;
        std::size_t k = 0;
        row[k++] = frame;
        row[k++] = t;
        row[k++] = std::to_string(i);
        row[k++] = Cell(d.dic->x_px[i]);
        row[k++] = Cell(d.dic->y_px[i]);
        for (const StrainMeasure& m : measures) row[k++] = Cell((*m.values)[j]);
        row[k++] = std::to_string(static_cast<int>(r.shear_band[j]));
        out.Row(row);
      }
    }
    out.Commit();
    c.summary.outputs.push_back(path);
  }
};

}  // namespace

std::shared_ptr<const OutputWriter> MakeStrainCsvWriter() {
  return std::make_shared<StrainCsvWriter>();
}

}  // namespace impactdic::outputs
