// Outputs never destroy inputs or other commands' data (docs/reliability.md):
// an output that is an input, or has the wrong extension, is refused before any work and the file
// is left as it was; writing into an existing HDF5 file replaces only the groups the command owns;
// an existing file of another kind under an .h5 name is kept.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "impactdic/io/hdf5_store.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

const std::string kSource = impactdic::SourceDir();
const std::string kSensorCsv = kSource + "/sample_frames/sensor.csv";
const std::string kFrames = kSource + "/sample_frames/frames/";

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void ExpectRefused(const CliResult& r, const std::vector<std::string>& words) {
  EXPECT_EQ(r.exit_code, 1) << r.output;
  for (const std::string& w : words)
    EXPECT_NE(r.output.find(w), std::string::npos) << w << "\n" << r.output;
}

// A results file as `run` leaves it, reduced to what the tests look at: /dic, /frames, /sensor.
void WriteResultsLike(const std::string& path) {
  H5Writer out(path);
  out.Write("dic/u_px", std::vector<double>{1.5, 2.5, 3.5}, "px", "displacement");
  out.Write("frames/images", std::vector<std::uint8_t>(2 * 3 * 4, 7), {2, 3, 4}, "grey level",
            "frames");
  out.Write("sensor/t_s", std::vector<double>{-1, -2}, "s", "an older sensor series");
  out.Write("sensor/old_only", std::vector<double>{9}, "1", "gone once /sensor is rewritten");
  out.SetAttribute("/", "scene_name", "kept");
  out.Commit();
}

TEST(OutputSafety, CalibrateRefusesAnImageAsItsOutput) {
  TestDir dir;
  std::vector<std::string> images;
  for (int k = 0; k < 6; ++k) {
    const std::string name = "view_0" + std::to_string(k) + ".png";
    fs::copy_file(kSource + "/calibration/" + name, dir.File(name));
    images.push_back(dir.File(name));
  }
  const std::string before = ReadBytes(images[0]);
  std::string args = "calibrate --board 9x6 --square 25";
  for (const auto& i : images) args += " " + i;
  // The case: -o one of the images.
  ExpectRefused(RunCli(args + " -o " + images[0]), {"-o", images[0], ".yaml"});
  EXPECT_EQ(ReadBytes(images[0]), before);
  // A YAML name that is the same file as an input (a hard link).
  fs::create_hard_link(images[1], dir.File("cam.yaml"));
  ExpectRefused(RunCli(args + " -o " + dir.File("cam.yaml")),
                {"-o", "cam.yaml", "one of the inputs", images[1]});
}

