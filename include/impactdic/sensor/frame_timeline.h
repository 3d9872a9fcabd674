// The frame timeline: for every analysed frame, its place in the frame source, its number on the
// source's own count and its time on the camera clock and on the DAQ clock, with where each came
// from. It is THE place a frame time is computed: the frames stage builds it from the frame
// source, `analyze` from the rows of a results file, and every consumer (kinematics, momentum,
// strain rates, the results file, render) reads it.
//
//   FrameTimeline all = MakeFrameTimeline(/*first_index=*/0, numbers, clock, &sensor);
//   FrameTimeline analysed = all.Rows(first, last);
//   double t_ms = analysed.MsSinceStart()[k];   // since the impact on the DAQ clock
#ifndef IMPACTDIC_SENSOR_FRAME_TIMELINE_H_
#define IMPACTDIC_SENSOR_FRAME_TIMELINE_H_

#include <cstddef>
#include <string>
#include <vector>

#include "impactdic/io/hdf5_store.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {

struct FrameTimeline {
  // Position of each frame in its source (0-based, consecutive: rows are frames first..last).
  std::vector<int> index;
  // The source's own number of each frame: the camera's count for a camera file (negative before
  // the trigger, save step included), the number in a numbered file name, else the position.
  std::vector<long long> number;
  // Time on the camera clock [s]: the camera's time stamps (relative to its trigger) where the
  // source has them, else index / fps; NaN when neither is known (fps 0).
  std::vector<double> camera_time_s;
  // Time on the DAQ clock [s] (sensor FrameTimes): empty without a sensor record.
  std::vector<double> daq_time_s;
  // The rate of these frames [1/s] (the kinematics' dt = 1 / fps): a camera file's rate of the
  // saved frames, else inputs.fps; 0 when unknown.
  double fps = 0;
  // Whether camera_time_s are the camera's own time stamps (a camera file), not index / fps.
  bool camera_stamps = false;
  // Where the times come from, in messages and in results.h5 (/time attributes).
  std::string camera_clock;  // "time stamps of rec.cine", "index / inputs.fps"
  std::string daq_clock;     // "exposure edges of daq.csv", ...; "" without a sensor record
  // Exposure rising edges found in the sensor record (0 without an exposure channel).
  std::size_t exposure_edges = 0;
  // The DAQ time of the impact [s] when the timeline has DAQ times (NaN otherwise).
  double impact_time_s = kNaN;

  std::size_t size() const { return index.size(); }
  bool OnDaqClock() const { return !daq_time_s.empty(); }
  // Rows first..last (positions in this timeline, inclusive).
  FrameTimeline Rows(std::size_t first, std::size_t last) const;
  // The row of the frame at source position `source_index`; size() when none.
  std::size_t RowOfIndex(int source_index) const;
  // Each frame's time [ms]: since the impact on the DAQ clock when there is one, else since
  // the first frame on the camera clock. The /time/ms of results.h5.
  std::vector<double> MsSinceStart() const;
};

// The source frames first_index .. first_index + numbers.size() - 1, numbered `numbers` (the
// source's FrameNumber of each), timed on the camera clock by `clock` (its time stamps of source
// frames 0.., else index / clock.fps) and, with a sensor record, on the DAQ clock by FrameTimes
// over source frames 0..last (the exposure edges, the camera's time stamps or the offset and
// fps). Errors of FrameTimes (too few edges, frames outside the record, a rate that disagrees
// with the edges) are thrown as they are.
FrameTimeline MakeFrameTimeline(int first_index, std::vector<long long> numbers,
                                const CameraClock& clock, const SensorResult* sensor);

// The same for count frames numbered by their position.
FrameTimeline MakeFrameTimeline(int first_index, int count, const CameraClock& clock,
                                const SensorResult* sensor);

// /time of a results file (io/results_layout.h, kTimeGroup): the timeline's datasets (t_ms =
// MsSinceStart, frame_index, frame_number, camera_time_s, daq_time_s with a DAQ clock) and its
// attributes (camera_clock, daq_clock, fps, impact_time_s); replaces an existing /time.
void WriteFrameTimeline(H5Writer& out, const FrameTimeline& timeline);
// /time as written by WriteFrameTimeline (files without frame_number, camera_time_s: numbers =
// indices, camera times NaN). Error naming the file when /time or its frame_index is missing or
// the lengths disagree.
FrameTimeline ReadFrameTimeline(const H5Reader& in, const std::string& file);

}  // namespace impactdic

#endif  // IMPACTDIC_SENSOR_FRAME_TIMELINE_H_
