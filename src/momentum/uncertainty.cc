// The Monte Carlo of the momentum figures' uncertainty (momentum/uncertainty.h).
#include "impactdic/momentum/uncertainty.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/numeric.h"
#include "impactdic/momentum/momentum.h"
#include "momentum_internal.h"

namespace impactdic {

void MomentumUncertaintyOptions::Check() const {
  CheckValue(kUncertaintyDrawsRange.Contains(draws), "momentum.uncertainty_draws",
             fmt::format("{}", draws), kUncertaintyDrawsRange.Text());
  for (const auto& [name, value] :
       {std::pair{"test.density_u_kg_m3", density_u_kg_m3}, std::pair{"test.depth_u_m", depth_u_m},
        std::pair{"inputs.mm_per_px_u (relative)", scale_u_fraction},
        std::pair{"dic.subset_size (on the panel, mm)", subset_size_mm}}) {
    CheckValue(std::isfinite(value) && value >= 0, name, fmt::format("{}", value),
               "a standard uncertainty >= 0");
  }
}

namespace {

constexpr std::uint32_t kSeed = 0x5eed42;

// Sample standard deviation of the finite values; NaN for fewer than two.
double FiniteSd(const std::vector<double>& values) {
  double sum = 0, sum2 = 0;
  std::size_t n = 0;
  for (double v : values) {
    if (!std::isfinite(v)) continue;
    sum += v;
    ++n;
  }
  if (n < 2) return kNaN;
  const double mean = sum / static_cast<double>(n);
  for (double v : values)
    if (std::isfinite(v)) sum2 += (v - mean) * (v - mean);
  return std::sqrt(sum2 / static_cast<double>(n - 1));
}

// Correlation of two subsets' errors: the overlap fraction of their areas (side `size`).
double OverlapFraction(double dx, double dy, double size) {
  if (!(size > 0)) return dx == 0 && dy == 0 ? 1.0 : 0.0;
  return std::max(0.0, 1 - std::abs(dx) / size) * std::max(0.0, 1 - std::abs(dy) / size);
}

// The accelerometer's part: the record processed again (sensor ProcessAccelerometer: offset,
// filter, release and impact detection, integration, stop) with fresh white noise of the
// record's own standard deviation (SensorSummary::noise_g, from the free-fall window before the
// impact) added to its reading.
class PounderDraws {
 public:
  explicit PounderDraws(const SensorResult& sensor) : sensor_(sensor), options_(sensor.options) {
    options_.columns.base_force.clear();
    options_.base = BaseForceOptions{};
  }
  // The record carries its reading (it came from ProcessSensor) and a measured noise.
  bool Available() const {
    const double noise = sensor_.summary.noise_g;
    return !sensor_.reading_g.empty() && sensor_.reading_g.size() == sensor_.time_s.size() &&
           std::isfinite(noise) && noise > 0;
  }
  // Throws Error when the draw's record cannot be analysed (e.g. no impact found).
  SensorResult Draw(std::mt19937_64& rng) const {
    std::normal_distribution<double> normal;
    SensorRecord record;
    record.path = sensor_.path;
    record.time_s = sensor_.time_s;
    record.sample_rate_hz = sensor_.summary.sample_rate_hz;
    record.accel_g.resize(sensor_.reading_g.size());
    for (std::size_t i = 0; i < record.accel_g.size(); ++i)
      record.accel_g[i] = sensor_.reading_g[i] + sensor_.summary.noise_g * normal(rng);
    return ProcessAccelerometer(record, options_);
  }

