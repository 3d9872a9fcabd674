// Comparison of a run on DEM footage with the grains' truth (docs/validation.md).
#include "impactdic/render/dem_validation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>  // flag values only (WriteImage encodes)
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <system_error>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/core/interrupt.h"
#include "impactdic/core/numeric.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/dic_results.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/image_io.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/kinematics/kinematics_results.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/model/model_results.h"
#include "impactdic/momentum/momentum_results.h"
#include "impactdic/momentum/wave_front.h"
#include "impactdic/render/figures.h"
#include "impactdic/render/gnuplot.h"
#include "impactdic/render/render_results.h"
#include "impactdic/render/velocity_field.h"
#include "impactdic/sensor/sensor.h"
#include "impactdic/sensor/sensor_results.h"
#include "impactdic/sensor/wave_results.h"

namespace impactdic {
namespace {

double Scalar(const H5Reader& in, const std::string& path) {
  const std::vector<double> v = in.ReadDouble(path);
  if (v.empty()) throw Error(ErrorKind::kFileFormat, path, "an empty dataset", "one value");
  return v[0];
}

double Attr(const H5Reader& in, const std::string& object, const std::string& name) {
  return in.HasAttribute(object, name) ? in.ReadNumberAttribute(object, name) : kNaN;
}

struct TruthFile {
  std::vector<double> frame_t, gx, gy, u, v, vx, vy, p_gran, p_gran_fd, v_sand, pounder_v,
      pounder_z;
  std::vector<double> fine_t, fine_p_gran, sensor_t, sensor_g;
  std::size_t cells = 0;
  double p_max = kNaN, t_e = kNaN, v_te = kNaN, m_add_max = kNaN, cons = kNaN, cons_peak = kNaN;
  double grid_mass = kNaN, bulk_density = kNaN, mp = kNaN, v0 = kNaN, width = kNaN, depth = kNaN;
  double sx = kNaN;
};

// What an HDF5 file is, by the groups and attributes impactdic's writers give it: "a DEM truth
// file", "a run's results file", ... For messages naming the file that was expected instead.
std::string DescribeFileKind(const H5Reader& in) {
  if (in.Exists("/dem")) return "a DEM truth file (impactdic synth --dem)";
  const std::string generator =
      in.HasAttribute("/", "generator") ? in.ReadStringAttribute("/", "generator") : "";
  if (generator.rfind("impactdic synth", 0) == 0 || in.Exists("/soil"))
    return "the ground truth of a synthetic scene (impactdic synth without --dem: the analytic "
           "soil field, no grains)";
  if (in.Exists(results_layout::kTimeFrameIndex) || in.HasAttribute("/", "scene_name"))
    return "a run's results file (impactdic run)";
  if (in.Exists(results_layout::kDicGroup)) return "correlation results (impactdic correlate)";
  if (in.Exists(results_layout::kModelGroup)) return "a model series (impactdic model -o)";
  if (in.Exists(results_layout::kSensorGroup)) return "sensor results (impactdic analyze --output)";
  return "an HDF5 file impactdic did not write";
}

// The two files are what validate-dem compares, before anything is read from them (given
// another file, the first missing dataset was named, not the file that was needed).
void CheckFileKinds(const std::string& truth_h5, const std::string& results_h5) {
  const std::string truth_kind = DescribeFileKind(H5Reader(truth_h5));
  if (truth_kind.rfind("a DEM truth file", 0) != 0)
    throw Error(ErrorKind::kFileFormat,
                fmt::format("is {}, not a DEM truth file; validate-dem compares a run with the "
                            "truth.h5 that `impactdic synth --dem` writes beside the DEM footage "
                            "(the grains' measured velocities and momentum: /dem, /soil, "
                            "/momentum); give it first, then the run's results.h5",
                            truth_kind))
        .WithFile(truth_h5);
  const std::string results_kind = DescribeFileKind(H5Reader(results_h5));
  if (results_kind.rfind("a run's results file", 0) != 0)
    throw Error(ErrorKind::kFileFormat,
                fmt::format("is {}, not a run's results file; validate-dem needs the results.h5 "
                            "of `impactdic run` on the DEM footage as its second file",
                            results_kind))
        .WithFile(results_h5);
}

TruthFile ReadTruth(const std::string& path) {
  H5Reader in(path);
  TruthFile t;
  t.frame_t = in.ReadDouble("frames/time_s");
  t.gx = in.ReadDouble("soil/grid_x_px");
  t.gy = in.ReadDouble("soil/grid_y_px");
  t.cells = t.gx.size();
  t.u = in.ReadDouble("soil/u_px");
  t.v = in.ReadDouble("soil/v_px");
  t.vx = in.ReadDouble("soil/velocity_x_mm_s");
  t.vy = in.ReadDouble("soil/velocity_y_mm_s");
  t.p_gran = in.ReadDouble("momentum/p_gran_Ns");
  t.v_sand = in.ReadDouble("momentum/v_sand_m_s");
  t.p_gran_fd = in.ReadDouble("momentum/p_gran_fd_Ns");
  t.pounder_v = in.ReadDouble("pounder/v_m_s");
  t.pounder_z = in.ReadDouble("pounder/z_m");
  if (in.Exists("series/t_s")) {
    t.fine_t = in.ReadDouble("series/t_s");
    t.fine_p_gran = in.ReadDouble("series/p_gran_Ns");
  }
  t.sensor_t = in.ReadDouble("sensor/t_s");
  t.sensor_g = in.ReadDouble("sensor/accel_true_g");
  t.p_max = Scalar(in, "momentum/p_max_Ns");
  t.t_e = Scalar(in, "momentum/t_e_s");
  t.v_te = Scalar(in, "momentum/v_te_m_s");
  t.m_add_max = Scalar(in, "momentum/m_add_max_kg");
  t.cons = Scalar(in, "momentum/conservation_error");
  t.cons_peak = Scalar(in, "momentum/conservation_error_peak");
  t.grid_mass = Scalar(in, "momentum/grid_mass_kg");
  t.bulk_density = Scalar(in, "momentum/bulk_density_kg_m3");
  t.mp = Attr(in, "dem", "pounder_mass_kg");
  t.v0 = Attr(in, "dem", "impact_velocity_m_s");
  t.width = Attr(in, "dem", "pounder_width_m");
  t.depth = Attr(in, "dem", "depth_m");
  t.sx = Attr(in, "camera", "sx_mm_per_px");
  return t;
}

// Matches each DIC subset with the truth cell of the same centre (within 0.5 px), or -1.
std::vector<long> MatchCells(const std::vector<double>& x, const std::vector<double>& y,
                             const TruthFile& t) {
  std::vector<long> cell(x.size(), -1);
  for (std::size_t i = 0; i < x.size(); ++i)
    for (std::size_t c = 0; c < t.cells; ++c)
      if (std::abs(x[i] - t.gx[c]) <= 0.5 && std::abs(y[i] - t.gy[c]) <= 0.5) {
        cell[i] = static_cast<long>(c);
        break;
      }
  return cell;
}

void CompareDic(const H5Reader& res, const std::string& file, const TruthFile& t,
                const std::vector<std::size_t>& frame, DemValidation* out,
                VelocityFieldSequence* tool_seq, VelocityFieldSequence* truth_seq) {
  const DicResultsTable dic = ReadDicResults(res, file);
  const KinematicsResult kin = ReadKinematicsResults(res, file).kinematics;
  const std::vector<double>&x = dic.x_px, &y = dic.y_px, &u = dic.u_px, &v = dic.v_px;
  const std::vector<double>&vx = kin.vel_x_mm_s, &vy = kin.vel_y_mm_s;
  const std::size_t N = x.size(), F = frame.size();
  const std::vector<long> cell = MatchCells(x, y, t);
  const double fps = 1 / (t.frame_t[1] - t.frame_t[0]);
  double se_v = 0, se_fd = 0, se_u = 0, vmax = 0;
  std::size_t n = 0, n_fd = 0;
  truth_seq->vx_mm_s.assign(F * N, kNaN);
  truth_seq->vy_mm_s.assign(F * N, kNaN);
  for (std::size_t f = 0; f < F; ++f) {
    const std::size_t k = frame[f];
    for (std::size_t i = 0; i < N; ++i) {
      if (cell[i] < 0) continue;
      const std::size_t c = k * t.cells + static_cast<std::size_t>(cell[i]);
      truth_seq->vx_mm_s[f * N + i] = t.vx[c];
      truth_seq->vy_mm_s[f * N + i] = t.vy[c];
      if (!(t.frame_t[k] > 0)) continue;
      vmax = std::max(vmax, std::hypot(t.vx[c], t.vy[c]));
      const std::size_t j = f * N + i;
      if (!std::isfinite(vx[j]) || !std::isfinite(vy[j]) || !std::isfinite(t.vx[c])) continue;
      se_v += std::pow(vx[j] - t.vx[c], 2) + std::pow(vy[j] - t.vy[c], 2);
      ++n;
      se_u += std::pow(u[j] - (t.u[c] - t.u[frame[0] * t.cells + (c % t.cells)]), 2) +
              std::pow(v[j] - (t.v[c] - t.v[frame[0] * t.cells + (c % t.cells)]), 2);
      if (k >= 1 && k + 1 < t.frame_t.size()) {
        const std::size_t cp = c + t.cells, cm = c - t.cells;
        const double sx = t.sx;  // mm/px (sx ~ sy for the fronto-parallel camera)
        const double fx = (t.u[cp] - t.u[cm]) * sx * fps / 2,
                     fy = (t.v[cp] - t.v[cm]) * sx * fps / 2;
        se_fd += std::pow(vx[j] - fx, 2) + std::pow(vy[j] - fy, 2);
        ++n_fd;
      }
    }
  }
  out->dic_samples = n;
  out->dic_velocity_rms_mm_s = n ? std::sqrt(se_v / n) : kNaN;
  out->dic_velocity_rms_fd_mm_s = n_fd ? std::sqrt(se_fd / n_fd) : kNaN;
  out->dic_displacement_rms_px = n ? std::sqrt(se_u / n) : kNaN;
  out->truth_speed_max_mm_s = vmax;
  tool_seq->num_subsets = truth_seq->num_subsets = N;
  tool_seq->x_px = truth_seq->x_px = x;
  tool_seq->y_px = truth_seq->y_px = y;
  tool_seq->vx_mm_s = vx;
  tool_seq->vy_mm_s = vy;
}

void CompareMomentum(const MomentumResultsGroup& tool, const TruthFile& t,
                     const std::vector<std::size_t>& frame, DemValidation* out) {
  const MomentumResult& m = tool.momentum;
  const MomentumSummary& s = m.summary;
  out->p_gran_tool_Ns = m.p_gran_kg_m_s;
  out->p_pounder_tool_Ns = m.p_pounder_kg_m_s;
  out->v_sand_tool_m_s = m.v_sand_m_s;
  out->m_add_tool_kg = m.added_mass_kg;
  out->p_max_tool_Ns = s.p_max_kg_m_s;
  out->t_e_tool_s = s.t_end_peak_s;
  out->conservation_tool = s.momentum_conservation_error;
  out->m_add_max_tool_kg = s.added_mass_max_kg;
  out->grid_mass_tool_kg = s.grid.mass_kg;
  out->sigmoid_M_kg = s.sigmoid.M_kg;  // NaN when no sigmoid was fitted.
  out->sigmoid_b_per_s = s.sigmoid.b_per_s;
  out->sigmoid_T_s = s.sigmoid.T_s;
  out->p_max_truth_Ns = t.p_max;
  out->t_e_truth_s = t.t_e;
  out->conservation_truth = t.cons;
  out->conservation_truth_peak = t.cons_peak;
  out->m_add_max_truth_kg = t.m_add_max;
  out->grid_mass_truth_kg = t.grid_mass;
  double worst = 0, worst_fd = 0, sum_tool = 0, sum_truth = 0;
  bool any = false;
  for (std::size_t f = 0; f < frame.size(); ++f) {
    const std::size_t k = frame[f];
    const double tk = t.frame_t[k];
    out->t_s.push_back(tk);
    out->p_gran_truth_Ns.push_back(t.p_gran[k]);
    out->p_gran_fd_truth_Ns.push_back(t.p_gran_fd[k]);
    out->p_pounder_truth_Ns.push_back(t.mp * t.pounder_v[k]);
    out->v_sand_truth_m_s.push_back(t.v_sand[k]);
    out->m_add_truth_kg.push_back(tk > 0 && tk <= t.t_e + 1e-9 ? t.p_max / t.pounder_v[k] - t.mp
                                                               : kNaN);
    if (tk > 0 && tk <= t.t_e + 1e-9 && f < out->p_gran_tool_Ns.size() &&
        std::isfinite(out->p_gran_tool_Ns[f])) {
      worst = std::max(worst, std::abs(out->p_gran_tool_Ns[f] - t.p_gran[k]));
      worst_fd = std::max(worst_fd, std::abs(out->p_gran_tool_Ns[f] - t.p_gran_fd[k]));
      sum_tool += out->p_gran_tool_Ns[f];
      sum_truth += t.p_gran[k];
      any = true;
    }
  }
  if (any) {
    out->p_gran_error_peak_Ns = worst;
    out->p_gran_error_peak_rel = worst / t.p_max;
    out->p_gran_ratio_peak = sum_tool / sum_truth;
    out->p_gran_fd_error_peak_rel = worst_fd / t.p_max;
  } else {
    out->notes.push_back("no analysed frame in (0, t_e] of the grains: p_gran not compared");
  }
}

// Eq. 9 with the tool's fitted M, b, T against the DEM pounder (deceleration from the noise-free
// accelerometer reading: decel = reading - 1 g).
void CompareModel(const TruthFile& t, DemValidation* out, std::vector<double>* model_t,
                  std::vector<double>* model_g) {
  for (std::size_t i = 0; i < t.sensor_t.size(); ++i) {
    if (t.sensor_t[i] < 0) continue;
    if (!(t.sensor_g[i] - 1 <= out->dem_peak_decel_g))
      out->dem_peak_decel_g = t.sensor_g[i] - 1, out->dem_t_peak_s = t.sensor_t[i];
  }
  out->dem_max_penetration_m = *std::max_element(t.pounder_z.begin(), t.pounder_z.end());
  if (!std::isfinite(out->sigmoid_M_kg) || !std::isfinite(out->sigmoid_b_per_s) ||
      !std::isfinite(out->sigmoid_T_s)) {
    out->notes.push_back("no sigmoid fit in the results: Eq. 9 with fitted parameters not run");
    return;
  }
  ImpactModelParameters p;
  p.pounder_mass_kg = t.mp;
  p.impact_velocity_m_s = t.v0;
  p.width_m = t.width;
  p.depth_m = t.depth;
  p.density_kg_m3 = t.bulk_density;
  p.added_mass_kg = out->sigmoid_M_kg;
  p.sigmoid_rate_b_per_s = out->sigmoid_b_per_s;
  p.sigmoid_delay_T_s = std::max(0.0, out->sigmoid_T_s);
  try {
    p.Check();
    const ImpactRun run = SimulateImpact(p, ImpactSolverOptions{});
    out->model_peak_decel_g = run.summary.peak_deceleration_g;
    out->model_t_peak_s = run.summary.t_peak_s;
    out->model_crater_depth_m = run.summary.crater_depth_m;
    const double t_end = std::min(run.summary.t_end_s, t.sensor_t.back());
    const double g = p.gravity_m_s2, h = 1e-5;
    double se = 0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < t.sensor_t.size(); ++i) {
      const double ti = t.sensor_t[i];
      if (ti < h || ti > t_end - h) continue;
      const double a =
          (run.solution.StateAt(ti + h).v_m_s - run.solution.StateAt(ti - h).v_m_s) / (2 * h);
      const double decel = -a / g;
      model_t->push_back(ti);
      model_g->push_back(decel);
      se += std::pow(decel - (t.sensor_g[i] - 1), 2);
      ++n;
    }
    out->decel_rms_g = n ? std::sqrt(se / n) : kNaN;
  } catch (const Error& e) {
    out->notes.push_back(std::string("Eq. 9 with the fitted parameters failed: ") + e.what());
  }
}

// One analysed frame (row) of a sequence holding every row's velocities, over `image`.
VelocityFieldSequence OneFrame(const VelocityFieldSequence& all, std::size_t row, double t_s,
                               const cv::Mat& image) {
  const std::size_t n = all.num_subsets;
  VelocityFieldSequence one;
  one.frames = {image};
  one.time_ms = {1e3 * t_s};
  one.num_subsets = n;
  one.x_px = all.x_px;
  one.y_px = all.y_px;
  one.vx_mm_s.assign(all.vx_mm_s.begin() + row * n, all.vx_mm_s.begin() + (row + 1) * n);
  one.vy_mm_s.assign(all.vy_mm_s.begin() + row * n, all.vy_mm_s.begin() + (row + 1) * n);
  one.mm_per_px = all.mm_per_px;
  return one;
}

// tool_seq, truth_seq: the velocities of every analysed frame (no images); `images` the camera
// frames `run` stored (outputs.frames) and `image_rows` their analysed-frame rows: every row
// (`all`), some (the default `preview`) or none (then no velocity-field figure, with a note).
void DrawFigures(const TruthFile& t, DemValidation* out, const VelocityFieldSequence& tool_seq,
                 const VelocityFieldSequence& truth_seq, const std::vector<cv::Mat>& images,
                 const std::vector<std::size_t>& image_rows, const std::vector<double>& model_t,
                 const std::vector<double>& model_g, const std::string& dir) {
  namespace fs = std::filesystem;
  const DemValidation& v = *out;
  std::error_code ec;
  MakeFolders(dir, ec);
  if (ec || !fs::is_directory(dir, ec))
    throw Error(ErrorKind::kIo, "figures folder", dir,
                "a folder that can be created (" + ec.message() + ")");
  if (image_rows.empty()) {
    out->notes.push_back(
        "the results hold no camera frames (outputs.frames: none): no velocity-field figure");
  } else {
    // Velocity fields at the stored frame nearest the grains' t_e (the end of the peak stage),
    // one colour scale; only frames after the contact qualify while there are any (before it
    // only noise moves). A preview (outputs.frames: preview) may have none near t_e: the note
    // says how far it is.
    const double t_show = std::isfinite(t.t_e) ? t.t_e : 0.002;
    const bool any_after = std::any_of(image_rows.begin(), image_rows.end(),
                                       [&](std::size_t f) { return v.t_s[f] > 0; });
    std::size_t j_show = image_rows.size();
    for (std::size_t j = 0; j < image_rows.size(); ++j) {
      if (any_after && !(v.t_s[image_rows[j]] > 0)) continue;
      if (j_show == image_rows.size() ||
          std::abs(v.t_s[image_rows[j]] - t_show) < std::abs(v.t_s[image_rows[j_show]] - t_show))
        j_show = j;
    }
    const std::size_t f_show = image_rows[j_show];
    out->velocity_figure_t_s = v.t_s[f_show];
    const double interval =
        v.t_s.size() > 1 ? (v.t_s.back() - v.t_s.front()) / (v.t_s.size() - 1) : kNaN;
    if (!(std::abs(v.t_s[f_show] - t_show) <= 0.5 * interval + 1e-12))
      out->notes.push_back(fmt::format(
          "the velocity-field figure is drawn at t = {:.2f} ms, the stored frame nearest t_e = "
          "{:.2f} ms (the results store a preview of the frames; `run --outputs.frames all` "
          "stores every one)",
          1e3 * v.t_s[f_show], 1e3 * t_show));
    const cv::Mat& frame = images[j_show];
    VelocityOverlayOptions o;
    double vmax = 0;
    for (std::size_t i = 0; i < truth_seq.num_subsets; ++i) {
      const double s = std::hypot(truth_seq.vx_mm_s[f_show * truth_seq.num_subsets + i],
                                  truth_seq.vy_mm_s[f_show * truth_seq.num_subsets + i]);
      if (std::isfinite(s)) vmax = std::max(vmax, s);
    }
    o.max_speed_mm_s = vmax > 0 ? vmax : kNaN;
    o.min_width_px = 640;
    o.max_width_px = 640;
    // The renderers keep a reference to their sequence.
    const VelocityFieldSequence tool_one = OneFrame(tool_seq, f_show, v.t_s[f_show], frame);
    const VelocityFieldSequence truth_one = OneFrame(truth_seq, f_show, v.t_s[f_show], frame);
    const VelocityFieldRenderer a(tool_one, o), b(truth_one, o);
    const std::string when = fmt::format("t = {:.2f} ms", 1e3 * v.t_s[f_show]);
    cv::Mat left = a.RenderFrame(0, "impactdic DIC, " + when);
    cv::Mat right = b.RenderFrame(0, "DEM grains (cell means), " + when);
    cv::Mat both;
    cv::hconcat(left, right, both);
    // WriteImage: atomic, and a full disk is an error naming the file (cv::imwrite says nothing).
    WriteImage((fs::path(dir) / "velocity_field_compare.png").string(), both);
    // Small versions for the documentation: the upper part (where the soil moves), scaled.
    cv::Mat top = both(cv::Rect(0, 0, both.cols, both.rows * 3 / 5)), small;
    cv::resize(top, small, cv::Size(), 0.6, 0.6, cv::INTER_AREA);
    WriteImage((fs::path(dir) / "velocity_field_compare_small.png").string(), small,
               {cv::IMWRITE_PNG_COMPRESSION, 9});
    WriteImage((fs::path(dir) / "frame_small.png").string(),
               frame(cv::Rect(0, 0, frame.cols, frame.rows * 3 / 5)),
               {cv::IMWRITE_PNG_COMPRESSION, 9});
  }

  std::vector<double> t_ms, fine_ms, model_ms, sensor_ms, sensor_g, p_tot_tool, p_tot_truth;
  for (double x : v.t_s) t_ms.push_back(1e3 * x);
  for (double x : t.fine_t) fine_ms.push_back(1e3 * x);
  for (double x : model_t) model_ms.push_back(1e3 * x);
  for (std::size_t i = 0; i < v.t_s.size(); ++i) {
    p_tot_tool.push_back(v.p_pounder_tool_Ns[i] + v.p_gran_tool_Ns[i]);
    p_tot_truth.push_back(v.p_pounder_truth_Ns[i] + v.p_gran_truth_Ns[i]);
  }
  XyFigureData m;
  m.title = "Momentum: impactdic vs DEM grains (6 x 2 grid)";
  m.x_label = "time since contact [ms]";
  m.y_label = "momentum [N s]";
  m.series = {{t_ms, v.p_pounder_tool_Ns, "p_pounder (tool)", SeriesStyle::kLinesPoints},
              {t_ms, v.p_gran_tool_Ns, "p_gran (tool, DIC)", SeriesStyle::kLinesPoints},
              {t_ms, p_tot_tool, "p_total (tool)", SeriesStyle::kLinesPoints},
              {t_ms, v.p_pounder_truth_Ns, "p_pounder (DEM)", SeriesStyle::kLines},
              {t_ms, p_tot_truth, "p_total (DEM grains)", SeriesStyle::kLines}};
  if (!fine_ms.empty())
    m.series.push_back(
        {fine_ms, t.fine_p_gran, "p_gran (DEM grains, 25 kHz)", SeriesStyle::kLines});
  else
    m.series.push_back({t_ms, v.p_gran_truth_Ns, "p_gran (DEM grains)", SeriesStyle::kLines});
  m.legend = LegendPosition::kTopRight;
  PlotXy(m, (fs::path(dir) / "momentum_compare.png").string());

  for (std::size_t i = 0; i < t.sensor_t.size(); ++i)
    if (t.sensor_t[i] >= -0.001) {
      sensor_ms.push_back(1e3 * t.sensor_t[i]);
      sensor_g.push_back(t.sensor_g[i] - 1);
    }
  XyFigureData d;
  d.title = "Pounder deceleration: DEM vs Eq. 9 with the fitted M, b, T";
  d.x_label = "time since contact [ms]";
  d.y_label = "deceleration [g]";
  d.series = {{sensor_ms, sensor_g, "DEM pounder (25 kHz)", SeriesStyle::kLines}};
  if (!model_ms.empty())
    d.series.push_back({model_ms, model_g, "Eq. 9, fitted", SeriesStyle::kLines});
  PlotXy(d, (fs::path(dir) / "deceleration_compare.png").string());
}

DemFront FromWaveFront(const WaveFront& f) {
  DemFront d;
  d.speed_m_s = f.speed_m_s;
  d.ci_low_m_s = f.speed_ci_m_s[0];
  d.ci_high_m_s = f.speed_ci_m_s[1];
  d.intercept_s = f.intercept_s;
  d.rms_residual_s = f.rms_residual_s;
  d.fit_subsets = f.fit_subsets;
  d.problem = f.computed || !f.problem.empty() ? f.problem : "not computed by the run";
  return d;
}

// The front criterion (momentum/wave_front.h) on the grains' cells at the analysed frames
// `frame`, times since the contact (the impact at 0): their mean vertical velocity, or with
// `finite_difference` the central difference of their mean displacement (NaN at the record's
// ends). The panel: x from the pounder's axis, y from the surface (truth.h5 /camera), D of /dem.
DemFront GrainsFront(const H5Reader& truth, const TruthFile& t,
                     const std::vector<std::size_t>& frame, bool finite_difference) {
  const double axis_px = Attr(truth, "camera", "pounder_axis_x_px");
  const double surface_px = Attr(truth, "camera", "surface_y_px");
  const double sy = Attr(truth, "camera", "sy_mm_per_px");
  if (!std::isfinite(axis_px) || !std::isfinite(surface_px) || !std::isfinite(sy) ||
      !std::isfinite(t.sx) || t.frame_t.size() < 2 || t.pounder_z.size() != t.frame_t.size())
    return DemFront{.problem =
                        "truth.h5 lacks /camera pounder_axis_x_px, surface_y_px, "
                        "sx/sy_mm_per_px or the frames' pounder positions"};
  const std::size_t N = t.cells, F = frame.size(), T = t.frame_t.size();
  const double fps = 1 / (t.frame_t[1] - t.frame_t[0]);
  KinematicsResult k;
  k.frames = F;
  k.subsets = N;
  for (std::size_t c = 0; c < N; ++c) {
    k.x_mm.push_back((t.gx[c] - axis_px) * t.sx);
    k.y_mm.push_back((t.gy[c] - surface_px) * sy);
  }
  k.disp_y_mm.assign(F * N, kNaN);
  k.vel_y_mm_s.assign(F * N, kNaN);
  std::vector<double> time_s;
  for (std::size_t f = 0; f < F; ++f) {
    const std::size_t kf = frame[f];
    time_s.push_back(t.frame_t[kf]);
    for (std::size_t c = 0; c < N; ++c) {
      k.disp_y_mm[f * N + c] = t.v[kf * N + c] * sy;
      if (!finite_difference)
        k.vel_y_mm_s[f * N + c] = t.vy[kf * N + c];
      else if (kf >= 1 && kf + 1 < T)
        k.vel_y_mm_s[f * N + c] = (t.v[(kf + 1) * N + c] - t.v[(kf - 1) * N + c]) * sy * fps / 2;
    }
  }
  k.time_s = time_s;
  SensorResult sensor;
  sensor.summary.impact_time_s = 0;
  sensor.time_s = t.frame_t;
  sensor.penetration_m = t.pounder_z;
  sensor.summary.final_penetration_m = t.pounder_z.back();
  WaveFrontOptions o;
  o.pounder_center_x_mm = 0;
  o.surface_y_mm = 0;
  o.pounder_width_mm = 1e3 * t.width;
  return FromWaveFront(AnalyzeWaveFront(k, time_s, sensor, t.t_e, o));
}

// The wave figures of both files (DemWaveChannel); nothing without the truth's base_sensors/.
void CompareWave(const H5Reader& truth, const std::string& truth_h5, const H5Reader& res,
                 const std::string& results_h5, DemValidation* out) {
  if (truth.Exists("/p_wave")) {
    out->p_wave_speed_m_s = Scalar(truth, "p_wave/speed_m_s");
    out->p_wave_speed_sigma_m_s = Scalar(truth, "p_wave/speed_sigma_m_s");
    out->p_wave_speed_peak_m_s = Scalar(truth, "p_wave/speed_peak_m_s");
    out->p_wave_speed_peak_sigma_m_s = Scalar(truth, "p_wave/speed_peak_sigma_m_s");
  }
  if (!truth.Exists("/base_sensors")) return;
  if (!res.Exists("/wave")) {
    out->notes.push_back(results_h5 + " has no /wave: the run did not process the base channels");
    return;
  }
  std::vector<std::string> columns;
  {
    std::stringstream list(truth.ReadStringAttribute("base_sensors", "columns"));
    for (std::string name; std::getline(list, name, ',');) columns.push_back(name);
  }
  const WaveResult tool = ReadWaveResults(res, results_h5);
  out->front_tool = FromWaveFront(tool.front);
  out->pounder_peak_truth_s = Attr(truth, "base_sensors", "pounder_peak_s");
  out->pounder_peak_tool_s = tool.pounder_peak_s;
  out->pounder_peak_stress_truth_Pa = Attr(truth, "base_sensors", "pounder_peak_stress_Pa");
  out->pounder_peak_stress_tool_Pa = tool.pounder_peak_stress_pa;
  auto at = [](const std::vector<double>& v, std::size_t i) { return i < v.size() ? v[i] : kNaN; };
  const std::vector<double> distance = truth.ReadDouble("base_sensors/distance_mm");
  const std::vector<double> onset = truth.ReadDouble("base_sensors/onset_s");
  const std::vector<double> peak = truth.ReadDouble("base_sensors/peak_s");
  const std::vector<double> speed = truth.ReadDouble("base_sensors/speed_peak_m_s");
  const std::vector<double> ratio = truth.ReadDouble("base_sensors/stress_ratio");
  const std::vector<double> rise_10 = truth.ReadDouble("base_sensors/rise_10_s");
  const std::vector<double> rise_50 = truth.ReadDouble("base_sensors/rise_50_s");
  std::vector<double> travel;
  if (truth.Exists("/base_sensors/p_wave_travel_s"))
    travel = truth.ReadDouble("base_sensors/p_wave_travel_s");
  for (std::size_t k = 0; k < columns.size(); ++k) {
    DemWaveChannel c;
    c.column = columns[k];
    c.distance_mm = at(distance, k);
    c.onset_truth_s = at(onset, k);
    c.peak_truth_s = at(peak, k);
    c.speed_peak_truth_m_s = at(speed, k);
    c.stress_ratio_truth = at(ratio, k);
    c.rise_10_truth_s = at(rise_10, k);
    c.rise_50_truth_s = at(rise_50, k);
    c.p_wave_travel_s = at(travel, k);
    const auto it = std::find_if(tool.channels.begin(), tool.channels.end(),
                                 [&](const WaveChannel& w) { return w.column == columns[k]; });
    if (it == tool.channels.end()) {
      out->notes.push_back(
          fmt::format("{}: /wave has no channel '{}' of {}", results_h5, columns[k], truth_h5));
    } else {
      c.onset_tool_s = it->onset_s;
      c.peak_tool_s = it->peak_s;
      c.speed_peak_tool_m_s = it->speed_peak_m_s;
      c.speed_peak_sigma_m_s = it->speed_peak_sigma_m_s;
      c.speed_onset_tool_m_s = it->speed_onset_m_s;
      c.speed_onset_sigma_m_s = it->speed_onset_sigma_m_s;
      c.stress_ratio_tool = it->stress_ratio;
    }
    out->wave.push_back(c);
  }
}

}  // namespace

