#include "impactdic/pipeline/pipeline.h"

#include <fmt/format.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <vector>

#include "impactdic/calib/calibration.h"
#include "impactdic/core/error.h"
#include "impactdic/core/interrupt.h"
#include "impactdic/core/log.h"
#include "impactdic/core/progress.h"
#include "impactdic/core/threads.h"
#include "impactdic/core/timer.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/image_io.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/kinematics/kinematics.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/momentum/momentum.h"
#include "impactdic/momentum/scene_analysis.h"
#include "impactdic/preprocess/preprocess.h"
#include "impactdic/render/gnuplot.h"
#include "impactdic/render/render_results.h"
#include "impactdic/render/results_layout.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {
namespace fs = std::filesystem;
namespace layout = results_layout;
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Records a stage's outcome and its time, and logs it.
class StageLog {
 public:
  explicit StageLog(PipelineSummary* summary) : summary_(summary) {}
  void Ran(const std::string& name, const std::string& note, const WallTimer& timer) {
    summary_->stages.push_back({name, true, note, timer.ElapsedSeconds()});
    LogInfo("[{}] {} ({:.2f} s)", name, note, timer.ElapsedSeconds());
  }
  void Skipped(const std::string& name, const std::string& why) {
    summary_->stages.push_back({name, false, why, 0});
    LogInfo("[{}] skipped: {}", name, why);
  }

 private:
  PipelineSummary* summary_;
};

// The frames of the scene: the sorted image files, or the frames of a video.
struct FrameSource {
  std::vector<std::string> files;     // Empty for a video.
  std::vector<cv::Mat> video;         // Decoded video frames.
  std::vector<std::string> warnings;  // A truncated video, a colour image in a grey sequence.
  SequenceColourCheck colour;         // Image files, in the order read.
  int count() const {
    return files.empty() ? static_cast<int>(video.size()) : static_cast<int>(files.size());
  }
  std::string Name(int k) const {
    return files.empty() ? fmt::format("video frame {}", k) : files[static_cast<std::size_t>(k)];
  }
  cv::Mat Read(int k) {
    if (files.empty()) return video[static_cast<std::size_t>(k)];
    const std::string& path = files[static_cast<std::size_t>(k)];
    int channels = 1;
    cv::Mat image = ReadGreyImage(path, &channels);
    const std::string warning = colour.Check(path, channels);
    if (!warning.empty()) warnings.push_back(warning);
    return image;
  }
};

FrameSource OpenFrames(const std::string& source) {
  FrameSource frames;
  if (IsVideoFile(source)) {
    std::string warning;
    frames.video = ReadVideoFrames(source, /*max_frames=*/0, &warning);
    if (!warning.empty()) frames.warnings.push_back(warning);
  } else {
    frames.files = ListFrameSequence(source);  // A gap in the numbering is an error.
  }
  return frames;
}

// dic.first_frame and dic.last_frame against the n frames of the source: Error naming the key,
// its value and the allowed range.
void CheckFrameRange(const Scene& scene, int n) {
  const int last = scene.dic.last_frame < 0 ? n - 1 : scene.dic.last_frame;
  if (last >= n) {
    throw Error(ErrorKind::kInvalidValue, "dic.last_frame", std::to_string(last),
                fmt::format("< the number of frames ({}) in {}", n, scene.inputs.frames))
        .WithFile(scene.path);
  }
  const int first = scene.dic.first_frame;
  if (first > 0 && last - first < 2) {
    throw Error(ErrorKind::kInvalidValue, "dic.first_frame", std::to_string(first),
                fmt::format("a frame index <= {}: {} holds {} frames (0..{}){}, and at least 3 "
                            "from dic.first_frame on are correlated",
                            std::max(0, last - 2), scene.inputs.frames, n, n - 1,
                            scene.dic.last_frame < 0
                                ? ""
                                : fmt::format(", dic.last_frame is {}", scene.dic.last_frame)))
        .WithFile(scene.path);
  }
}

// dic.roi against the frame size: the correlator needs it inside the frame. Error naming the key,
// its value and the frame size.
void CheckSceneRoi(const Scene& scene, cv::Size frame) {
  const auto& r = scene.dic.roi;
  if (!(r[2] > r[0] && r[3] > r[1])) return;  // Not set: the whole frame.
  if (r[2] <= frame.width && r[3] <= frame.height) return;
  throw Error(
      ErrorKind::kInvalidValue, "dic.roi",
      fmt::format("[{}, {}, {}, {}]{}", r[0], r[1], r[2], r[3],
                  r[0] >= frame.width || r[1] >= frame.height ? ", entirely outside the frames"
                                                              : ", partly outside the frames"),
      fmt::format("a rectangle [x0, y0, x1, y1] inside the {}x{} frames (x1 <= {}, "
                  "y1 <= {})",
                  frame.width, frame.height, frame.width, frame.height))
      .WithFile(scene.path);
}

std::vector<cv::Point> PolygonPoints(const std::vector<std::array<double, 2>>& vertices) {
  std::vector<cv::Point> points;
  for (const auto& v : vertices)
    points.emplace_back(static_cast<int>(std::lround(v[0])), static_cast<int>(std::lround(v[1])));
  return points;
}

