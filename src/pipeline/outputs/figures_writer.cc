// The figures (momentum, deceleration, added mass), the velocity snapshot at t_e and the
// animation, drawn by render RenderResults from results.h5 (on disk, or held in memory when
// outputs.hdf5 is false), over the frames re-read from their source one at a time. When the run
// computed strain (results.h5 has /strain), also the strain maps at t_e and at the last frame
// (with outputs.figures) and the strain animation (with outputs.animation); a run without it
// writes none of them.
#include <array>
#include <cstddef>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/pipeline/frame_stream.h"
#include "impactdic/pipeline/output_writer.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/render/gnuplot.h"
#include "impactdic/render/render_results.h"
#include "writers.h"

namespace impactdic::outputs {
namespace L = results_layout;
namespace {

class FiguresWriter : public OutputWriter {
 public:
  std::string name() const override { return "figures"; }
  std::vector<std::string> FileNames() const override {
    return {L::kRenderOutputNames.begin(), L::kRenderOutputNames.end()};
  }
  // Figures need gnuplot: find out before the run, not after it.
  void CheckBeforeRun(const Scene& scene) const override {
    if (scene.outputs.figures) DetectPngTerminal(ResolveGnuplotBinary(PlotOptions{}));
  }
  std::string SkipReason(const Scene& scene, const SceneRunData& d) const override {
    if (!scene.outputs.figures && !scene.outputs.animation) {
      return "outputs.figures and outputs.animation are false";
    }
    // A run of the first stages only (e.g. frames alone, to check them): nothing to draw.
    if (!d.sensor && !d.kinematics && !d.momentum && !d.model) {
      return "nothing to draw: none of the sensor, kinematics, momentum and model stages ran";
    }
    return "";
  }
  void Write(OutputContext& c) const override {
    const Scene& scene = c.scene;
    RenderResultsOptions r = SceneRenderOptions(scene);
    r.output_dir = c.folder;
    r.new_generation = false;  // Part of the run's generation.
    r.png_frames = r.animation && (c.options.png_frames || scene.outputs.png_frames);
    if (c.data.frames) {  // Re-read from the source, one at a time (results.h5 holds a preview).
      const std::shared_ptr<FrameStream> frames = c.data.frames;
      r.frame_loader = [frames](std::size_t row) { return frames->Read(static_cast<int>(row)); };
    }
    const RenderResultsSummary rendered =
        scene.outputs.hdf5
            ? RenderResults(c.results_path, r)
            : RenderResults(H5Reader(c.results_path, c.results_in_memory), c.results_path, r);
    for (const auto& w : rendered.written) c.summary.outputs.push_back(w);
    for (const auto& s : rendered.skipped) c.summary.warnings.push_back("render: " + s);
  }
};

}  // namespace

std::shared_ptr<const OutputWriter> MakeFiguresWriter() {
  return std::make_shared<FiguresWriter>();
}

}  // namespace impactdic::outputs