DemValidation ValidateDemRun(const std::string& truth_h5, const std::string& results_h5,
                             const std::string& figures_dir) {
  CheckFileKinds(truth_h5, results_h5);
  const TruthFile t = ReadTruth(truth_h5);
  H5Reader res(results_h5);
  DemValidation out;
  std::vector<double> index = res.ReadDouble(results_layout::kTimeFrameIndex);
  std::vector<std::size_t> frame;
  for (double k : index) {
    if (!(k >= 0) || static_cast<std::size_t>(k) >= t.frame_t.size())
      throw Error(ErrorKind::kInvalidValue, results_h5 + ": " + results_layout::kTimeFrameIndex,
                  fmt::format("{}", k),
                  fmt::format("frame indices of the {} truth frames", t.frame_t.size()));
    frame.push_back(static_cast<std::size_t>(k));
  }
  VelocityFieldSequence tool_seq, truth_seq;
  CompareDic(res, results_h5, t, frame, &out, &tool_seq, &truth_seq);
  CompareMomentum(ReadMomentumResults(res, results_h5), t, frame, &out);
  std::vector<double> model_t, model_g;
  CompareModel(t, &out, &model_t, &model_g);
  {
    const H5Reader truth(truth_h5);
    CompareWave(truth, truth_h5, res, results_h5, &out);
    if (!out.wave.empty()) {
      out.front_grains = GrainsFront(truth, t, frame, /*finite_difference=*/false);
      out.front_grains_fd = GrainsFront(truth, t, frame, /*finite_difference=*/true);
    }
  }
  if (!figures_dir.empty()) {
    // The frames `run` stored (render_results.h): all, a preview (/frames/row) or none.
    const VelocityFieldSequence stored = ReadVelocityFieldSequence(res, /*require_frames=*/false);
    std::vector<std::size_t> image_rows;
    if (!stored.frames.empty()) {
      if (res.Exists(results_layout::kFrameRows)) {
        for (double row : res.ReadDouble(results_layout::kFrameRows))
          image_rows.push_back(static_cast<std::size_t>(row));  // checked by the reader
      } else {
        for (std::size_t f = 0; f < frame.size(); ++f) image_rows.push_back(f);
      }
    }
    tool_seq.mm_per_px = truth_seq.mm_per_px = stored.mm_per_px;
    DrawFigures(t, &out, tool_seq, truth_seq, stored.frames, image_rows, model_t, model_g,
                figures_dir);
  }
  return out;
}

