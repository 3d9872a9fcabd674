// Camera timing on the DAQ clock (sensor/sensor.h "camera timing"): the exposure channel's
// rising edges, the frame times they (or the camera's clock) give, and the first frame of an
// impact. The accelerometer processing is sensor.cc.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {

std::vector<double> ExposureRisingEdges(const std::vector<double>& time_s,
                                        const std::vector<double>& exposure) {
  std::vector<double> edges;
  if (exposure.size() < 2) return edges;
  const auto [lo_it, hi_it] = std::minmax_element(exposure.begin(), exposure.end());
  const double lo = *lo_it, hi = *hi_it;
  if (!(hi - lo > 0)) return edges;
  const double threshold = 0.5 * (lo + hi);
  for (std::size_t i = 1; i < exposure.size(); ++i) {
    if (exposure[i - 1] < threshold && exposure[i] >= threshold) {
      const double f = (threshold - exposure[i - 1]) / (exposure[i] - exposure[i - 1]);
      edges.push_back(time_s[i - 1] + f * (time_s[i] - time_s[i - 1]));
    }
  }
  return edges;
}

namespace {

// The frame rate the exposure edges of the frames give, (n - 1) / (t_last - t_first), against the
// given fps (not checked when fps is 0 or NaN, or with fewer than 2 frames): Error naming
// inputs.fps with both rates beyond kFrameRateTolerance + one DAQ sample over the edges' span.
void CheckFrameRateAgainstExposure(const std::vector<double>& edges_s, double fps,
                                   const std::string& fps_name, double daq_rate_hz,
                                   const std::string& path) {
  if (!(fps > 0) || !std::isfinite(fps) || edges_s.size() < 2) return;
  const double span = edges_s.back() - edges_s.front();
  const double rate = static_cast<double>(edges_s.size() - 1) / span;
  const double tolerance = kFrameRateTolerance + (daq_rate_hz > 0 ? 1 / (daq_rate_hz * span) : 0);
  if (std::abs(fps / rate - 1) <= tolerance) return;
  throw Error(ErrorKind::kInvalidValue, fps_name, fmt::format("{:.6g} 1/s", fps),
              fmt::format("the frame rate of the exposure channel{}, {:.6g} 1/s ({} rising "
                          "edges from {:.6g} s to {:.6g} s), within {:.2g} %: velocities scale "
                          "with the frame rate",
                          path.empty() ? "" : " in " + path, rate, edges_s.size(), edges_s.front(),
                          edges_s.back(), 100 * tolerance));
}

}  // namespace

std::vector<double> FrameTimes(const SensorResult& result, int n_frames, const CameraClock& clock,
                               std::size_t* edges_found) {
  CheckValue(n_frames >= 1, "n_frames", fmt::format("{}", n_frames), ">= 1");
  std::vector<double> times;
  if (edges_found) *edges_found = 0;
  if (!result.exposure.empty()) {
    times = ExposureRisingEdges(result.time_s, result.exposure);
    if (edges_found) *edges_found = times.size();
    if (times.size() < static_cast<std::size_t>(n_frames)) {
      throw Error(ErrorKind::kInvalidValue, "exposure channel",
                  fmt::format("{} rising edges", times.size()),
                  fmt::format("one rising edge per frame ({} frames): the sensor record does not "
                              "cover the frames",
                              n_frames));
    }
    times.resize(static_cast<std::size_t>(n_frames));
    CheckFrameRateAgainstExposure(times, clock.fps, clock.fps_name, result.summary.sample_rate_hz,
                                  result.path);
  } else if (!clock.time_s.empty()) {  // The camera's own time stamps.
    CheckValue(clock.time_s.size() >= static_cast<std::size_t>(n_frames), "camera time stamps",
               std::to_string(clock.time_s.size()), fmt::format("one per frame ({})", n_frames));
    CheckValue(std::isfinite(clock.offset_s), "frame_time_offset_s",
               fmt::format("{}", clock.offset_s), "a finite time");
    for (int k = 0; k < n_frames; ++k) {
      times.push_back(clock.offset_s + clock.time_s[static_cast<std::size_t>(k)] -
                      clock.time_s.front());
    }
  } else {
    CheckValue(std::isfinite(clock.fps) && clock.fps > 0, "fps", fmt::format("{}", clock.fps),
               "> 0");
    CheckValue(std::isfinite(clock.offset_s), "frame_time_offset_s",
               fmt::format("{}", clock.offset_s), "a finite time");
    for (int k = 0; k < n_frames; ++k) times.push_back(clock.offset_s + k / clock.fps);
  }
  const double t0 = result.time_s.front(), t1 = result.time_s.back();
  if (times.front() < t0 || times.back() > t1) {
    throw Error(ErrorKind::kInvalidValue, "frame times",
                fmt::format("frames from {:.6g} s to {:.6g} s", times.front(), times.back()),
                fmt::format("inside the sensor record [{:.6g} s, {:.6g} s]: the sensor record "
                            "does not cover the frames",
                            t0, t1));
  }
  return times;
}

void RequireExposureChannel(const SensorResult& result, const std::string& column) {
  if (column.empty() || !result.exposure.empty()) return;
  std::string names;
  for (const auto& n : result.column_names) names += (names.empty() ? "" : ", ") + n;
  throw Error(
      ErrorKind::kFileFormat, "column '" + column + "' (sensor.exposure_column)",
      "a file without it; its columns are " + (names.empty() ? std::string("unknown") : names),
      "the camera's exposure channel, whose rising edges time the frames; or "
      "sensor.exposure_column: \"\" to time them by sensor.frame_time_offset_s + k / "
      "inputs.fps")
      .WithFile(result.path);
}

int ReferenceFrameForImpact(const std::vector<double>& daq_time_s, double impact_time_s) {
  int reference = 0;
  for (std::size_t k = 0; k < daq_time_s.size(); ++k)
    if (daq_time_s[k] <= impact_time_s) reference = static_cast<int>(k);
  return reference;
}

}  // namespace impactdic