// The correlator's mask from the scene's polygon and mask image (empty if neither is given):
// non-zero where subsets may be centred.
cv::Mat SceneMask(const Scene& scene, cv::Size frame_size) {
  const SceneDic& d = scene.dic;
  cv::Mat mask;
  if (!d.mask.empty()) {
    const cv::Mat image = ReadGreyImage(d.mask);
    if (image.size() != frame_size) {
      throw Error(ErrorKind::kInvalidValue, "dic.mask",
                  fmt::format("a {}x{} image", image.cols, image.rows),
                  fmt::format("a mask of the frames' size {}x{} (non-zero = correlate)",
                              frame_size.width, frame_size.height))
          .WithFile(d.mask);
    }
    mask = image != 0;
  }
  if (!d.roi_polygon.empty()) {
    cv::Mat inside = cv::Mat::zeros(frame_size, CV_8U);
    cv::fillPoly(inside, std::vector<std::vector<cv::Point>>{PolygonPoints(d.roi_polygon)},
                 cv::Scalar(255));
    if (cv::countNonZero(inside) == 0) {
      throw Error(
          ErrorKind::kInvalidValue, "dic.roi_polygon", "a polygon outside the frames",
          fmt::format("vertices inside the {}x{} frames", frame_size.width, frame_size.height))
          .WithFile(scene.path);
    }
    mask = mask.empty() ? inside : (mask & inside);
  }
  return mask;
}

// The correlation series the kinematics and momentum use: without the samples above the scene's
// momentum.max_sigma_px (if set; counted in a warning). /dic keeps them.
CorrelationSeries AnalysedSeries(const CorrelationSeries& series, const Scene& scene,
                                 std::vector<std::string>* warnings) {
  CorrelationSeries s = series;
  if (scene.momentum.max_sigma_px) {
    const std::size_t n =
        ExcludeUncertainSamples(*scene.momentum.max_sigma_px, "momentum.max_sigma_px", &s);
    warnings->push_back(
        fmt::format("kinematics: {} of {} subset samples left out (sigma_u or sigma_v > "
                    "momentum.max_sigma_px = {} px)",
                    n, s.frames * s.subsets, *scene.momentum.max_sigma_px));
  }
  return s;
}

}  // namespace

DicOptions MakeDicOptions(const SceneDic& d) {
  DicOptions o;
  o.grid.subset_size = d.subset_size;
  o.grid.step = d.step;
  if (d.roi[2] > d.roi[0] && d.roi[3] > d.roi[1]) {
    o.grid.roi = cv::Rect(d.roi[0], d.roi[1], d.roi[2] - d.roi[0], d.roi[3] - d.roi[1]);
  }
  if (!d.roi_polygon.empty()) {
    // The grid covers the polygon's bounding box (within `roi`); SceneMask leaves out the
    // subsets whose centre is outside the polygon.
    const cv::Rect box = cv::boundingRect(PolygonPoints(d.roi_polygon));
    if (o.grid.roi.area() > 0 && (o.grid.roi & box).area() == 0) {
      throw Error(ErrorKind::kInvalidValue, "dic.roi_polygon", "a polygon outside dic.roi",
                  "a polygon that overlaps dic.roi (or no dic.roi)");
    }
    o.grid.roi = o.grid.roi.area() > 0 ? (o.grid.roi & box) : box;
  }
  o.icgn.interpolation = InterpolationFromString(d.interpolation);
  o.icgn.shape = ShapeFunctionFromString(d.shape);
  o.icgn.min_zncc = d.min_zncc;
  o.icgn.max_iterations = d.max_iterations;
  o.icgn.convergence_px = d.convergence_px;
  if (d.max_uncertainty_px) o.icgn.max_uncertainty_px = *d.max_uncertainty_px;
  o.init.search_radius_px = d.search_radius_px;
  o.update.mode = ReferenceUpdateFromString(d.reference_update, &o.update.every_n);
  o.Check();
  return o;
}