const std::vector<std::string>& DemValidationCsvColumns() {
  static const std::vector<std::string> kColumns = {
      "t_s",           "p_pounder_tool_Ns", "p_pounder_dem_Ns", "p_gran_tool_Ns",
      "p_gran_dem_Ns", "p_gran_dem_fd_Ns",  "v_sand_tool_m_s",  "v_sand_dem_m_s",
      "m_add_tool_kg", "m_add_dem_kg"};
  return kColumns;
}

const std::vector<std::string>& DemValidationWaveCsvColumns() {
  static const std::vector<std::string> kColumns = {"distance_mm",
                                                    "onset_tool_s",
                                                    "onset_dem_s",
                                                    "p_wave_travel_s",
                                                    "peak_tool_s",
                                                    "peak_dem_s",
                                                    "speed_peak_tool_m_s",
                                                    "speed_peak_sigma_m_s",
                                                    "speed_peak_dem_m_s",
                                                    "speed_onset_tool_m_s",
                                                    "speed_onset_sigma_m_s",
                                                    "p_wave_speed_m_s",
                                                    "p_wave_speed_sigma_m_s",
                                                    "stress_ratio_tool",
                                                    "stress_ratio_dem",
                                                    "front_speed_tool_m_s",
                                                    "front_speed_tool_ci_low_m_s",
                                                    "front_speed_tool_ci_high_m_s",
                                                    "front_speed_dem_m_s",
                                                    "front_speed_dem_ci_low_m_s",
                                                    "front_speed_dem_ci_high_m_s",
                                                    "front_speed_dem_fd_m_s",
                                                    "front_speed_dem_fd_ci_low_m_s",
                                                    "front_speed_dem_fd_ci_high_m_s"};
  return kColumns;
}