TEST(OutputSafety, WrongOutputExtensionsAreRefusedBeforeAnyWork) {
  TestDir dir;
  const std::string frames =
      "--reference " + kFrames + "frame_0000.png --deformed " + kFrames + "frame_0001.png";
  ExpectRefused(RunCli("correlate " + frames + " --subset 21 --step 40 -o " + dir.File("d.png")),
                {"-o/--output", "d.png", ".csv, .h5 or .hdf5"});
  ExpectRefused(RunCli("model --mass 10 --height 0.7 --width 0.15 -o " + dir.File("series.json")),
                {"-o", "series.json", ".csv, .h5 or .hdf5"});
  ExpectRefused(RunCli("analyze --sensor " + kSensorCsv + " --from-release --output " +
                       dir.File("sensor.csv")),
                {"--output", "sensor.csv", ".h5 or .hdf5"});
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

TEST(OutputSafety, AnalyzeRefusesItsInputAsItsOutput) {
  // A DAQ record stored under an .h5 name: --output the same file would replace it.
  TestDir dir;
  fs::copy_file(kSensorCsv, dir.File("record.h5"));
  const std::string before = ReadBytes(dir.File("record.h5"));
  ExpectRefused(RunCli("analyze --sensor " + dir.File("record.h5") + " --from-release --output " +
                       dir.File("record.h5")),
                {"--output", "record.h5", "one of the inputs"});
  EXPECT_EQ(ReadBytes(dir.File("record.h5")), before);
}

TEST(OutputSafety, AnalyzeOutputIntoResultsKeepsDicAndFrames) {
  TestDir dir;
  const std::string results = dir.File("results.h5");
  WriteResultsLike(results);
  const CliResult r = RunCli("-q analyze --sensor " + kSensorCsv + " --from-release --output " +
                             results + " --format json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const H5Reader in(results);
  EXPECT_EQ(in.ReadDouble("dic/u_px"), (std::vector<double>{1.5, 2.5, 3.5}));
  EXPECT_EQ(in.ReadInt("frames/images"), std::vector<std::int32_t>(24, 7));
  EXPECT_EQ(in.ReadStringAttribute("/", "scene_name"), "kept");
  // /sensor is the command's own: replaced as a whole.
  EXPECT_FALSE(in.Exists("sensor/old_only"));
  EXPECT_GT(in.Dimensions("sensor/t_s")[0], 1000u);
  EXPECT_TRUE(in.Exists("sensor/velocity_m_s"));
}

TEST(OutputSafety, ModelAndCorrelateIntoAnExistingFileReplaceOnlyTheirGroups) {
  TestDir dir;
  const std::string results = dir.File("results.h5");
  WriteResultsLike(results);
  const CliResult model =
      RunCli("-q model --mass 10 --height 0.7 --width 0.15 -o " + results + " --format json");
  ASSERT_EQ(model.exit_code, 0) << model.output;
  const CliResult correlate =
      RunCli("-q correlate --reference " + kFrames + "frame_0000.png --deformed " + kFrames +
             "frame_0001.png --subset 21 --step 60 -o " + results);
  ASSERT_EQ(correlate.exit_code, 0) << correlate.output;
  const H5Reader in(results);
  EXPECT_TRUE(in.Exists("model/t_s"));  // The run's /model layout since 2026-11-28.
  EXPECT_EQ(in.ReadDouble("sensor/t_s"), (std::vector<double>{-1, -2}));
  EXPECT_EQ(in.ReadInt("frames/images"), std::vector<std::int32_t>(24, 7));
  // /dic is correlate's: its new grid, not the old three values.
  EXPECT_TRUE(in.Exists("dic/x_px"));
  EXPECT_EQ(in.Dimensions("dic/u_px")[0], 2u);  // the reference row and one deformed frame
  EXPECT_GT(in.Dimensions("dic/u_px")[1], 3u);
}

TEST(OutputSafety, ExistingFileThatIsNotHdf5IsKept) {
  TestDir dir;
  const std::string notes = dir.Write("notes.h5", "my notes, not HDF5\n");
  ExpectRefused(RunCli("model --mass 10 --height 0.7 --width 0.15 -o " + notes),
                {"-o", "notes.h5", "not HDF5", "kept"});
  ExpectRefused(RunCli("analyze --sensor " + kSensorCsv + " --from-release --output " + notes),
                {"--output", "notes.h5", "not HDF5"});
  EXPECT_EQ(ReadBytes(notes), "my notes, not HDF5\n");
}

TEST(OutputSafety, RunRefusesAnOutputFolderHoldingItsInputs) {
  TestDir dir;
  const CliResult synth = RunCli("-q synth --preset tiny --no-calibrate -o " + dir.File("scene"));
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  const std::string scene_before = ReadBytes(dir.File("scene/scene.yaml"));
  // The scene's own folder (scene, frames, sensor CSV, truth) and the frames folder.
  ExpectRefused(RunCli("run " + dir.File("scene/scene.yaml") + " -o " + dir.File("scene")),
                {"-o", "holds the input"});
  ExpectRefused(RunCli("run " + dir.File("scene/scene.yaml") + " -o " + dir.File("scene/frames")),
                {"-o", "holds the input", "frames"});
  EXPECT_FALSE(fs::exists(dir.File("scene/results.h5")));
  EXPECT_FALSE(fs::exists(dir.File("scene/summary.json")));
  EXPECT_FALSE(fs::exists(dir.File("scene/frames/momentum.png")));
  EXPECT_EQ(ReadBytes(dir.File("scene/scene.yaml")), scene_before);
}

// A campaign replaces its folder whole: a scene read from inside it (here a synth folder nested
// in it, which the folder's own rules accept) would be deleted by the swap.
TEST(OutputSafety, CampaignRefusesAFolderHoldingASceneItRuns) {
  TestDir dir;
  const CliResult synth = RunCli("-q synth --preset tiny --no-calibrate -o " + dir.File("camp/s1"));
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  const std::string scene_before = ReadBytes(dir.File("camp/s1/scene.yaml"));
  ExpectRefused(RunCli("campaign " + dir.File("camp/s1/scene.yaml") + " -o " + dir.File("camp")),
                {"-o", "holds the input", dir.File("camp")});
  EXPECT_EQ(ReadBytes(dir.File("camp/s1/scene.yaml")), scene_before);
  EXPECT_TRUE(fs::exists(dir.File("camp/s1/frames")));
  EXPECT_FALSE(fs::exists(dir.File("camp/campaign.csv")));
}

TEST(OutputSafety, SynthRefusesToReplaceItsSpec) {
  TestDir dir;
  const std::string spec = dir.Write("scene.yaml", "preset: tiny\n");
  ExpectRefused(RunCli("synth " + spec + " --no-calibrate -o " + dir.path().string()),
                {"-o", "scene.yaml", "one of the inputs"});
  EXPECT_EQ(ReadBytes(spec), "preset: tiny\n");
  EXPECT_FALSE(fs::exists(dir.File("frames")));
}

TEST(OutputSafety, ValidateDemRefusesAnInputAsItsCsv) {
  TestDir dir;
  const std::string truth = dir.File("truth.h5"), results = dir.File("results.h5");
  WriteResultsLike(truth);
  WriteResultsLike(results);
  const std::string truth_before = ReadBytes(truth);
  ExpectRefused(RunCli("validate-dem " + truth + " " + results + " --csv " + truth),
                {"--csv", truth, ".csv"});
  EXPECT_EQ(ReadBytes(truth), truth_before);
}

}  // namespace
}  // namespace impactdic
