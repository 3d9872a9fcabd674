// The momentum analysis' readers and measured figures used by `impactdic analyze SCENE.yaml`
// (pipeline/scene_analysis.h) and the pipeline's stages.
//
// The correlation results are read with io ReadDicResults (any layout version,
// io/results_layout.h): row 0 is the first reference, a sample is valid when its status is
// converged (or, without /dic/status, when its displacement is finite); the /dic attribute
// first_frame is the index of row 0 in the camera sequence (default: the scene's dic.first_frame).
//
//   long first = -1;
//   CorrelationSeries dic = ReadCorrelationSeries("results/results.h5", &first);
#ifndef IMPACTDIC_MOMENTUM_SCENE_ANALYSIS_H_
#define IMPACTDIC_MOMENTUM_SCENE_ANALYSIS_H_

#include <string>

#include "impactdic/io/dic_results.h"
#include "impactdic/kinematics/kinematics.h"
#include "impactdic/momentum/momentum.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {

// The correlation arrays of a results table (io/dic_results.h): valid = status converged.
CorrelationSeries CorrelationSeriesFromTable(const DicResultsTable& table);

// The same without a copy of the table's rows: the series borrows the table's columns (x, y, u, v
// and the sigmas are moved into it; only `valid` is new) and gives them back, unchanged, when it
// is destroyed (ExcludeUncertainSamples and ComputeKinematics change `valid` only). The table
// must outlive it and is not used meanwhile. For the run's kinematics stage, so that the analysis
// of a long recording holds the correlation results once.
class BorrowedCorrelationSeries {
 public:
  explicit BorrowedCorrelationSeries(DicResultsTable* table);
  ~BorrowedCorrelationSeries();
  BorrowedCorrelationSeries(const BorrowedCorrelationSeries&) = delete;
  BorrowedCorrelationSeries& operator=(const BorrowedCorrelationSeries&) = delete;
  CorrelationSeries& series() { return series_; }

 private:
  void GiveBack();
  DicResultsTable* table_;
  CorrelationSeries series_;
};

// Reads the correlation results (io ReadDicResults). *first_frame (optional) receives the /dic
// attribute first_frame, or -1 when absent.
CorrelationSeries ReadCorrelationSeries(const std::string& h5_path, long* first_frame = nullptr);

// Measured peak deceleration [g] of the PEAK STAGE: the largest filtered deceleration between the
// impact and `peak_stage_s` after it (sensor PeakDecelerationSample; the pipeline takes t_e, or
// the model's T + 4/b when t_e was not measured). The record's global maximum can be the stop,
// where -dv/dt grows like v^-n (docs/model.md). NaN without an impact or a sample in the window.
double MeasuredPeakDeceleration(const SensorResult& sensor, double peak_stage_s);

// Mean deceleration [g] of the sensor record over [impact + t1, stop]: the measured counterpart
// of the model's plateau deceleration v(t1) / (t_end - t1) / g. NaN without impact or stop, or
// when the stop is not after t1.
double MeasuredPlateauDeceleration(const SensorResult& sensor, double t1_after_impact_s, double g);

}  // namespace impactdic

#endif  // IMPACTDIC_MOMENTUM_SCENE_ANALYSIS_H_