DemValidation ValidateDemFiles(const std::string& truth_h5, const std::string& results_h5,
                               const std::string& figures_dir, const std::string& csv_path,
                               const std::string& wave_csv_path) {
  for (const auto& [name, path] : {std::pair{"TRUTH", truth_h5}, {"RESULTS", results_h5}}) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
      throw Error(ErrorKind::kFileNotFound, name, path, "an existing HDF5 file");
  }
  // Before any work: the table is never written over an input (io/atomic_file.h).
  const std::vector<std::string>& columns = DemValidationCsvColumns();
  if (!csv_path.empty()) {
    CheckOutputLocation(csv_path,
                        {"--csv", {".csv"}, {truth_h5, results_h5}, {CsvHeaderLine(columns)}});
  }
  const std::vector<std::string>& wave_columns = DemValidationWaveCsvColumns();
  if (!wave_csv_path.empty()) {
    CheckOutputLocation(
        wave_csv_path,
        {"--wave-csv", {".csv"}, {truth_h5, results_h5, csv_path}, {CsvHeaderLine(wave_columns)}});
  }
  DemValidation v = ValidateDemRun(truth_h5, results_h5, figures_dir);
  if (!wave_csv_path.empty()) {
    std::vector<std::vector<double>> cols(wave_columns.size());
    for (const DemWaveChannel& c : v.wave) {
      const double row[] = {c.distance_mm,
                            c.onset_tool_s,
                            c.onset_truth_s,
                            c.p_wave_travel_s,
                            c.peak_tool_s,
                            c.peak_truth_s,
                            c.speed_peak_tool_m_s,
                            c.speed_peak_sigma_m_s,
                            c.speed_peak_truth_m_s,
                            c.speed_onset_tool_m_s,
                            c.speed_onset_sigma_m_s,
                            v.p_wave_speed_m_s,
                            v.p_wave_speed_sigma_m_s,
                            c.stress_ratio_tool,
                            c.stress_ratio_truth,
                            v.front_tool.speed_m_s,
                            v.front_tool.ci_low_m_s,
                            v.front_tool.ci_high_m_s,
                            v.front_grains.speed_m_s,
                            v.front_grains.ci_low_m_s,
                            v.front_grains.ci_high_m_s,
                            v.front_grains_fd.speed_m_s,
                            v.front_grains_fd.ci_low_m_s,
                            v.front_grains_fd.ci_high_m_s};
      for (std::size_t i = 0; i < cols.size(); ++i) cols[i].push_back(row[i]);
    }
    WriteCsv(wave_csv_path, wave_columns, cols, 8);
  }
  if (!csv_path.empty()) {
    WriteCsv(csv_path, columns,
             {v.t_s, v.p_pounder_tool_Ns, v.p_pounder_truth_Ns, v.p_gran_tool_Ns, v.p_gran_truth_Ns,
              v.p_gran_fd_truth_Ns, v.v_sand_tool_m_s, v.v_sand_truth_m_s, v.m_add_tool_kg,
              v.m_add_truth_kg},
             8);
  }
  return v;
}