 private:
  const SensorResult& sensor_;
  SensorOptions options_;
};

// The grid's part: displacement errors [frames x grid] of one draw, sigma * (sqrt(1/2) a_i +
// sqrt(1/2) b_ki) with a (the reference's noise, common to the frames) and b_k (frame k's) each
// correlated over the grid by L L^T (the overlap fractions).
class GridNoise {
 public:
  GridNoise(const KinematicsResult& kin, const MomentumGrid& grid, double subset_size_mm)
      : kin_(kin), grid_(grid) {
    const std::size_t g = grid.subset_ids.size();
    Eigen::MatrixXd r(g, g);
    for (std::size_t i = 0; i < g; ++i) {
      for (std::size_t j = 0; j < g; ++j) {
        const std::size_t a = grid.subset_ids[i], b = grid.subset_ids[j];
        r(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
            OverlapFraction(kin.x_mm[a] - kin.x_mm[b], kin.y_mm[a] - kin.y_mm[b], subset_size_mm);
      }
    }
    // The overlap fractions are a product of two triangle functions, positive semi-definite; a
    // small ridge keeps the factorisation defined.
    r.diagonal().array() += 1e-12;
    l_ = r.llt().matrixL();
  }
  void Draw(std::mt19937_64& rng, std::vector<double>* err) const {
    const std::size_t g = grid_.subset_ids.size(), nf = kin_.frames;
    std::normal_distribution<double> normal;
    auto correlated = [&] {
      Eigen::VectorXd z(static_cast<Eigen::Index>(g));
      for (Eigen::Index i = 0; i < z.size(); ++i) z(i) = normal(rng);
      return Eigen::VectorXd(l_ * z);
    };
    const Eigen::VectorXd common = correlated();
    err->assign(nf * g, 0);
    for (std::size_t k = 0; k < nf; ++k) {
      const Eigen::VectorXd own = correlated();
      for (std::size_t i = 0; i < g; ++i) {
        const float sigma = kin_.disp_y_sigma_mm[k * kin_.subsets + grid_.subset_ids[i]];
        const auto ii = static_cast<Eigen::Index>(i);
        (*err)[k * g + i] =
            std::isfinite(sigma) ? sigma * std::sqrt(0.5) * (common(ii) + own(ii)) : 0.0;
      }
    }
  }

 private:
  const KinematicsResult& kin_;
  const MomentumGrid& grid_;
  Eigen::MatrixXd l_;
};

// The headline figures of one analysis, in UncertainFigures' order.
std::vector<double> Figures(const MomentumSummary& s) {
  std::vector<double> v;
  for (const auto& f : UncertainFigures(s))
    v.push_back(s.sigmoid_fitted || std::string(f.name).rfind("sigmoid_", 0) != 0 ? *f.value
                                                                                  : kNaN);
  return v;
}

double MedianOf(std::vector<double> v) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return kNaN;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// The notes on what the draws left out: draws without a measurable t_e, inputs stated without
// an uncertainty.
void AddNotes(const MomentumUncertaintyOptions& uo, int not_measured, MomentumUncertainty* out) {
  MomentumUncertainty& u = *out;
  if (not_measured > 0) {
    u.notes.push_back(fmt::format(
        "in {} of {} draws t_e was not measurable; the figures' spread is over the others",
        not_measured, uo.draws));
  }
  std::string exact;
  for (const auto& [key, value] :
       {std::pair{"inputs.mm_per_px_u (or a calibration's plane scale uncertainty)",
                  uo.scale_u_fraction},
        std::pair{"test.density_u_kg_m3", uo.density_u_kg_m3},
        std::pair{"test.depth_u_m", uo.depth_u_m}})
    if (value == 0) exact += (exact.empty() ? "" : ", ") + std::string(key);
  if (!exact.empty()) {
    u.notes.push_back("stated without an uncertainty, so counted as exact (0): " + exact);
  }
}

// The per-frame standard deviations of the draws (NaN where the nominal series is).
void FrameBands(const std::vector<std::vector<double>>& v_sand,
                const std::vector<std::vector<double>>& p_gran,
                const std::vector<std::vector<double>>& p_total,
                const std::vector<std::vector<double>>& m_add, MomentumResult* result) {
  const std::size_t nf = result->frame_time_s.size();
  result->v_sand_u_m_s.resize(nf);
  result->p_gran_u_kg_m_s.resize(nf);
  result->p_total_u_kg_m_s.resize(nf);
  result->added_mass_u_kg.resize(nf);
  for (std::size_t k = 0; k < nf; ++k) {
    auto sd = [&](const std::vector<double>& nominal_series, const std::vector<double>& draws) {
      return std::isfinite(nominal_series[k]) ? FiniteSd(draws) : kNaN;
    };
    result->v_sand_u_m_s[k] = sd(result->v_sand_m_s, v_sand[k]);
    result->p_gran_u_kg_m_s[k] = sd(result->p_gran_kg_m_s, p_gran[k]);
    result->p_total_u_kg_m_s[k] = sd(result->p_total_kg_m_s, p_total[k]);
    result->added_mass_u_kg[k] = sd(result->added_mass_kg, m_add[k]);
  }
}

// t_e on a frame (not refined): the frame grid's resolution, uniform over one interval of dt.
void AddFrameGridTerm(double dt, MomentumSummary* summary) {
  const MomentumSummary& s = *summary;
  MomentumUncertainty& u = summary->uncertainty;
  if (std::isfinite(s.t_end_peak_s) && !s.t_end_refined) {
    u.t_end_grid_s = dt / std::sqrt(12.0);
    u.t_end_peak_s =
        std::hypot(std::isfinite(u.t_end_peak_s) ? u.t_end_peak_s : 0.0, u.t_end_grid_s);
    u.notes.push_back(fmt::format(
        "t_e lies on a frame (not refined between two): its uncertainty includes the frame "
        "grid's dt / sqrt(12) = {:.4g} s; the figures at t_e do not",
        u.t_end_grid_s));
  }
}

// One Monte Carlo draw's analysis.
struct Draw {
  bool analysed = false;  // false: the analysis threw (e.g. the draw's record has no impact).
  MomentumResult result;
};

// The draws' spread: each headline figure's standard deviation into its u in result->summary
// (NaN where the nominal figure is), the per-frame bands into `result`. Returns how many draws
// did not measure t_e.
int Aggregate(const std::vector<Draw>& draws, std::size_t nf, MomentumResult* result) {
  MomentumSummary& s = result->summary;
  const std::size_t nfig = Figures(s).size();
  std::vector<std::vector<double>> figures(nfig);
  std::vector<std::vector<double>> v_sand(nf), p_gran(nf), p_total(nf), m_add(nf);
  int not_measured = 0;
  for (const Draw& draw : draws) {
    if (!draw.analysed || !draw.result.summary.t_end_problem.empty()) ++not_measured;
    if (!draw.analysed) continue;
    const MomentumResult& r = draw.result;
    const std::vector<double> f = Figures(r.summary);
    for (std::size_t j = 0; j < nfig; ++j) figures[j].push_back(f[j]);
    for (std::size_t k = 0; k < nf; ++k) {
      v_sand[k].push_back(r.v_sand_m_s[k]);
      p_gran[k].push_back(r.p_gran_kg_m_s[k]);
      p_total[k].push_back(r.p_total_kg_m_s[k]);
      m_add[k].push_back(r.added_mass_kg[k]);
    }
  }
  std::vector<double*> us;
  for (const auto& f : UncertainFigures(s)) us.push_back(f.u);
  const std::vector<double> nominal = Figures(s);
  for (std::size_t j = 0; j < nfig; ++j)
    *us[j] = std::isfinite(nominal[j]) ? FiniteSd(figures[j]) : kNaN;
  FrameBands(v_sand, p_gran, p_total, m_add, result);
  return not_measured;
}

}  // namespace

void EstimateMomentumUncertainty(const KinematicsResult& kin, const SensorResult& sensor,
                                 const MomentumOptions& options, MomentumResult* result) {
  const MomentumUncertaintyOptions& uo = options.uncertainty;
  MomentumSummary& s = result->summary;
  MomentumUncertainty& u = s.uncertainty;
  u = MomentumUncertainty{};
  u.accel_noise_g = sensor.summary.noise_g;
  u.scale_u_fraction = uo.scale_u_fraction;
  u.density_u_kg_m3 = uo.density_u_kg_m3;
  u.depth_u_m = uo.depth_u_m;
  u.subset_size_mm = uo.subset_size_mm;
  const std::size_t nf = kin.frames, g = s.grid.subset_ids.size();
  if (uo.draws == 0) {
    u.notes.push_back("not estimated: momentum.uncertainty_draws is 0");
    return;
  }
  if (kin.disp_y_sigma_mm.size() != nf * kin.subsets) {
    u.notes.push_back(
        "not estimated: the correlation results carry no sigma_u_px / sigma_v_px (written "
        "before they existed); correlate again");
    return;
  }
  // The grid's subsets alone, ids 0..g-1, and their displacements.
  KinematicsResult grid_kin;
  grid_kin.frames = nf;
  grid_kin.subsets = g;
  grid_kin.time_s = kin.time_s;
  std::vector<double> disp(nf * g), sigmas;
  for (std::size_t i = 0; i < g; ++i) {
    const std::size_t id = s.grid.subset_ids[i];
    grid_kin.x_mm.push_back(kin.x_mm[id]);
    grid_kin.y_mm.push_back(kin.y_mm[id]);
    for (std::size_t k = 0; k < nf; ++k) {
      disp[k * g + i] = kin.disp_y_mm[k * kin.subsets + id];
      if (k > 0) sigmas.push_back(kin.disp_y_sigma_mm[k * kin.subsets + id]);
    }
  }
  u.dic_sigma_median_mm = MedianOf(sigmas);
  grid_kin.disp_y_mm.resize(nf * g);
  grid_kin.vel_y_mm_s.resize(nf * g);
  grid_kin.acc_y_mm_s2.resize(nf * g);
  const double dt = nf > 1 ? kin.time_s[1] - kin.time_s[0] : 1.0;
  MomentumGrid grid_template = s.grid;
  for (std::size_t i = 0; i < g; ++i) grid_template.subset_ids[i] = i;
  MomentumOptions o = options;
  o.uncertainty.draws = 0;

  const GridNoise grid_noise(kin, s.grid, uo.subset_size_mm);
  const PounderDraws pounder_draws(sensor);
  if (!pounder_draws.Available()) {
    u.notes.push_back(
        "the accelerometer's noise is not propagated: the sensor result carries no reading to "
        "process again, or no measured noise");
  }
  // One draw: its own random stream (seeded by the draw's index, so that the result does not
  // depend on the number of threads), the inputs perturbed, the analysis on the grid; `red` and
  // `grid` are the draw's scratch copies of grid_kin and grid_template.
  auto run_draw = [&](std::size_t d, KinematicsResult* red, MomentumGrid* grid) {
    std::seed_seq seq{kSeed, static_cast<std::uint32_t>(d)};
    std::mt19937_64 rng(seq);
    std::normal_distribution<double> normal;
    const double scale = 1 + uo.scale_u_fraction * normal(rng);
    const double density = options.density_kg_m3 + uo.density_u_kg_m3 * normal(rng);
    const double depth = options.depth_m + uo.depth_u_m * normal(rng);
    std::vector<double> err, column(nf);
    grid_noise.Draw(rng, &err);
    for (std::size_t i = 0; i < g; ++i) {
      for (std::size_t k = 0; k < nf; ++k) column[k] = scale * (disp[k * g + i] + err[k * g + i]);
      const std::vector<double> v = FirstDerivative(column, dt), a = SecondDerivative(column, dt);
      for (std::size_t k = 0; k < nf; ++k) {
        red->disp_y_mm[k * g + i] = column[k];
        red->vel_y_mm_s[k * g + i] = v[k];
        red->acc_y_mm_s2[k * g + i] = a[k];
      }
    }
    grid->area_m2 = s.grid.area_m2 * scale * scale;
    grid->mass_kg = density * grid->area_m2 * depth;
    Draw out;
    try {
      SensorResult drawn;
      if (pounder_draws.Available()) drawn = pounder_draws.Draw(rng);
      const SensorResult& pounder = pounder_draws.Available() ? drawn : sensor;
      out.result = internal::AnalyzeMomentumOnGrid(*red, result->frame_time_s, pounder, o, *grid);
      out.analysed = true;
    } catch (const Error&) {
      out.analysed = false;
    }
    return out;
  };
  std::vector<Draw> draws(static_cast<std::size_t>(uo.draws));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, draws.size()),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      KinematicsResult red = grid_kin;
                      MomentumGrid grid = grid_template;
                      for (std::size_t d = range.begin(); d != range.end(); ++d)
                        draws[d] = run_draw(d, &red, &grid);
                    });
  u.draws = uo.draws;
  const int not_measured = Aggregate(draws, nf, result);
  AddFrameGridTerm(dt, &s);
  AddNotes(uo, not_measured, &u);
}

JsonObject UncertaintyJson(const MomentumSummary& s) {
  const MomentumUncertainty& u = s.uncertainty;
  JsonObject j;
  j.Add("method", kMomentumUncertaintyMethod).Add("draws", u.draws);
  const std::vector<double> values = Figures(s);
  std::size_t i = 0;
  for (const auto& f : UncertainFigures(s)) {
    JsonObject figure;
    figure.Add("value", values[i++]).Add("u", u.draws > 0 ? *f.u : kNaN);
    j.Add(f.name, figure);
  }
  JsonObject inputs;
  inputs.Add("accel_noise_g", u.accel_noise_g)
      .Add("dic_sigma_median_mm", u.dic_sigma_median_mm)
      .Add("scale_u_fraction", u.scale_u_fraction)
      .Add("density_u_kg_m3", u.density_u_kg_m3)
      .Add("depth_u_m", u.depth_u_m)
      .Add("subset_size_mm", u.subset_size_mm);
  j.Add("t_end_grid_s", u.t_end_grid_s).Add("inputs", inputs).Add("notes", u.notes);
  return j;
}

}  // namespace impactdic
