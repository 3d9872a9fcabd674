// Every dataset of a run's results.h5 is read by the reader of its group's owner
// (io/results_layout.h lists them), and `model -o` writes the run's /model layout.
#include <gtest/gtest.h>

#include <exception>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "../reliability/fault_util.h"
#include "impactdic/core/error.h"
#include "impactdic/io/dic_results.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/kinematics/kinematics_results.h"
#include "impactdic/model/model_results.h"
#include "impactdic/momentum/momentum_results.h"
#include "impactdic/render/render_results.h"
#include "impactdic/sensor/frame_timeline.h"
#include "impactdic/sensor/sensor_results.h"
#include "impactdic/sensor/wave_results.h"
#include "impactdic/strain/strain_results.h"

namespace impactdic {
namespace {
namespace L = results_layout;

// Every dataset below `group` ("/dic/u_px", ...), recursively.
std::set<std::string> Datasets(const H5Reader& in, const std::string& group) {
  std::set<std::string> out;
  for (const std::string& name : in.List(group)) {
    const std::string path = (group == "/" ? "" : group) + "/" + name;
    std::vector<std::string> members;
    try {
      members = in.List(path);
    } catch (const std::exception&) {  // Not a group: a dataset.
      out.insert(path);
      continue;
    }
    for (const std::string& d : Datasets(in, path)) out.insert(d);
  }
  return out;
}

// One run of the sample scene (figures, animation and results.xdmf off: the /xdmf views are read
// by ParaView, tests/reliability/xdmf_reader_test.cc), shared by the tests.
class ResultsOwners : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TestDir("ResultsOwners");
    const std::string scene = SampleScene(*dir_, {{"xdmf: true", "xdmf: false"}});
    const CliResult run = RunCli("-q run " + scene + " -o " + dir_->File("out"));
    ASSERT_EQ(run.exit_code, 0) << run.output;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string Results() { return dir_->File("out/results.h5"); }
  static TestDir* dir_;
};
TestDir* ResultsOwners::dir_ = nullptr;

TEST_F(ResultsOwners, EveryDatasetOfARunIsReadByItsGroupsOwner) {
  const std::string file = Results();
  const H5Reader in(file);
  const DicResultsTable dic = ReadDicResults(in, file);
  const SensorResultsGroup sensor = ReadSensorResults(in, file);
  const KinematicsResultsGroup kin = ReadKinematicsResults(in, file);
  const MomentumResultsGroup momentum = ReadMomentumResults(in, file);
  const ModelResultsGroup model = ReadModelResults(in, file);
  const StrainResult strain = ReadStrainResults(in, file);
  const FrameTimeline timeline = ReadFrameTimeline(in, file);
  const WaveResult wave = ReadWaveResults(in, file);  // The sample has base channels.
  const std::vector<BaseForceRecord> base_force = ReadBaseForceRecords(in, file, wave);
  // /time/t_ms and /frames (the run's own outputs): the figures' reader.
  const VelocityFieldSequence field = ReadVelocityFieldSequence(in);
  // Read by validate-dem by its name (dem_validation.cc): the frames' index in the input sequence.
  const std::set<std::string> read_by_name = {L::kTimeFrameIndex};

  const std::vector<std::string> read = in.DatasetsRead();
  const std::set<std::string> read_set(read.begin(), read.end());
  for (const std::string& d : Datasets(in, "/"))
    EXPECT_TRUE(read_set.count(d) || read_by_name.count(d)) << d << " has no reader";

  // What was read is the run's: one row per analysed frame in every per-frame group.
  ASSERT_GT(dic.rows, 2u);
  EXPECT_EQ(kin.kinematics.frames, dic.rows);
  EXPECT_EQ(kin.kinematics.subsets, dic.subsets);
  EXPECT_EQ(kin.frame_time_daq_s.size(), dic.rows);
  EXPECT_GT(kin.mm_per_px, 0);
  EXPECT_EQ(kin.vy_positive, "down");
  EXPECT_EQ(momentum.momentum.p_gran_kg_m_s.size(), dic.rows);
  EXPECT_EQ(momentum.t_after_impact_s.size(), dic.rows);
  EXPECT_EQ(momentum.t_e_found, "yes");
  EXPECT_EQ(momentum.momentum.summary.p_max_kg_m_s,
            in.ReadNumberAttribute("/summary", "p_max_kg_m_s"));
  EXPECT_TRUE(momentum.momentum.summary.sigmoid_fitted);
  EXPECT_EQ(momentum.momentum.summary.grid.subset_ids.size(), 12u);  // The sample's 6 x 2.
  EXPECT_EQ(strain.field.frames, dic.rows);
  EXPECT_EQ(sensor.sensor.time_s.size(), sensor.decel_g.size());
  EXPECT_DOUBLE_EQ(sensor.sensor.summary.impact_velocity_m_s,
                   in.ReadNumberAttribute("/summary", "impact_velocity_m_s"));
  EXPECT_FALSE(sensor.sign_convention.empty());
  EXPECT_EQ(model.series.size(), model.decel_g.size());
  EXPECT_EQ(model.summary.crater_depth_m,
            in.ReadNumberAttribute("/summary", "crater_depth_model_m"));
  EXPECT_FALSE(field.frames.empty());
  ASSERT_EQ(timeline.size(), dic.rows);
  EXPECT_EQ(timeline.daq_time_s, kin.frame_time_daq_s);
  EXPECT_EQ(timeline.index.front(), dic.first_frame);
  EXPECT_DOUBLE_EQ(timeline.impact_time_s, sensor.sensor.summary.impact_time_s);
}

TEST_F(ResultsOwners, ModelCommandWritesTheRunsModelLayout) {
  const std::string model_h5 = dir_->File("model.h5");
  const CliResult model = RunCli("-q model --mass 10 --height 0.7 --width 0.15 -o " + model_h5);
  ASSERT_EQ(model.exit_code, 0) << model.output;
  const H5Reader run(Results()), alone(model_h5);
  EXPECT_EQ(Datasets(alone, L::kModelGroup), Datasets(run, L::kModelGroup));
  const ModelResultsGroup m = ReadModelResults(alone, model_h5);
  EXPECT_GT(m.series.size(), 10u);
  EXPECT_EQ(m.decel_g.size(), m.series.size());
  EXPECT_EQ(m.parameters.pounder_mass_kg, 10);
  for (const char* name : {"units", "description"})
    EXPECT_EQ(alone.ReadStringAttribute(L::kModelDecel, name),
              run.ReadStringAttribute(L::kModelDecel, name));
}

// A file without the group: the owner's reader names the group and the file.
TEST_F(ResultsOwners, AReaderNamesTheMissingGroupAndTheFile) {
  const std::string model_h5 = dir_->File("model_only.h5");
  ASSERT_EQ(RunCli("-q model --mass 10 --height 0.7 --width 0.15 -o " + model_h5).exit_code, 0);
  const H5Reader in(model_h5);
  for (const auto& read : std::vector<std::function<void()>>{
           [&] { ReadSensorResults(in, model_h5); }, [&] { ReadKinematicsResults(in, model_h5); },
           [&] { ReadMomentumResults(in, model_h5); }}) {
    try {
      read();
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(model_h5), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("missing"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace impactdic
