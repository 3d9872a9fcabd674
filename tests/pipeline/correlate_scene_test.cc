// `impactdic correlate` is a scene run through the one stage graph
// (pipeline/correlate_scene.h): CorrelateScene runs the frames and correlate stages of `run`, so on
// the same scene its /dic is the run's own, bit for bit (NaNs included); only the row numbering
// differs (from the reference, no first_frame attribute, as `correlate -o` always wrote). Before,
// `correlate` had its own driver (CorrelateFiles) and no stages.
#include "impactdic/pipeline/correlate_scene.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "../reliability/fault_util.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic {
namespace {

// The bytes of a vector (NaNs compare by their bits).
template <typename T>
bool SameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

TEST(CorrelateScene, RunsTheFramesAndCorrelateStagesOfRunBitForBit) {
  const TestDir dir;
  // The sample's frames 5..9, no calibration or sensor (what `correlate` reads).
  Scene scene = LoadScene(SampleScene(dir, {}));
  scene.inputs.calibration.clear();
  scene.inputs.sensor.clear();
  scene.inputs.mm_per_px = 0.5;
  scene.dic.first_frame = 5;
  scene.dic.last_frame = 9;
  scene.stages = {"frames", "correlate", "outputs"};
  PipelineOptions options;
  options.output_folder = dir.File("run");
  RunScene(scene, options);
  const PipelineSummary s = CorrelateScene(scene, dir.File("correlate.h5"));
  ASSERT_EQ(s.stages.size(), 2u);
  EXPECT_EQ(s.stages[0].name, "frames");
  EXPECT_EQ(s.stages[1].name, "correlate");
  EXPECT_TRUE(s.stages[0].ran && s.stages[1].ran);
  EXPECT_EQ(s.outputs, std::vector<std::string>{dir.File("correlate.h5")});

  const H5Reader run(dir.File("run/results.h5")), cor(dir.File("correlate.h5"));
  for (const char* name : {"/dic/x_px", "/dic/y_px", "/dic/u_px", "/dic/v_px", "/dic/frame_number"})
    EXPECT_TRUE(SameBits(run.ReadDouble(name), cor.ReadDouble(name))) << name;
  for (const char* name : {"/dic/zncc", "/dic/sigma_u_px", "/dic/sigma_v_px", "/dic/sigma_px"})
    EXPECT_TRUE(SameBits(run.ReadFloat(name), cor.ReadFloat(name))) << name;
  for (const char* name : {"/dic/status", "/dic/iterations"})
    EXPECT_EQ(run.ReadInt(name), cor.ReadInt(name)) << name;
  EXPECT_EQ(run.ReadDouble("/dic/u_px").size(), 5 * run.ReadDouble("/dic/x_px").size());
  // Rows numbered from the reference: the run's frame indices less its first frame.
  std::vector<std::int32_t> frame = run.ReadInt("/dic/frame");
  for (auto& f : frame) f -= 5;
  EXPECT_EQ(cor.ReadInt("/dic/frame"), frame);
  EXPECT_EQ(cor.ReadInt("/dic/frame"), (std::vector<std::int32_t>{0, 1, 2, 3, 4}));
  EXPECT_FALSE(cor.HasAttribute("/dic", "first_frame"));
}

// With inputs.calibration (`correlate --inputs.calibration`), the calibrate stage runs first and
// the frames are undistorted as in `run`: the same /dic as the run's, unlike the raw frames'.
TEST(CorrelateScene, ACalibrationIsAppliedAsInRun) {
  const TestDir dir;
  Scene scene = LoadScene(SampleScene(dir, {}));
  ASSERT_FALSE(scene.inputs.calibration.empty());
  scene.inputs.sensor.clear();
  scene.dic.first_frame = 5;
  scene.dic.last_frame = 7;
  scene.dic.options.grid.step = 40;
  scene.stages = {"calibrate", "frames", "correlate", "outputs"};
  PipelineOptions options;
  options.output_folder = dir.File("run");
  RunScene(scene, options);
  const PipelineSummary s = CorrelateScene(scene, dir.File("calibrated.h5"));
  ASSERT_EQ(s.stages.size(), 3u);
  EXPECT_EQ(s.stages[0].name, "calibrate");
  EXPECT_TRUE(s.stages[0].ran);
  scene.inputs.calibration.clear();
  scene.inputs.mm_per_px = 0.5;
  CorrelateScene(scene, dir.File("raw.h5"));
  const H5Reader run(dir.File("run/results.h5")), cal(dir.File("calibrated.h5")),
      raw(dir.File("raw.h5"));
  for (const char* name : {"/dic/u_px", "/dic/v_px"}) {
    EXPECT_TRUE(SameBits(run.ReadDouble(name), cal.ReadDouble(name))) << name;
    EXPECT_FALSE(SameBits(raw.ReadDouble(name), cal.ReadDouble(name))) << name;
  }
}

// The command is that function: its log shows the two stages, and its file is CorrelateScene's.
TEST(CorrelateScene, TheCommandRunsTheStages) {
  const TestDir dir;
  const std::string frames = std::string(impactdic::SourceDir()) + "/sample_frames/frames/*.png";
  const CliResult r = RunCli("correlate --frames '" + frames +
                             "' --dic.first_frame 5 --dic.last_frame 7 --step 64 --warp-gradient "
                             "-o " +
                             dir.File("cli.h5"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* stage : {"[frames] 3 of 54 frames", "[correlate] "})
    EXPECT_NE(r.output.find(stage), std::string::npos) << stage << "\n" << r.output;
  Scene scene;
  scene.inputs.frames = frames;
  scene.dic.first_frame = 5;
  scene.dic.last_frame = 7;
  scene.dic.options.grid.step = 64;
  scene.dic.options.keep_warp_gradient = true;
  CorrelateScene(scene, dir.File("lib.h5"));
  const H5Reader cli(dir.File("cli.h5")), lib(dir.File("lib.h5"));
  for (const char* name : {"/dic/u_px", "/dic/v_px", "/dic/dudx_warp", "/dic/dvdy_warp"})
    EXPECT_TRUE(SameBits(cli.ReadDouble(name), lib.ReadDouble(name))) << name;
}

}  // namespace
}  // namespace impactdic
