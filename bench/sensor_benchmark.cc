// Speed of the accelerometer processing: the zero-phase filter and the whole ProcessSensor chain
// (offset, filter, onset detection, integration) on records of realistic length (25 kHz).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "impactdic/sensor/filter.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {
namespace {

// Rest 20 ms, free fall to 3.7 m/s, a 40 g half-sine pulse until the stop, rest; 0.05 g noise.
SensorRecord MakeRecord(double seconds) {
  const double fs = 25000, g = 9.81, v0 = 3.7, a_pk = 40 * g, t_d = 0.02;
  const double t_rel = 0.02, t_imp = t_rel + v0 / g, w = std::numbers::pi / t_d;
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0, 0.05);
  SensorRecord r;
  r.sample_rate_hz = fs;
  bool stopped = false;
  for (int i = 0; i < static_cast<int>(seconds * fs); ++i) {
    const double t = i / fs, tau = t - t_imp;
    double reading = 1;
    if (t >= t_rel && tau < 0) reading = 0;
    if (tau >= 0 && !stopped) {
      const double v = v0 + g * tau - a_pk / w * (1 - std::cos(w * tau));
      stopped = v <= 0;
      if (!stopped) reading = a_pk / g * std::sin(w * tau);
    }
    r.time_s.push_back(t);
    r.accel_g.push_back(reading + 0.02 + noise(rng));
  }
  return r;
}

void BM_FiltFilt(benchmark::State& state) {
  const SensorRecord r = MakeRecord(static_cast<double>(state.range(0)) / 25000);
  const FirstOrderLowpass lp = DesignButterworthLowpass1(1500, 25000);
  for (auto _ : state) benchmark::DoNotOptimize(FiltFilt(lp, r.accel_g));
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_FiltFilt)->Arg(12500)->Arg(125000);

void BM_ProcessSensor(benchmark::State& state) {
  const SensorRecord r = MakeRecord(0.5);
  for (auto _ : state) benchmark::DoNotOptimize(ProcessSensor(r, SensorOptions{}));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(r.time_s.size()));
}
BENCHMARK(BM_ProcessSensor);

}  // namespace
}  // namespace impactdic

BENCHMARK_MAIN();
