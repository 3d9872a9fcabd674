// The frame timeline (sensor/frame_timeline.h): the one place where a frame's number and its
// times on the camera and DAQ clocks are worked out.
#include "impactdic/sensor/frame_timeline.h"

#include <fmt/format.h>

#include <cmath>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_io.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {
namespace {

template <typename T>
std::vector<T> Slice(const std::vector<T>& v, std::size_t first, std::size_t last) {
  if (v.empty()) return {};
  return std::vector<T>(v.begin() + static_cast<std::ptrdiff_t>(first),
                        v.begin() + static_cast<std::ptrdiff_t>(last) + 1);
}

}  // namespace

FrameTimeline FrameTimeline::Rows(std::size_t first, std::size_t last) const {
  CheckValue(first <= last && last < size(), "frame timeline rows",
             fmt::format("{}..{}", first, last), fmt::format("within 0..{}", size() - 1));
  FrameTimeline t = *this;
  t.index = Slice(index, first, last);
  t.number = Slice(number, first, last);
  t.camera_time_s = Slice(camera_time_s, first, last);
  t.daq_time_s = Slice(daq_time_s, first, last);
  return t;
}

std::size_t FrameTimeline::RowOfIndex(int source_index) const {
  if (index.empty() || source_index < index.front() || source_index > index.back()) return size();
  return static_cast<std::size_t>(source_index - index.front());
}

std::vector<double> FrameTimeline::MsSinceStart() const {
  std::vector<double> t_ms(size());
  for (std::size_t r = 0; r < size(); ++r) {
    t_ms[r] = OnDaqClock() ? 1e3 * (daq_time_s[r] - impact_time_s)
                           : 1e3 * (camera_time_s[r] - camera_time_s.front());
  }
  return t_ms;
}

FrameTimeline MakeFrameTimeline(int first_index, std::vector<long long> numbers,
                                const CameraClock& clock, const SensorResult* sensor) {
  CheckValue(first_index >= 0, "first frame index", std::to_string(first_index), ">= 0");
  CheckValue(!numbers.empty(), "frames", "none", "at least one frame");
  FrameTimeline t;
  const std::size_t n = numbers.size();
  t.number = std::move(numbers);
  t.fps = std::isfinite(clock.fps) && clock.fps > 0 ? clock.fps : 0;
  const bool stamped = !clock.time_s.empty();
  t.camera_stamps = stamped;
  t.camera_clock = stamped     ? "the camera's time stamps (" + clock.fps_name + ")"
                   : t.fps > 0 ? "k / " + clock.fps_name
                               : std::string("unknown (no frame rate)");
  const int last_index = first_index + static_cast<int>(n) - 1;
  if (stamped) {
    CheckValue(clock.time_s.size() > static_cast<std::size_t>(last_index), "camera time stamps",
               std::to_string(clock.time_s.size()),
               fmt::format("one per frame (frames up to index {})", last_index));
  }
  for (std::size_t r = 0; r < n; ++r) {
    const int k = first_index + static_cast<int>(r);
    t.index.push_back(k);
    t.camera_time_s.push_back(stamped     ? clock.time_s[static_cast<std::size_t>(k)]
                              : t.fps > 0 ? k / t.fps
                                          : kNaN);
  }
  if (sensor != nullptr) {
    const std::vector<double> all = FrameTimes(*sensor, last_index + 1, clock, &t.exposure_edges);
    t.daq_time_s.assign(all.begin() + first_index, all.end());
    t.impact_time_s = sensor->summary.impact_time_s;
    t.daq_clock = !sensor->exposure.empty() ? "the exposure edges of " + sensor->path
                  : stamped ? "sensor.frame_time_offset_s + the camera's time stamps"
                            : "sensor.frame_time_offset_s + k / " + clock.fps_name;
  }
  return t;
}

FrameTimeline MakeFrameTimeline(int first_index, int count, const CameraClock& clock,
                                const SensorResult* sensor) {
  CheckValue(count >= 1, "frames", std::to_string(count), "at least one frame");
  std::vector<long long> numbers(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k) numbers[static_cast<std::size_t>(k)] = first_index + k;
  return MakeFrameTimeline(first_index, std::move(numbers), clock, sensor);
}

void WriteFrameTimeline(H5Writer& out, const FrameTimeline& t) {
  namespace L = results_layout;
  out.Remove(L::kTimeGroup);
  const std::vector<double> index(t.index.begin(), t.index.end());
  const std::vector<double> number(t.number.begin(), t.number.end());
  out.Write(L::kTimeMs, t.MsSinceStart(), "ms",
            t.OnDaqClock() ? "time of each analysed frame since the impact (DAQ clock)"
                           : "time of each analysed frame since the first (camera clock)");
  out.Write(L::kTimeFrameIndex, index, "1", "index of the analysed frame in the input sequence");
  out.Write(L::kTimeFrameNumber, number, "1",
            "number of the analysed frame on its source's own count (camera, file name)");
  out.Write(L::kTimeCameraS, t.camera_time_s, "s",
            t.camera_stamps ? "the camera's time stamp of the analysed frame (camera clock)"
                            : "time of the analysed frame on the camera clock: index / fps");
  if (t.OnDaqClock())
    out.Write(L::kTimeDaqS, t.daq_time_s, "s", "time of the analysed frame on the DAQ clock");
  out.SetAttribute(L::kTimeGroup, L::kTimeCameraClockAttr, t.camera_clock);
  out.SetAttribute(L::kTimeGroup, L::kTimeDaqClockAttr,
                   t.OnDaqClock() ? t.daq_clock : std::string("none (no sensor record)"));
  out.SetAttribute(L::kTimeGroup, L::kTimeFpsAttr, t.fps);
  out.SetAttribute(L::kTimeGroup, L::kTimeImpactAttr, t.impact_time_s);
}

FrameTimeline ReadFrameTimeline(const H5Reader& in, const std::string& file) {
  namespace L = results_layout;
  RequireGroup(in, L::kTimeGroup, file, "the analysed frames' timeline (impactdic run or analyze)");
  FrameTimeline t;
  std::size_t n = kAnyLength;
  for (double i : ReadSeries(in, L::kTimeFrameIndex, file, &n))
    t.index.push_back(static_cast<int>(std::lround(i)));
  ReadSeries(in, L::kTimeMs, file, &n);  // Derived (MsSinceStart); its length checked.
  if (in.Exists(L::kTimeFrameNumber)) {
    for (double v : ReadSeries(in, L::kTimeFrameNumber, file, &n))
      t.number.push_back(std::llround(v));
  } else {
    t.number.assign(t.index.begin(), t.index.end());
  }
  t.camera_time_s = in.Exists(L::kTimeCameraS) ? ReadSeries(in, L::kTimeCameraS, file, &n)
                                               : std::vector<double>(n, kNaN);
  if (in.Exists(L::kTimeDaqS)) t.daq_time_s = ReadSeries(in, L::kTimeDaqS, file, &n);
  t.camera_clock = ReadStringAttributeOr(in, L::kTimeGroup, L::kTimeCameraClockAttr, "");
  t.camera_stamps = t.camera_clock.rfind("the camera's time stamps", 0) == 0;
  t.daq_clock =
      t.OnDaqClock() ? ReadStringAttributeOr(in, L::kTimeGroup, L::kTimeDaqClockAttr, "") : "";
  t.fps = ReadNumberAttributeOr(in, L::kTimeGroup, L::kTimeFpsAttr, 0);
  t.impact_time_s = ReadNumberAttributeOr(in, L::kTimeGroup, L::kTimeImpactAttr, kNaN);
  return t;
}

}  // namespace impactdic