namespace {

ImpactModelParameters MakeModelParameters(const Scene& scene, double impact_velocity_m_s) {
  ImpactModelParameters p;
  p.pounder_mass_kg = scene.test.mass_kg;
  p.impact_velocity_m_s = impact_velocity_m_s;
  p.width_m = scene.test.width_m;
  p.depth_m = scene.test.depth_m;
  p.added_mass_kg = scene.model.added_mass_kg ? *scene.model.added_mass_kg : kNaN;
  p.friction_K = scene.model.K;
  p.damping_exponent_n = scene.model.n;
  p.damping_factor_u = scene.model.u;
  p.sigmoid_delay_T_s = scene.model.T_s;
  p.sigmoid_rate_b_per_s = scene.model.b_per_s;
  p.density_kg_m3 = scene.test.density_kg_m3;
  p.gravity_m_s2 = scene.test.g_m_s2;
  p.bed_height_m = scene.test.bed_height_m;
  p.Check();
  return p;
}

// Mean deceleration [g] of the sensor record over [impact + t1, stop]: the measured counterpart of
// the model's plateau deceleration v(t1) / (t_end - t1) / g.
double MeasuredPlateau(const SensorResult& sensor, double t1_after_impact_s, double g) {
  const SensorSummary& s = sensor.summary;
  if (!std::isfinite(s.impact_time_s) || !std::isfinite(s.stop_time_s)) return kNaN;
  const double t1 = s.impact_time_s + t1_after_impact_s;
  if (!(s.stop_time_s > t1)) return kNaN;
  const std::vector<double> v =
      SampleSeries(sensor.time_s, sensor.velocity_m_s, {t1, s.stop_time_s}, "sensor velocity");
  return (v[0] - v[1]) / (s.stop_time_s - t1) / g;
}

// Measured peak deceleration: the largest filtered deceleration of the PEAK STAGE, between the
// impact and t_e (t_end_peak_s; NaN: up to T + 4/b of the scene's model instead, with a warning
// when the momentum stage ran but could not measure t_e). The record's global maximum can be the
// stop, where -dv/dt grows like v^-n (docs/model.md).
double MeasuredPeakDeceleration(const SensorResult& sensor, double t_end_peak_s,
                                const SceneModel& model, bool momentum_ran,
                                std::vector<std::string>* warnings) {
  double window_s = t_end_peak_s;
  if (!std::isfinite(window_s)) {
    window_s = model.T_s + 4 / model.b_per_s;
    if (momentum_ran) {
      warnings->push_back(fmt::format(
          "peak deceleration (measured): t_e was not measured, so the peak stage is taken as the "
          "first T + 4/b = {:.3f} ms after the impact (the scene's model)",
          1e3 * window_s));
    }
  }
  const double t_i = sensor.summary.impact_time_s;
  double peak = kNaN;
  for (std::size_t i = 0; i < sensor.time_s.size(); ++i) {
    const double dt = sensor.time_s[i] - t_i;
    if (dt >= 0 && dt <= window_s && !(sensor.accel_g[i] - 1 <= peak)) peak = sensor.accel_g[i] - 1;
  }
  return peak;
}

// Why the correlation produced nothing usable ("" if it did): no valid subset in any frame.
std::string CorrelationProblem(const DicSummary& s, double min_zncc) {
  if (s.frames == 0 || s.valid_fraction > 0) return "";
  std::size_t most = 0;
  long long total = 0;
  for (std::size_t i = 0; i < s.status_counts.size(); ++i) {
    total += s.status_counts[i];
    if (s.status_counts[i] > s.status_counts[most]) most = i;
  }
  return fmt::format(
      "no valid subset in any of the {} frames after the reference ({} subsets; most common "
      "status: {} in {} of {} results; dic.min_zncc = {})",
      s.frames, s.subsets, ToString(static_cast<SubsetStatus>(most)), s.status_counts[most], total,
      min_zncc);
}

// Throws when a stage produced nothing usable, unless the options allow a partial run.
void ThrowIfFailed(const PipelineSummary& summary, const PipelineOptions& options) {
  if (summary.failures.empty() || options.allow_partial) return;
  std::string stages;
  for (const StageFailure& f : summary.failures)
    stages += fmt::format("\n  {}: {}", f.stage, f.reason);
  throw Error(ErrorKind::kNumerical,
              fmt::format("scene {}: {} stage(s) produced nothing usable:{}\nNo output was "
                          "written (outputs of an earlier run in {} are kept); `impactdic run "
                          "--allow-partial` writes them, with the figures that could not be "
                          "measured as null and the reasons in summary.json",
                          summary.scene_name, summary.failures.size(), stages,
                          OutputPathForMessages(summary.output_folder)));
}

std::vector<float> ToFloat(const std::vector<double>& v) { return {v.begin(), v.end()}; }

// A run's outputs are one generation of its output folder (io/output_generation.h): written into
// a staging folder beside it and swapped in when all are complete.
OutputGenerationOptions RunGenerationOptions() {
  OutputGenerationOptions o;
  o.command = "impactdic run";
  for (const char* name : layout::kRunOnlyOutputNames) o.own_names.emplace_back(name);
  for (const char* name : layout::kRenderOutputNames) o.own_names.emplace_back(name);
  return o;
}

}  // namespace

void CheckOutputFolderHoldsNoInput(const Scene& scene, const std::string& folder,
                                   const std::string& option) {
  std::error_code ec;
  const fs::path out = fs::weakly_canonical(fs::absolute(folder, ec), ec);
  // A glob's folder is the input (its files may be written later); a video or a folder is itself.
  std::string frames = scene.inputs.frames;
  if (frames.find_first_of("*?[") != std::string::npos)
    frames = fs::path(frames).parent_path().string();
  for (const std::string& input : {scene.path, frames, scene.inputs.calibration,
                                   scene.inputs.sensor, scene.inputs.truth, scene.dic.mask}) {
    if (input.empty()) continue;
    const fs::path in = fs::weakly_canonical(fs::absolute(input, ec), ec);
    if (!IsSameOrInside(in.string(), out.string())) continue;
    throw Error(
        ErrorKind::kInvalidValue, option,
        OutputPathForMessages(folder) + ", which holds the input " + input,
        "an output folder apart from the inputs (what was written there before is replaced)")
        .WithFile(scene.path);
  }
}

void PipelineOptions::Check() const {
  CheckValue(threads == -1 || IsValidThreadCount(threads), "threads", std::to_string(threads),
             std::string("-1 (the scene's dic.threads) or ") + kThreadCountExpected);
}

JsonObject SceneFigures::ToJson() const {
  JsonObject j;
  const auto names = CsvNames();
  const auto values = CsvValues();
  for (std::size_t i = 0; i < names.size(); ++i) j.Add(names[i], values[i]);
  return j;
}

std::vector<std::string> SceneFigures::CsvNames() const {
  return {"impact_velocity_m_s",
          "p_max_kg_m_s",
          "t_end_peak_s",
          "momentum_conservation_error",
          "added_mass_max_kg",
          "added_mass_eq4_kg",
          "sigmoid_M_kg",
          "sigmoid_b_per_s",
          "sigmoid_T_s",
          "momentum_ratio_measured",
          "momentum_ratio_model",
          "v_sand_max_m_s",
          "peak_deceleration_measured_g",
          "peak_deceleration_model_g",
          "plateau_deceleration_measured_g",
          "plateau_deceleration_model_g",
          "crater_depth_measured_m",
          "crater_depth_model_m",
          "t_end_model_s",
          "dic_valid_fraction",
          "dic_subsets_per_s"};
}

std::vector<double> SceneFigures::CsvValues() const {
  return {impact_velocity_m_s,
          p_max_kg_m_s,
          t_end_peak_s,
          momentum_conservation_error,
          added_mass_max_kg,
          added_mass_eq4_kg,
          sigmoid_M_kg,
          sigmoid_b_per_s,
          sigmoid_T_s,
          momentum_ratio_measured,
          momentum_ratio_model,
          v_sand_max_m_s,
          peak_deceleration_measured_g,
          peak_deceleration_model_g,
          plateau_deceleration_measured_g,
          plateau_deceleration_model_g,
          crater_depth_measured_m,
          crater_depth_model_m,
          t_end_model_s,
          dic_valid_fraction,
          dic_subsets_per_s};
}