std::string DemValidation::Report() const {
  auto pct = [](double x) { return fmt::format("{:.1f} %", 100 * x); };
  std::string r;
  r += "| quantity | impactdic | DEM truth (grains) |\n|---|---|---|\n";
  r += fmt::format(
      "| DIC velocity error, RMS over {} subset samples after contact [mm/s] | {:.1f} "
      "(vs central differences of the grains' displacement: {:.1f}) | max cell "
      "speed {:.0f} |\n",
      dic_samples, dic_velocity_rms_mm_s, dic_velocity_rms_fd_mm_s, truth_speed_max_mm_s);
  r += fmt::format("| DIC displacement error, RMS [px] | {:.3f} | |\n", dic_displacement_rms_px);
  r += fmt::format("| grid mass [kg] | {:.3f} (rho_d A t_z) | {:.3f} (sum of grain masses) |\n",
                   grid_mass_tool_kg, grid_mass_truth_kg);
  r += fmt::format("| p_max [N s] | {:.2f} | {:.2f} |\n", p_max_tool_Ns, p_max_truth_Ns);
  r += fmt::format("| t_e [ms] | {:.2f} | {:.2f} |\n", 1e3 * t_e_tool_s, 1e3 * t_e_truth_s);
  r += fmt::format(
      "| p_gran through the peak stage: max abs(tool - grains) | {:.2f} N s ({} of "
      "p_max); sum ratio tool/grains {:.3f} | |\n",
      p_gran_error_peak_Ns, pct(p_gran_error_peak_rel), p_gran_ratio_peak);
  r += fmt::format(
      "| p_gran through the peak stage: max abs(tool - perfect DIC) | {} of p_max | (perfect "
      "DIC: central differences of the grains' displacement) |\n",
      pct(p_gran_fd_error_peak_rel));
  r += fmt::format("| conservation error (Eq. 3) at t_e | {} | {} (max {} over the peak stage) |\n",
                   pct(conservation_tool), pct(conservation_truth), pct(conservation_truth_peak));
  r += fmt::format("| m_add,max [kg] | {:.2f} | {:.2f} |\n", m_add_max_tool_kg, m_add_max_truth_kg);
  r += fmt::format("| sigmoid fit M [kg], b [1/s], T [ms] | {:.3g}, {:.4g}, {:.3f} | |\n",
                   sigmoid_M_kg, sigmoid_b_per_s, 1e3 * sigmoid_T_s);
  r += fmt::format(
      "| peak deceleration [g] at [ms] | Eq. 9 fitted: {:.1f} at {:.2f} | {:.1f} at "
      "{:.2f} |\n",
      model_peak_decel_g, 1e3 * model_t_peak_s, dem_peak_decel_g, 1e3 * dem_t_peak_s);
  r += fmt::format("| deceleration RMS difference [g] | {:.1f} | |\n", decel_rms_g);
  r += fmt::format("| crater depth [mm] | Eq. 9 fitted: {:.1f} | {:.1f} (max penetration) |\n",
                   1e3 * model_crater_depth_m, 1e3 * dem_max_penetration_m);
  if (std::isfinite(p_wave_speed_m_s))
    r += fmt::format(
        "| P-wave speed of the settled bed [m/s] (pulse run: half-peak arrivals; peaks) | | "
        "{:.1f} +- {:.1f}; {:.1f} +- {:.1f} |\n",
        p_wave_speed_m_s, p_wave_speed_sigma_m_s, p_wave_speed_peak_m_s,
        p_wave_speed_peak_sigma_m_s);
  if (!wave.empty())
    r += fmt::format(
        "| pounder's peak stress m_p a_peak / (D t_z) [kPa] at [ms] | {:.1f} at {:.3f} | {:.1f} "
        "at {:.3f} |\n",
        1e-3 * pounder_peak_stress_tool_Pa, 1e3 * pounder_peak_tool_s,
        1e-3 * pounder_peak_stress_truth_Pa, 1e3 * pounder_peak_truth_s);
  for (const DemWaveChannel& c : wave) {
    r += fmt::format(
        "| {} (r = {:.0f} mm): wave speed from peaks [m/s] | {:.1f} +- {:.1f} | {:.1f} "
        "(noise-free floor force) |\n",
        c.column, c.distance_mm, c.speed_peak_tool_m_s, c.speed_peak_sigma_m_s,
        c.speed_peak_truth_m_s);
    r += fmt::format(
        "| {}: wave speed from onsets [m/s] | {:.1f} +- {:.1f} | P-wave {:.1f} +- {:.1f} |\n",
        c.column, c.speed_onset_tool_m_s, c.speed_onset_sigma_m_s, p_wave_speed_m_s,
        p_wave_speed_sigma_m_s);
    r += fmt::format(
        "| {}: arrival onset, peak [ms] | {:.3f}, {:.3f} | {:.3f}, {:.3f} (rise 10 % {:.3f}, "
        "50 % {:.3f}; r / P-wave speed {:.3f}) |\n",
        c.column, 1e3 * c.onset_tool_s, 1e3 * c.peak_tool_s, 1e3 * c.onset_truth_s,
        1e3 * c.peak_truth_s, 1e3 * c.rise_10_truth_s, 1e3 * c.rise_50_truth_s,
        1e3 * c.p_wave_travel_s);
    r += fmt::format("| {}: stress ratio | {:.4f} | {:.4f} |\n", c.column, c.stress_ratio_tool,
                     c.stress_ratio_truth);
  }
  if (!wave.empty()) {
    auto front = [](const DemFront& f) {
      if (!f.problem.empty()) return "not measured: " + f.problem;
      return fmt::format("{:.1f} [{:.1f}, {:.1f}] ({} subsets, intercept {:.3f} ms)", f.speed_m_s,
                         f.ci_low_m_s, f.ci_high_m_s, f.fit_subsets, 1e3 * f.intercept_s);
    };
    r += fmt::format(
        "| front in the DIC field: speed [m/s] [95 % interval] | {} | the grains' velocity: {}; "
        "central differences of their displacement (a perfect DIC): {}; P-wave {:.1f} +- {:.1f} "
        "|\n",
        front(front_tool), front(front_grains), front(front_grains_fd), p_wave_speed_m_s,
        p_wave_speed_sigma_m_s);
  }
  for (const auto& n : notes) r += "note: " + n + "\n";
  return r;
}

}  // namespace impactdic
