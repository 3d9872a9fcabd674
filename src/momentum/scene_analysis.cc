#include "impactdic/momentum/scene_analysis.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/io/dic_results.h"
#include "impactdic/io/hdf5_store.h"

namespace impactdic {

namespace {

// The series' columns from the table's, copied (a const table) or moved.
template <typename Table>
void TakeColumns(Table&& t, CorrelationSeries* s) {
  s->frames = t.rows;
  s->subsets = t.subsets;
  s->x_px = std::forward<Table>(t).x_px;
  s->y_px = std::forward<Table>(t).y_px;
  s->u_px = std::forward<Table>(t).u_px;
  s->v_px = std::forward<Table>(t).v_px;
  s->sigma_u_px = std::forward<Table>(t).sigma_u_px;
  s->sigma_v_px = std::forward<Table>(t).sigma_v_px;
}

// valid = status converged (empty without a status: valid where finite).
void SetValid(const DicResultsTable& t, CorrelationSeries* s) {
  if (t.status.empty()) return;
  s->valid.resize(t.status.size());
  for (std::size_t k = 0; k < t.status.size(); ++k) s->valid[k] = t.IsValid(k) ? 1 : 0;
}

}  // namespace

CorrelationSeries CorrelationSeriesFromTable(const DicResultsTable& t) {
  CorrelationSeries s;
  SetValid(t, &s);
  TakeColumns(t, &s);
  s.Check();
  return s;
}

BorrowedCorrelationSeries::BorrowedCorrelationSeries(DicResultsTable* table) : table_(table) {
  SetValid(*table_, &series_);
  TakeColumns(std::move(*table_), &series_);
  try {
    series_.Check();
  } catch (...) {
    GiveBack();
    throw;
  }
}

BorrowedCorrelationSeries::~BorrowedCorrelationSeries() { GiveBack(); }

void BorrowedCorrelationSeries::GiveBack() {
  table_->x_px = std::move(series_.x_px);
  table_->y_px = std::move(series_.y_px);
  table_->u_px = std::move(series_.u_px);
  table_->v_px = std::move(series_.v_px);
  table_->sigma_u_px = std::move(series_.sigma_u_px);
  table_->sigma_v_px = std::move(series_.sigma_v_px);
}

CorrelationSeries ReadCorrelationSeries(const std::string& h5_path, long* first_frame) {
  if (!std::filesystem::exists(h5_path)) {
    throw Error(ErrorKind::kFileNotFound, "", "",
                "the correlation results (run `impactdic correlate` or `impactdic run` first)")
        .WithFile(h5_path);
  }
  const DicResultsTable table = ReadDicResults(H5Reader(h5_path), h5_path);
  if (first_frame) *first_frame = table.first_frame;
  return CorrelationSeriesFromTable(table);
}

double MeasuredPeakDeceleration(const SensorResult& sensor, double peak_stage_s) {
  const double t_i = sensor.summary.impact_time_s;
  const std::size_t k =
      PeakDecelerationSample(sensor.time_s, sensor.accel_g, t_i, /*from_s=*/0.0, peak_stage_s);
  return k < sensor.accel_g.size() ? sensor.accel_g[k] - 1 : std::nan("");
}

double MeasuredPlateauDeceleration(const SensorResult& sensor, double t1_after_impact_s, double g) {
  const SensorSummary& s = sensor.summary;
  if (!std::isfinite(s.impact_time_s) || !std::isfinite(s.stop_time_s)) return std::nan("");
  const double t1 = s.impact_time_s + t1_after_impact_s;
  if (!(s.stop_time_s > t1)) return std::nan("");
  const std::vector<double> v =
      SampleSeries(sensor.time_s, sensor.velocity_m_s, {t1, s.stop_time_s}, "sensor velocity");
  return (v[0] - v[1]) / (s.stop_time_s - t1) / g;
}

}  // namespace impactdic