std::string PipelineSummary::FailureText() const {
  std::string text;
  for (const StageFailure& f : failures)
    text += (text.empty() ? "" : "; ") + f.stage + ": " + f.reason;
  return text;
}

std::string PipelineSummary::BriefReport() const {
  return fmt::format(
             "{}: conservation error {:.2f} %, m_add,max {:.3f} kg (Eq. 4: {:.3f} kg), crater "
             "depth {:.2f} mm measured / {:.2f} mm model, {:.1f} s",
             scene_name, 100 * figures.momentum_conservation_error, figures.added_mass_max_kg,
             figures.added_mass_eq4_kg, 1e3 * figures.crater_depth_measured_m,
             1e3 * figures.crater_depth_model_m, seconds) +
         (failures.empty() ? "" : "; PARTIAL: " + FailureText());
}

JsonObject PipelineSummary::ToJson() const {
  JsonObject j = figures.ToJson();
  JsonObject failed;
  for (const StageFailure& f : failures) failed.Add(f.stage, f.reason);
  j.Add("usable", IsUsable()).Add("failures", failed).Add("warnings", warnings);
  return j;
}

std::string PipelineSummary::FullReport() const {
  std::string text = fmt::format("Scene {} -> {}\n", scene_name, output_folder);
  for (const auto& s : stages) {
    text += fmt::format("  {:<11} {} {}\n", s.name,
                        s.ran ? fmt::format("{:6.2f} s", s.seconds) : " skipped", s.note);
  }
  for (const StageFailure& f : failures)
    text += fmt::format("  FAILED {}: {} (its figures are null)\n", f.stage, f.reason);
  text += "Key figures (measured / model):\n";
  const auto names = figures.CsvNames();
  const auto values = figures.CsvValues();
  for (std::size_t i = 0; i < names.size(); ++i)
    text += fmt::format("  {:<32} {:.6g}\n", names[i], values[i]);
  for (const auto& w : warnings) text += "  warning: " + w + "\n";
  text += "Outputs:\n";
  for (const auto& o : outputs) text += "  " + o + "\n";
  return text;
}

