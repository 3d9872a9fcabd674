// Test helper of the strain validation (docs/validation_strain.md, "Strain"): the errors of a
// strain field (strain/strain.h) against the strain of a truth.h5 (soil/dudx ..., soil/eps_v ...,
// written by `impactdic synth`, analytic or DEM), and the correlation results of a run as the
// strain module's input.
#ifndef IMPACTDIC_TESTS_VALIDATION_STRAIN_COMPARE_H_
#define IMPACTDIC_TESTS_VALIDATION_STRAIN_COMPARE_H_

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "impactdic/io/hdf5_store.h"
#include "impactdic/kinematics/kinematics.h"
#include "impactdic/strain/strain.h"

namespace impactdic::strain_validation {

// The run's /dic as the strain module's input (valid = converged status), and /time/frame_index
// (the truth frame of each row; the row itself without it, as `correlate` writes).
struct RunDic {
  CorrelationSeries series;
  std::vector<std::size_t> truth_frame;
};
inline RunDic ReadRunDic(const std::string& results_h5) {
  const H5Reader in(results_h5);
  RunDic r;
  CorrelationSeries& s = r.series;
  s.x_px = in.ReadDouble("/dic/x_px");
  s.y_px = in.ReadDouble("/dic/y_px");
  s.u_px = in.ReadDouble("/dic/u_px");
  s.v_px = in.ReadDouble("/dic/v_px");
  s.subsets = s.x_px.size();
  s.frames = s.u_px.size() / s.subsets;
  const std::vector<std::int32_t> status = in.ReadInt("/dic/status");
  s.valid.resize(status.size());
  for (std::size_t i = 0; i < status.size(); ++i) s.valid[i] = status[i] == 0 ? 1 : 0;
  if (in.Exists("/time/frame_index")) {
    for (double k : in.ReadDouble("/time/frame_index"))
      r.truth_frame.push_back(static_cast<std::size_t>(k));
  } else {  // `impactdic correlate`: row f is image f
    for (std::size_t f = 0; f < s.frames; ++f) r.truth_frame.push_back(f);
  }
  return r;
}

// RMS and max |error| over the compared samples, and their count.
struct ErrorStats {
  double rms = NAN, max = NAN;
  std::size_t samples = 0;
};

// The truth of one run: every soil/ strain dataset, indexed like the run's rows (row f = truth
// frame truth_frame[f]); `use` marks the compared samples: rows after the first, valid in the
// run, not covered by the pounder (soil/occluded, when the truth has it).
class StrainTruth {
 public:
  StrainTruth(const std::string& truth_h5, const RunDic& run) : in_(truth_h5), run_(run) {
    const std::size_t N = run.series.subsets;
    std::vector<std::int32_t> occluded;
    if (in_.Exists("soil/occluded")) occluded = in_.ReadInt("soil/occluded");
    use_.assign(run.series.frames * N, 0);
    for (std::size_t f = 1; f < run.series.frames; ++f)
      for (std::size_t i = 0; i < N; ++i) {
        const std::size_t j = f * N + i, t = run.truth_frame[f] * N + i;
        use_[j] = run.series.valid[j] != 0 && (occluded.empty() || occluded[t] == 0);
      }
  }
  // The truth's `name` (soil/NAME) in the run's rows.
  std::vector<double> Field(const std::string& name) const {
    const std::vector<double> all = in_.ReadDouble("soil/" + name);
    const std::size_t N = run_.series.subsets;
    std::vector<double> out(run_.series.frames * N);
    for (std::size_t f = 0; f < run_.series.frames; ++f)
      std::copy_n(all.begin() + static_cast<std::ptrdiff_t>(run_.truth_frame[f] * N), N,
                  out.begin() + static_cast<std::ptrdiff_t>(f * N));
    return out;
  }
  // The truth displacements (soil/u_px, soil/v_px) as a correlation series on the run's grid,
  // valid where the run is: what a perfect correlation would give.
  CorrelationSeries PerfectSeries() const {
    CorrelationSeries s = run_.series;
    s.u_px = Field("u_px");
    s.v_px = Field("v_px");
    return s;
  }
  // tool - truth over the compared samples finite in both.
  ErrorStats Compare(const std::vector<double>& tool, const std::vector<double>& truth) const {
    ErrorStats e;
    double sum = 0, worst = 0;
    for (std::size_t j = 0; j < use_.size(); ++j) {
      if (!use_[j] || !std::isfinite(tool[j]) || !std::isfinite(truth[j])) continue;
      const double d = tool[j] - truth[j];
      sum += d * d, worst = std::max(worst, std::abs(d));
      ++e.samples;
    }
    if (e.samples > 0) e.rms = std::sqrt(sum / static_cast<double>(e.samples)), e.max = worst;
    return e;
  }
  ErrorStats Compare(const std::vector<double>& tool, const std::string& name) const {
    return Compare(tool, Field(name));
  }

 private:
  H5Reader in_;
  const RunDic& run_;
  std::vector<std::uint8_t> use_;
};

// Strain measures by their soil/ and /strain names (dudx ... gamma_max).
using NamedFields = std::map<std::string, std::vector<double>>;
inline NamedFields Named(const DisplacementGradient& g, const StrainField& s) {
  return {{"dudx", g.dudx},
          {"dudy", g.dudy},
          {"dvdx", g.dvdx},
          {"dvdy", g.dvdy},
          {"exx", s.exx},
          {"eyy", s.eyy},
          {"exy", s.exy},
          {"green_lagrange_xx", s.gxx},
          {"green_lagrange_yy", s.gyy},
          {"green_lagrange_xy", s.gxy},
          {"eps_v", s.eps_v},
          {"gamma_max", s.gamma_max}};
}
inline NamedFields Named(const StrainTruth& truth) {
  NamedFields f;
  for (const char* name : {"dudx", "dudy", "dvdx", "dvdy", "exx", "eyy", "exy", "green_lagrange_xx",
                           "green_lagrange_yy", "green_lagrange_xy", "eps_v", "gamma_max"})
    f[name] = truth.Field(name);
  return f;
}

// A results file's /strain datasets (the pipeline's strain stage) under the same names.
inline NamedFields ReadStrainGroup(const std::string& results_h5) {
  const H5Reader in(results_h5);
  NamedFields f;
  for (const char* name : {"dudx", "dudy", "dvdx", "dvdy", "exx", "eyy", "exy", "green_lagrange_xx",
                           "green_lagrange_yy", "green_lagrange_xy", "eps_v", "gamma_max"})
    f[name] = in.ReadDouble(std::string("/strain/") + name);
  return f;
}

// a - b elementwise (e.g. the Green-Lagrange quadratic term (H^T H) / 2 = GL - small strain).
inline std::vector<double> Minus(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> d(a.size());
  for (std::size_t j = 0; j < a.size(); ++j) d[j] = a[j] - b[j];
  return d;
}

}  // namespace impactdic::strain_validation

#endif  // IMPACTDIC_TESTS_VALIDATION_STRAIN_COMPARE_H_
