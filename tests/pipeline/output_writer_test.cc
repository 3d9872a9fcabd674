// The output writers' extension point (pipeline/output_writer.h), shown by a worked example: a
// test-only writer of one more format, registered with one line (PipelineOptions::
// extra_output_writers) and invoked by the outputs stage like the built-in ones. The same steps
// add a built-in format (docs/architecture.md, "How to add an output format").
#include "impactdic/pipeline/output_writer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

// The new format: the modelled crater depth and stopping time as a two-line text file.
class ModelTextWriter : public OutputWriter {
 public:
  std::string name() const override { return "model.txt"; }
  std::vector<std::string> FileNames() const override { return {"model.txt"}; }
  std::string SkipReason(const Scene&, const SceneRunData& data) const override {
    return data.model ? "" : "no model solve";
  }
  void Write(OutputContext& c) const override {
    const std::string path = c.Path("model.txt");
    std::ostringstream text;
    text.precision(17);
    text << "crater_depth_m " << c.data.model->summary.crater_depth_m << "\n"
         << "t_end_s " << c.data.model->summary.t_end_s << "\n";
    WriteTextFileAtomic(path, text.str());
    c.summary.outputs.push_back(path);
  }
};

Scene ModelOnlyScene(const TestDir& dir, const std::string& stages) {
  // The frames are named but not read (no frames stage).
  return ParseScene("inputs: {frames: frames}\nstages: " + stages +
                        "\noutputs: {folder: out, figures: false, animation: false}\n",
                    dir.File("scene.yaml"));
}

TEST(OutputWriter, ARegisteredWriterIsInvokedWithTheRunsData) {
  TestDir dir;
  PipelineOptions options;
  options.extra_output_writers.push_back(std::make_shared<ModelTextWriter>());  // Registration.
  const PipelineSummary s = RunScene(ModelOnlyScene(dir, "[model, outputs]"), options);
  const fs::path file = fs::path(dir.File("out")) / "model.txt";
  ASSERT_TRUE(fs::exists(file));
  // Listed among the outputs with its final path (not the staging folder's).
  EXPECT_NE(std::find(s.outputs.begin(), s.outputs.end(), file.string()), s.outputs.end());
  // It saw the same model solve as the summary.
  std::ifstream in(file);
  std::string key;
  double depth = 0, t_end = 0;
  in >> key >> depth >> key >> t_end;
  EXPECT_EQ(depth, s.figures.crater_depth_model_m);
  EXPECT_EQ(t_end, s.figures.t_end_model_s);
  EXPECT_TRUE(fs::exists(fs::path(dir.File("out")) / "summary.json"));  // The built-in ones too.
  // Its file is one of the run's own names: the next run's generation replaces it.
  const PipelineSummary again = RunScene(ModelOnlyScene(dir, "[outputs]"), options);
  EXPECT_FALSE(fs::exists(file));  // No model this time: skipped, and the old file is gone.
  EXPECT_TRUE(fs::exists(fs::path(dir.File("out")) / "summary.json"));
}

// Reading and checking the frames alone (docs/architecture.md: `frames` alone) with the default
// figures on: the figures writer has nothing to draw and says so, instead of failing the finished
// run.
TEST(OutputWriter, AFramesOnlyRunSkipsTheFiguresInsteadOfFailing) {
  TestDir dir;
  const std::string sample = std::string(impactdic::SourceDir()) + "/sample_frames/";
  const Scene scene =
      ParseScene("inputs: {frames: " + sample + "frames}\nstages: [frames, outputs]\n" +
                     "dic: {last_frame: 2}\noutputs: {folder: out, animation: false}\n",
                 dir.File("scene.yaml"));
  ASSERT_TRUE(scene.outputs.figures);  // The default.
  const PipelineSummary s = RunScene(scene, PipelineOptions{});
  const fs::path out = dir.File("out");
  EXPECT_TRUE(fs::exists(out / "results.h5"));
  EXPECT_TRUE(fs::exists(out / "summary.json"));
  for (const auto& o : s.outputs) EXPECT_NE(fs::path(o).extension(), ".png") << o;
}

TEST(OutputWriter, BuiltInWritersAreTheSevenFormats) {
  std::vector<std::string> names;
  for (const auto& w : BuiltInOutputWriters()) names.push_back(w->name());
  // strain.csv first: the strain fields are released once results.h5 is written.
  EXPECT_EQ(names, (std::vector<std::string>{"strain.csv", "results.h5", "results.xdmf", "figures",
                                             "summary.json", "summary.csv", "timing.json"}));
}

}  // namespace
}  // namespace impactdic