namespace {

PipelineSummary RunStages(const Scene& scene, const PipelineOptions& options) {
  WallTimer total;
  PipelineSummary summary;
  summary.scene_name = scene.name;
  summary.output_folder =
      options.output_folder.empty() ? scene.outputs.folder : options.output_folder;
  StageLog stages(&summary);
  SceneFigures& fig = summary.figures;
  const bool want_outputs = scene.HasStage("outputs");
  std::optional<OutputGeneration> generation;  // Removed again unless committed at the end.
  if (want_outputs) {
    generation.emplace(summary.output_folder, RunGenerationOptions());
    // Figures need gnuplot: find out now, not after the whole run.
    if (scene.outputs.figures) DetectPngTerminal(ResolveGnuplotBinary(PlotOptions{}));
  }

  // --- calibration ---------------------------------------------------------------------------
  std::optional<CameraCalibration> calibration;
  double mm_per_px = scene.inputs.mm_per_px;
  {
    WallTimer t;
    if (!scene.inputs.calibration.empty() && scene.HasStage("calibrate")) {
      calibration = LoadCalibration(scene.inputs.calibration);
      std::string note =
          fmt::format("{} (RMS {:.3f} px)", scene.inputs.calibration, calibration->rms_px);
      if (mm_per_px <= 0) {
        if (!calibration->plane) {
          throw Error(ErrorKind::kInvalidValue, "inputs.mm_per_px",
                      "0 and the calibration has no plane scale",
                      "a scale > 0 [mm/px] or a calibration made with --plane")
              .WithFile(scene.path);
        }
        mm_per_px = calibration->plane->mm_per_px;
        note += fmt::format(", plane scale {:.5f} +- {:.5f} mm/px", mm_per_px,
                            calibration->plane->mm_per_px_uncertainty);
      } else {
        note += fmt::format(", scale {:.5f} mm/px from the scene", mm_per_px);
      }
      stages.Ran("calibrate", note, t);
    } else {
      stages.Skipped("calibrate", scene.inputs.calibration.empty()
                                      ? "no calibration file in the scene"
                                      : "not among the scene's stages");
    }
  }

  // --- sensor (first: it tells where the impact is, so no frame before it is correlated) -------
  std::optional<SensorResult> sensor;
  if (!scene.inputs.sensor.empty() && scene.HasStage("sensor")) {
    WallTimer t;
    sensor = AnalyzeSensorCsv(scene.inputs.sensor, SensorOptionsFromScene(scene));
    for (const auto& w : sensor->summary.warnings) summary.warnings.push_back("sensor: " + w);
    stages.Ran("sensor", sensor->summary.BriefReport(), t);
    fig.impact_velocity_m_s = sensor->summary.impact_velocity_m_s;
    fig.crater_depth_measured_m = sensor->summary.final_penetration_m;
  } else {
    stages.Skipped("sensor", scene.inputs.sensor.empty() ? "no sensor CSV in the scene"
                                                         : "not among the scene's stages");
  }

  // --- frames --------------------------------------------------------------------------------
  const bool need_frames = scene.HasStage("correlate");
  FrameSource source;
  std::vector<double> frame_times_all;  // DAQ clock, all frames of the source.
  int first = scene.dic.first_frame, last = -1;
  std::vector<cv::Mat> frames;  // Preprocessed frames first..last.
  std::string preprocess_note;
  if (need_frames) {
    WallTimer t;
    source = OpenFrames(scene.inputs.frames);
    const int n = source.count();
    CheckFrameRange(scene, n);
    last = scene.dic.last_frame < 0 ? n - 1 : scene.dic.last_frame;
    std::string skipped_note;
    if (sensor) {
      std::size_t edges = 0;  // Exposure edges in the record.
      try {
        frame_times_all =
            FrameTimes(*sensor, n, scene.inputs.fps, scene.sensor.frame_time_offset_s, &edges);
      } catch (Error& e) {  // e.g. a record that ends before the last frame: name the file.
        if (e.file().empty()) e.WithFile(scene.inputs.sensor);
        throw;
      }
      if (edges > static_cast<std::size_t>(n)) {
        const std::string w = fmt::format(
            "{} exposure edges in {} for {} frames: frame k is timed by edge k, the last {} "
            "edge(s) are unused; if frames are missing from the sequence, every later frame "
            "time is wrong",
            edges, scene.inputs.sensor, n, edges - static_cast<std::size_t>(n));
        LogWarning("{}", w);
        summary.warnings.push_back("sensor: " + w);
      }
      if (scene.dic.first_frame == 0) {
        // The reference is the last frame exposed before the impact: nothing earlier moves.
        const double t_impact = sensor->summary.impact_time_s;
        int ref = 0;
        for (int k = 0; k < n; ++k)
          if (frame_times_all[static_cast<std::size_t>(k)] <= t_impact) ref = k;
        first = ref;
        if (first > 0)
          skipped_note =
              fmt::format("; frames 0..{} before the impact are not correlated", first - 1);
      }
    }
    if (last - first < 2) {
      throw Error(
          ErrorKind::kInvalidValue, "frames",
          fmt::format("{} frames from {} to {}", std::max(0, last - first + 1), first, last),
          "at least 3 frames to correlate and differentiate")
          .WithFile(scene.inputs.frames);
    }
    PreprocessOptions pre_options;
    pre_options.gaussian.enabled = scene.preprocess.gaussian;
    pre_options.gaussian.sigma_px = scene.preprocess.gaussian_sigma;
    pre_options.gaussian.kernel_size = scene.preprocess.gaussian_kernel;
    pre_options.clahe.enabled = scene.preprocess.clahe;
    pre_options.clahe.clip_limit = scene.preprocess.clahe_clip_limit;
    pre_options.clahe.tile_grid = scene.preprocess.clahe_tile_grid;
    const DicOptions probe = MakeDicOptions(scene.dic);
    pre_options.undistortion.roi = probe.grid.roi;
    std::vector<std::string> names;
    std::optional<Preprocessor> pre;
    ProgressBar bar("frames", static_cast<std::size_t>(last - first + 1));
    for (int k = first; k <= last; ++k) {
      cv::Mat image = source.Read(k);
      if (frames.empty()) {
        CheckSceneRoi(scene, image.size());
        if (calibration) CheckFrameSize(*calibration, image.size(), source.Name(k));
        pre.emplace(pre_options, calibration ? &*calibration : nullptr, image.size());
      }
      names.push_back(source.Name(k));
      frames.push_back(image);
      CheckSameSize({frames.front(), image}, {names.front(), names.back()});
      frames.back() = pre->Apply(image);
      bar.Advance();
    }
    bar.Finish();
    for (const auto& w : source.warnings) summary.warnings.push_back("frames: " + w);
    preprocess_note = pre->summary().BriefReport();
    stages.Ran("frames",
               fmt::format("{} of {} frames ({}x{}, {}-bit){}; {}", frames.size(), n,
                           frames[0].cols, frames[0].rows, frames[0].depth() == CV_16U ? 16 : 8,
                           skipped_note, preprocess_note),
               t);
  } else {
    stages.Skipped("frames", "no correlation among the scene's stages");
  }

  // --- correlate -----------------------------------------------------------------------------
  std::optional<DicResult> dic;
  if (need_frames) {
    WallTimer t;
    DicOptions dic_options = MakeDicOptions(scene.dic);
    dic_options.grid.mask = SceneMask(scene, frames[0].size());
    const int threads = options.threads >= 0 ? options.threads : scene.dic.threads;
    std::optional<tbb::global_control> limit;
    if (threads > 0)
      limit.emplace(tbb::global_control::max_allowed_parallelism,
                    static_cast<std::size_t>(threads));
    dic = CorrelateSequence(frames, dic_options);
    fig.dic_valid_fraction = dic->summary.valid_fraction;
    fig.dic_subsets_per_s = dic->summary.SubsetsPerSecond();
    if (!dic->summary.IsUsable()) {
      summary.warnings.push_back(fmt::format("correlation: only {:.1f} % of the subsets are valid",
                                             100 * dic->summary.valid_fraction));
    }
    const std::string problem = CorrelationProblem(dic->summary, scene.dic.min_zncc);
    if (!problem.empty()) summary.failures.push_back({"correlate", problem});
    stages.Ran("correlate", dic->summary.BriefReport(), t);
  } else {
    stages.Skipped("correlate", "not among the scene's stages");
  }

  // --- kinematics + momentum -----------------------------------------------------------------
  std::optional<SceneAnalysis> analysis;
  std::optional<KinematicsResult> kinematics_only;  // Kinematics without momentum (no sensor).
  CorrelationSeries series;
  if (dic) {
    const std::size_t F = dic->frames.size() + 1, N = dic->positions.size();
    series.frames = F;
    series.subsets = N;
    for (const auto& p : dic->positions) {
      series.x_px.push_back(p.x);
      series.y_px.push_back(p.y);
    }
    series.u_px.assign(F * N, 0.0);
    series.v_px.assign(F * N, 0.0);
    series.valid.assign(F * N, 1);
    series.sigma_u_px.assign(F * N, 0.0f);
    series.sigma_v_px.assign(F * N, 0.0f);
    for (std::size_t f = 1; f < F; ++f) {
      const FrameResult& r = dic->frames[f - 1];
      for (std::size_t i = 0; i < N; ++i) {
        series.u_px[f * N + i] = r.u_px[i];
        series.v_px[f * N + i] = r.v_px[i];
        series.sigma_u_px[f * N + i] = r.sigma_u_px[i];
        series.sigma_v_px[f * N + i] = r.sigma_v_px[i];
        series.valid[f * N + i] = r.status[i] == SubsetStatus::kConverged ? 1 : 0;
      }
    }
    // The reference frame is valid for every subset the reference itself allows.
    for (std::size_t i = 0; i < N; ++i) {
      const SubsetStatus s = dic->frames[0].status[i];
      const bool reference_side = s == SubsetStatus::kMasked ||
                                  s == SubsetStatus::kSingularHessian ||
                                  s == SubsetStatus::kLowContrast || s == SubsetStatus::kSaturated;
      series.valid[i] = reference_side ? 0 : 1;
      if (reference_side) series.u_px[i] = series.v_px[i] = kNaN;
    }
  }
  if (dic && scene.HasStage("kinematics")) {
    if (!(mm_per_px > 0)) {
      throw Error(ErrorKind::kInvalidValue, "inputs.mm_per_px", "no scale",
                  "inputs.mm_per_px > 0 or a calibration with a plane scale")
          .WithFile(scene.path);
    }
    PanelMapping mapping;
    mapping.mm_per_px = mm_per_px;
    const CorrelationSeries analysed = AnalysedSeries(series, scene, &summary.warnings);
    if (sensor && scene.HasStage("momentum")) {
      WallTimer t;
      const MomentumOptions m = MomentumOptionsFromScene(scene, mm_per_px);
      // Frame times on the DAQ clock of the analysed frames (exposure edges, or the scene's offset
      // + k / fps when the record has no exposure channel).
      KinematicsOptions k;
      k.fps = scene.inputs.fps;
      analysis.emplace();
      analysis->frame_time_s.assign(frame_times_all.begin() + first,
                                    frame_times_all.begin() + last + 1);
      analysis->kinematics = ComputeKinematics(analysed, mapping, k);
      analysis->momentum =
          AnalyzeMomentum(analysis->kinematics, analysis->frame_time_s, *sensor, m);
      const MomentumSummary& ms = analysis->momentum.summary;
      for (const auto& w : ms.warnings) summary.warnings.push_back("momentum: " + w);
      fig.p_max_kg_m_s = ms.p_max_kg_m_s;
      fig.t_end_peak_s = ms.t_end_peak_s;
      fig.momentum_conservation_error = ms.momentum_conservation_error;
      fig.added_mass_max_kg = ms.added_mass_max_kg;
      fig.v_sand_max_m_s = ms.v_sand_max_m_s;
      fig.momentum_ratio_measured = ms.momentum_ratio;
      if (ms.sigmoid_fitted) {
        fig.sigmoid_M_kg = ms.sigmoid.M_kg;
        fig.sigmoid_b_per_s = ms.sigmoid.b_per_s;
        fig.sigmoid_T_s = ms.sigmoid.T_s;
      }
      if (!ms.IsUsable())
        summary.failures.push_back({"momentum", "t_e is not measurable: " + ms.t_end_problem});
      stages.Ran("kinematics", analysis->kinematics.summary.BriefReport(), t);
      stages.Ran("momentum", ms.BriefReport(), t);
    } else {
      // The fields alone (frame times k / fps).
      WallTimer t;
      KinematicsOptions k;
      k.fps = scene.inputs.fps;
      kinematics_only = ComputeKinematics(analysed, mapping, k);
      stages.Ran("kinematics", kinematics_only->summary.BriefReport(), t);
      stages.Skipped("momentum", sensor ? "not among the scene's stages"
                                        : "needs the sensor record (pounder velocity)");
    }
  } else {
    stages.Skipped("kinematics", dic ? "not among the scene's stages" : "no correlation results");
    if (!analysis) stages.Skipped("momentum", "no kinematics");
  }

  if (sensor) {
    fig.peak_deceleration_measured_g = MeasuredPeakDeceleration(
        *sensor, fig.t_end_peak_s, scene.model, analysis.has_value(), &summary.warnings);
  }

  // --- model ---------------------------------------------------------------------------------
  std::optional<ImpactRun> model;
  ImpactModelParameters model_params;
  if (scene.HasStage("model")) {
    WallTimer t;
    const double v0 = std::isfinite(fig.impact_velocity_m_s) ? fig.impact_velocity_m_s
                                                             : scene.test.ImpactVelocity();
    model_params = MakeModelParameters(scene, v0);
    ImpactSolverOptions solver;
    solver.solver = ImpactSolverFromString(scene.model.solver);
    solver.rtol = scene.model.rtol;
    solver.atol = scene.model.atol;
    model = SimulateImpact(model_params, solver);
    const ImpactSummary& s = model->summary;
    for (const auto& w : s.warnings) summary.warnings.push_back("model: " + w);
    fig.added_mass_eq4_kg = AddedMassMaxEq4(scene.test.mass_kg, v0, scene.test.ContactArea());
    fig.momentum_ratio_model = s.momentum_ratio;
    fig.peak_deceleration_model_g = s.peak_deceleration_g;
    fig.plateau_deceleration_model_g = s.plateau_deceleration_g;
    fig.crater_depth_model_m = s.crater_depth_m;
    fig.t_end_model_s = s.t_end_s;
    if (sensor)
      fig.plateau_deceleration_measured_g = MeasuredPlateau(*sensor, s.t1_s, scene.test.g_m_s2);
    if (!s.IsUsable())
      summary.failures.push_back({"model", "the solve did not reach v = 0: " + s.stop_reason});
    stages.Ran("model", s.BriefReport(), t);
  } else {
    stages.Skipped("model", "not among the scene's stages");
  }

  ThrowIfFailed(summary, options);

  // --- outputs -------------------------------------------------------------------------------
  if (!want_outputs) {
    stages.Skipped("outputs", "not among the scene's stages");
    summary.seconds = total.ElapsedSeconds();
    return summary;
  }
  WallTimer t_out;
  const fs::path folder(generation->staging_folder());
  const std::string results_path = (folder / layout::kResultsFile).string();
  // Without outputs.hdf5 the renderer reads the results from memory: results.h5 is not written.
  std::vector<char> results_in_memory;
  if (scene.outputs.hdf5 || scene.outputs.figures || scene.outputs.animation) {
    H5Writer out(results_path);
    out.WriteProvenance(scene.yaml_text);
    out.SetAttribute("/", "scene_name", scene.name);
    out.SetAttribute("/", "scene_path", scene.path);
    for (const auto& s : summary.stages)
      out.SetAttribute("/stages", s.name, s.ran ? "ran: " + s.note : "skipped: " + s.note);
    if (dic) {
      const std::size_t F = series.frames, N = series.subsets;
      const double t_ref =
          frame_times_all.empty() ? 0.0 : frame_times_all[static_cast<std::size_t>(first)];
      const double t_impact = sensor ? sensor->summary.impact_time_s : t_ref;
      std::vector<double> t_ms(F), frame_index(F);
      for (std::size_t f = 0; f < F; ++f) {
        const double tf = frame_times_all.empty()
                              ? f / scene.inputs.fps
                              : frame_times_all[static_cast<std::size_t>(first) + f];
        t_ms[f] = 1e3 * (tf - (frame_times_all.empty() ? 0.0 : t_impact));
        frame_index[f] = static_cast<double>(first + static_cast<int>(f));
      }
      out.Write(layout::kTimeMs, t_ms, "ms", "time of each analysed frame since the impact");
      out.Write("/time/frame_index", frame_index, "1",
                "index of the analysed frame in the input sequence");
      out.Write(layout::kDicX, series.x_px, "px",
                "subset centre x in the first reference (x right)");
      out.Write(layout::kDicY, series.y_px, "px",
                "subset centre y in the first reference (y down)");
      out.Write(layout::kDicU, ToFloat(series.u_px), {F, N}, "px",
                "accumulated displacement x (right); NaN = failed");
      out.Write(layout::kDicV, ToFloat(series.v_px), {F, N}, "px",
                "accumulated displacement y (down); NaN = failed");
      std::vector<float> zncc(F * N, 1.0f);
      // Frame 0 is the reference itself: ZNCC 1, sigma 0.
      std::vector<float> sigma_u(F * N, 0.0f), sigma_v(F * N, 0.0f);
      std::vector<std::int32_t> status(F * N, 0), iterations(F * N, 0);
      for (std::size_t f = 1; f < F; ++f) {
        const FrameResult& r = dic->frames[f - 1];
        for (std::size_t i = 0; i < N; ++i) {
          zncc[f * N + i] = r.zncc[i];
          sigma_u[f * N + i] = r.sigma_u_px[i];
          sigma_v[f * N + i] = r.sigma_v_px[i];
          status[f * N + i] = static_cast<std::int32_t>(r.status[i]);
          iterations[f * N + i] = r.iterations[i];
        }
      }
      out.Write("/dic/zncc", zncc, {F, N}, "1",
                "zero-normalised cross-correlation per subset and frame");
      out.Write("/dic/status", status, {F, N}, "1",
                "subset status code (see attribute status_names)");
      out.Write("/dic/iterations", iterations, {F, N}, "1", "IC-GN iterations");
      out.Write("/dic/sigma_u_px", sigma_u, {F, N}, "px",
                "estimated standard deviation of u against the frame's reference; NaN = failed");
      out.Write("/dic/sigma_v_px", sigma_v, {F, N}, "px",
                "estimated standard deviation of v against the frame's reference; NaN = failed");
      out.SetAttribute("/dic", "max_uncertainty_px",
                       MakeDicOptions(scene.dic).icgn.max_uncertainty_px);
      // The same attributes under the names `impactdic correlate` uses (codes, shape_function).
      out.SetAttribute("/dic/status", "status_names", SubsetStatusCodes());
      out.SetAttribute("/dic/status", "codes", SubsetStatusCodes());
      out.SetAttribute("/dic", "shape_function", scene.dic.shape);
      out.SetAttribute("/dic", "subset_size_px", scene.dic.subset_size);
      out.SetAttribute("/dic", "step_px", scene.dic.step);
      out.SetAttribute("/dic", "interpolation", scene.dic.interpolation);
      out.SetAttribute("/dic", "shape", scene.dic.shape);
      out.SetAttribute("/dic", "reference_update", scene.dic.reference_update);
      out.SetAttribute("/dic", "first_frame", static_cast<double>(first));
      out.SetAttribute("/dic", "summary", dic->summary.BriefReport());
      out.SetAttribute("/dic", "preprocess", preprocess_note);
      // The analysed frames, for `impactdic render` (animation).
      const std::size_t R = static_cast<std::size_t>(frames[0].rows),
                        C = static_cast<std::size_t>(frames[0].cols);
      // Stored with the frames' own depth (8 or 16 bit).
      auto write_frames = [&](auto sample) {
        using T = decltype(sample);
        std::vector<T> pixels(F * R * C);
        for (std::size_t f = 0; f < F; ++f) {
          const cv::Mat& m = frames[f];
          for (std::size_t y = 0; y < R; ++y)
            std::copy(m.ptr<T>(static_cast<int>(y)), m.ptr<T>(static_cast<int>(y)) + C,
                      pixels.begin() + (f * R + y) * C);
        }
        out.Write(layout::kFrameImages, pixels, {F, R, C}, "grey level",
                  "analysed camera frames after preprocessing");
      };
      if (frames[0].depth() == CV_16U)
        write_frames(std::uint16_t{});
      else
        write_frames(std::uint8_t{});
      out.SetAttribute(layout::kFramesGroup, layout::kBitDepthAttr,
                       frames[0].depth() == CV_16U ? 16.0 : 8.0);
    }
    if (sensor) WriteSensor(out, *sensor);
    if (analysis) WriteAnalysis(out, *analysis, *sensor);
    if (analysis) {
      out.SetAttribute(layout::kKinematicsGroup, layout::kMmPerPxAttr, mm_per_px);
    } else if (kinematics_only) {
      const KinematicsResult& kin = *kinematics_only;
      const Dims fn{kin.frames, kin.subsets};
      out.Write(layout::kVx, kin.vel_x_mm_s, fn, "mm/s", "subset velocity x (right)");
      out.Write(layout::kVy, kin.vel_y_mm_s, fn, "mm/s", "subset velocity y (down)");
      out.SetAttribute(layout::kKinematicsGroup, layout::kMmPerPxAttr, mm_per_px);
    }
    if (model) {
      const ImpactSeries s = MakeImpactSeries(model_params, *model);
      std::vector<double> decel(s.size());
      for (std::size_t i = 0; i < s.size(); ++i)
        decel[i] = -s.dv_dt_m_s2[i] / model_params.gravity_m_s2;
      out.Write(layout::kModelT, s.t_s, "s", "model time since impact");
      out.Write(layout::kModelDecel, decel, "g", "model pounder deceleration -dv/dt / g");
      out.Write("/model/z_m", s.z_m, "m", "model penetration (down)");
      out.Write("/model/v_m_s", s.v_m_s, "m/s", "model pounder velocity (down)");
      out.Write("/model/m_add_kg", s.m_add_kg, "kg", "model added mass, Eq. 5");
      out.SetAttribute("/model", "summary", model->summary.BriefReport());
      out.SetAttribute("/model", "solver", model->summary.solver);
      out.SetAttribute("/model", "error_estimate", model->summary.error_estimate);
    }
    const auto names = fig.CsvNames();
    const auto values = fig.CsvValues();
    out.CreateGroup("/summary");
    for (std::size_t i = 0; i < names.size(); ++i)
      out.SetAttribute("/summary", names[i], values[i]);
    out.SetAttribute("/summary", "failures",
                     summary.failures.empty() ? std::string("none") : summary.FailureText());
    if (scene.outputs.hdf5) {
      out.Commit();
      summary.outputs.push_back(results_path);
    } else {
      results_in_memory = out.CommitToMemory();
    }
  }
  if (scene.outputs.figures || scene.outputs.animation) {
    RenderResultsOptions r;
    r.output_dir = generation->staging_folder();
    r.new_generation = false;  // Part of the run's generation.
    r.figures = scene.outputs.figures;
    r.snapshot = scene.outputs.figures;
    r.animation = scene.outputs.animation;
    r.png_frames = options.png_frames || scene.outputs.png_frames;
    const RenderResultsSummary rendered =
        scene.outputs.hdf5
            ? RenderResults(results_path, r)
            : RenderResults(H5Reader(results_path, results_in_memory), results_path, r);
    for (const auto& w : rendered.written) summary.outputs.push_back(w);
    for (const auto& s : rendered.skipped) summary.warnings.push_back("render: " + s);
  }
  const std::string json_path = (folder / layout::kSummaryJson).string();
  WriteTextFileAtomic(json_path, summary.ToJson().Dump() + "\n");
  summary.outputs.push_back(json_path);
  if (scene.outputs.csv) {
    const std::string csv_path = (folder / layout::kSummaryCsv).string();
    std::vector<std::vector<double>> columns;
    for (double v : fig.CsvValues()) columns.push_back({v});
    WriteCsv(csv_path, fig.CsvNames(), columns);
    summary.outputs.push_back(csv_path);
  }
  // All complete: swap the new generation in (the previous one stays until this succeeds).
  generation->Commit();
  for (auto& o : summary.outputs) o = generation->FinalPath(o);
  stages.Ran("outputs",
             fmt::format("{} files in {}", summary.outputs.size(),
                         OutputPathForMessages(summary.output_folder)),
             t_out);
  summary.seconds = total.ElapsedSeconds();
  return summary;
}

}  // namespace

PipelineSummary RunScene(const Scene& scene, const PipelineOptions& options) {
  options.Check();
  const std::string folder =
      options.output_folder.empty() ? scene.outputs.folder : options.output_folder;
  CheckOutputFolderHoldsNoInput(scene, folder,
                                options.output_folder.empty() ? "outputs.folder" : "-o");
  // The highest folder of the output path that does not exist yet (the run may create it and
  // its children).
  std::error_code ec;
  fs::path created;
  for (fs::path p = fs::absolute(folder, ec).lexically_normal(); !p.empty() && !fs::exists(p, ec);
       p = p.parent_path()) {
    created = p;
    if (p == p.parent_path()) break;
  }
  try {
    return RunStages(scene, options);
  } catch (...) {
    // A failed run leaves no empty folders behind (files already complete stay).
    if (!created.empty() && fs::is_directory(created, ec)) {
      bool has_files = false;
      for (auto it = fs::recursive_directory_iterator(created, ec);
           !ec && it != fs::recursive_directory_iterator(); it.increment(ec))
        has_files = has_files || !it->is_directory();
      if (!has_files && !ec) fs::remove_all(created, ec);
    }
    throw;
  }
}

}  // namespace impactdic
