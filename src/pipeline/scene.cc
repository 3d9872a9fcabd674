#include "impactdic/pipeline/scene.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "impactdic/calib/undistort.h"
#include "impactdic/core/error.h"
#include "impactdic/core/range.h"
#include "impactdic/core/strings.h"
#include "impactdic/core/threads.h"
#include "impactdic/dic/bspline.h"
#include "impactdic/dic/reference_update.h"
#include "impactdic/io/input_file.h"
#include "impactdic/momentum/fit.h"

namespace impactdic {
namespace fs = std::filesystem;
namespace {

constexpr const char* kSceneFileWhat = "a scene file (YAML)";

// Ranges of scene-only keys (the library options' ranges are their structs').
// A bound of 1e300 is none (ExpectedText, io/yaml.h).
constexpr ValueRange kPositive{0, 1e300, "", /*min_open=*/true};
constexpr ValueRange kPositivePx{0, 1e300, "px", /*min_open=*/true};
constexpr ValueRange kNonNegativePx{0, 1e300, "px"};
constexpr ValueRange kAnyTime{-1e300, 1e300, "s"};
constexpr ValueRange kCount{1, 1e300, ""};
constexpr ValueRange kFraction{0, 1, "", /*min_open=*/true};
constexpr ValueRange kStrainWindowRange{3, 99, "grid points"};
constexpr ValueRange kStrainCompactionRange{0, 1, "", /*min_open=*/false, /*max_open=*/true};
constexpr ValueRange kStrainShearRange{0, 1e300, ""};
// Gravity must push the pounder down in a scene (0 is only for the model's exact solutions).
constexpr ValueRange kSceneGravityRange{kGravityRange.min, kGravityRange.max, kGravityRange.unit,
                                        /*min_open=*/true};

std::string Num(double v) { return fmt::format("{}", v); }

// A number in `range`, or null/absent: unset.
void AddOptional(YamlOptionTable& t, const std::string& key, std::optional<double>* field,
                 const ValueRange& range, const std::string& what, const std::string& doc) {
  t.AddNumber(
      key, ExpectedText(what, range), field->has_value() ? Num(**field) : "unset",
      [field, range](const YAML::Node& n) {
        double v = 0;
        if (!DecodeNumber(n, range, &v)) return false;
        *field = v;
        return true;
      },
      doc);
}

// "auto" (stored as NaN) or a number in `range`.
void AddAutoNumber(YamlOptionTable& t, const std::string& key, double* field,
                   const ValueRange& range, const std::string& what, const std::string& doc) {
  t.AddNumber(
      key, "auto or " + ExpectedText(what, range), std::isnan(*field) ? "auto" : Num(*field),
      [field, range](const YAML::Node& n) {
        double v = kNaN;
        if (!(n.IsScalar() && n.Scalar() == "auto") && !DecodeNumber(n, range, &v)) return false;
        *field = v;
        return true;
      },
      doc);
}

// A path, resolved against the scene file's folder.
void AddPath(YamlOptionTable& t, const std::string& key, std::string* field,
             const std::string& folder, const std::string& doc) {
  t.AddCustom(
      key, "a path", *field,
      [field, folder](const YAML::Node& n) {
        if (!n.IsScalar()) return false;
        if (n.Scalar().empty()) return true;
        const fs::path p(n.Scalar());
        *field = p.is_absolute() ? p.lexically_normal().string()
                                 : (fs::path(folder) / p).lexically_normal().string();
        return true;
      },
      doc);
}

// An odd integer in `range` (subset and kernel sizes).
void AddOdd(YamlOptionTable& t, const std::string& key, int* field, const ValueRange& range,
            const std::string& doc) {
  t.AddNumber(
      key, "an odd integer in " + range.Text(), std::to_string(*field),
      [field, range](const YAML::Node& n) {
        int v = 0;
        if (!DecodeNumber(n, range, &v) || v % 2 == 0) return false;
        *field = v;
        return true;
      },
      doc);
}

YamlOptionTable InputsTable(Scene* s) {
  YamlOptionTable t("inputs");
  SceneInputs& in = s->inputs;
  AddPath(t, "frames", &in.frames, s->folder,
          "Folder, glob, video or camera file (.cine, .mraw, .cih, .cihx) of the frames "
          "(required)");
  t.AddNumber(
      "fps", ExpectedText("a camera frame rate", kCameraFpsRange), Num(in.fps),
      [&in](const YAML::Node& n) {
        if (!DecodeNumber(n, kCameraFpsRange, &in.fps)) return false;
        in.fps_given = true;
        return true;
      },
      "Camera frame rate; a camera file's own rate when not given");
  AddPath(t, "calibration", &in.calibration, s->folder, "Calibration YAML (impactdic calibrate)");
  t.Add("mm_per_px", &in.mm_per_px, kMmPerPxRange, "an image scale",
        "Scale without a calibration; 0 = the calibration's plane scale");
  t.Add("mm_per_px_u", &in.mm_per_px_u, kNonNegativeUncertaintyRange, "a standard uncertainty",
        "Standard uncertainty of the scale [mm/px]; 0 = the calibration's plane-scale one when "
        "the scale is the calibration's, else exact");
  AddPath(t, "sensor", &in.sensor, s->folder, "DAQ CSV; none = no sensor stage");
  AddPath(t, "truth", &in.truth, s->folder, "Ground-truth HDF5 (synthetic scenes)");
  return t;
}

// The pounder and soil are the model's parameters (ImpactModelParameters), read by every stage.
YamlOptionTable TestTable(Scene* s) {
  YamlOptionTable t("test");
  ImpactModelParameters& m = s->model;
  t.Add("mass_kg", &m.pounder_mass_kg, kPounderMassRange, "a pounder mass", "Pounder mass m_p");
  t.Add("drop_height_m", &s->test.drop_height_m, kDropHeightRange, "a drop height",
        "Drop height h; v0 = sqrt(2 g h) unless impact_velocity_m_s is given");
  AddOptional(t, "impact_velocity_m_s", &s->test.impact_velocity_m_s, kImpactVelocityRange,
              "an impact velocity", "Impact velocity v0 (overrides the drop height)");
  t.Add("width_m", &m.width_m, kPounderSizeRange, "a pounder width D", "Pounder width D");
  t.Add("depth_m", &m.depth_m, kPounderSizeRange, "an out-of-plane depth t_z",
        "Out-of-plane depth t_z");
  t.Add("density_kg_m3", &m.density_kg_m3, kSoilDensityRange, "a dry density", "Dry density rho_d");
  MomentumUncertaintyOptions& u = s->momentum.options.uncertainty;
  t.Add("density_u_kg_m3", &u.density_u_kg_m3, kNonNegativeUncertaintyRange,
        "a standard uncertainty", "Standard uncertainty of rho_d; 0 = exact");
  t.Add("depth_u_m", &u.depth_u_m, kNonNegativeUncertaintyRange, "a standard uncertainty",
        "Standard uncertainty of t_z; 0 = exact");
  t.Add("bed_height_m", &m.bed_height_m, kBedHeightRange, "a bed height", "Sand bed height");
  t.Add("g_m_s2", &m.gravity_m_s2, kSceneGravityRange, "a gravitational acceleration",
        "Gravitational acceleration g");
  return t;
}

// Every field of PreprocessOptions is a key: undistort and undistortion.* of
// preprocess.undistortion, gaussian and clahe of theirs; roi and undistortion.roi are dic.roi
// (MakePreprocessOptions, pipeline.h).
std::vector<YamlOptionTable> PreprocessTables(Scene* s) {
  PreprocessOptions& p = s->preprocess;
  YamlOptionTable undistortion("preprocess.undistortion");
  undistortion.Add("enabled", &p.undistort,
                   "Undistort the frames when a calibration is given (and the lens moves a roi "
                   "pixel by more than skip_threshold_px)");
  undistortion.Add("skip_threshold_px", &p.undistortion.skip_threshold_px,
                   kUndistortSkipThresholdRange, "a lens shift",
                   "Skip the undistortion when no roi pixel moves by more than this");
  undistortion.AddChoice(
      "interpolation", kUndistortInterpolationNames.Names(), ToString(p.undistortion.interpolation),
      [&p](const std::string& v) {
        p.undistortion.interpolation = UndistortInterpolationFromString(v);
      },
      "Interpolation of the undistorted frames");
  GaussianBlurOptions& g = s->preprocess.gaussian;
  YamlOptionTable gauss("preprocess.gaussian");
  gauss.AddCustom(
      "enabled", "auto, true or false", ToString(g.mode),
      [&g](const YAML::Node& n) {
        if (!n.IsScalar()) return false;
        try {
          g.mode = GaussianModeFromString(n.Scalar(), "");
        } catch (const Error&) {
          return false;
        }
        return true;
      },
      "Gaussian blur: true, false, or auto = when the first frame's near-Nyquist bias figure is "
      "above auto_threshold_px (docs/dic_accuracy.md, Sub-pixel bias)");
  gauss.Add("sigma", &g.sigma_px, kGaussianSigmaRange, "a sigma", "Standard deviation of the blur");
  AddOdd(gauss, "kernel", &g.kernel_size, kGaussianKernelRange, "Kernel size");
  gauss.Add("auto_threshold_px", &g.auto_threshold_px, kNyquistBiasThresholdRange, "a bias figure",
            "enabled auto: blur when the near-Nyquist bias figure is above it");
  ClaheOptions& c = s->preprocess.clahe;
  YamlOptionTable clahe("preprocess.clahe");
  clahe.Add("enabled", &c.enabled, "CLAHE on/off");
  clahe.Add("clip_limit", &c.clip_limit, kClaheClipLimitRange, "a clip limit",
            "Contrast limit relative to a flat histogram");
  clahe.Add("tile_grid", &c.tile_grid, kClaheTileGridRange, "tile count", "Tiles per side");
  return {undistortion, gauss, clahe};
}

void AddDicFrameKeys(YamlOptionTable& t, Scene* s) {
  SceneDic& d = s->dic;
  AddPath(t, "mask", &d.mask, s->folder, "Mask image: subsets centred on non-zero pixels only");
  t.AddNumber(
      "threads", kThreadCountExpected, std::to_string(d.threads),
      [&d](const YAML::Node& n) {
        int v = 0;
        if (!n.IsScalar() || !YAML::convert<int>::decode(n, v) || !IsValidThreadCount(v))
          return false;
        d.threads = v;
        return true;
      },
      "Worker threads");
  t.Add("first_frame", &d.first_frame, ValueRange{0, 1e300, ""}, "frame index",
        "First frame to correlate; 0 with a sensor record: the last frame before the impact (4 "
        "before it with base channels, for the wave front's noise)");
  t.Add("last_frame", &d.last_frame, ValueRange{-1, 1e300, ""}, "frame index (-1: the last)",
        "Last frame (inclusive); -1 = the last frame");
  // The same selection by the frames' own numbers (io FrameSource::FrameNumber).
  for (auto [key, field, doc] :
       {std::tuple{"first_frame_number", &d.first_frame_number,
                   "First frame to correlate (the reference) by the frames' own numbers: a "
                   "numbered file name's, a video's index, a camera's (< 0: before the trigger); "
                   "instead of first_frame"},
        std::tuple{"last_frame_number", &d.last_frame_number,
                   "Last frame (inclusive), numbered as first_frame_number; instead of "
                   "last_frame"}}) {
    std::optional<long long>* value = field;
    t.AddNumber(
        key, "an integer frame number (the frames' own numbering)",
        value->has_value() ? std::to_string(**value) : "unset",
        [value](const YAML::Node& n) {
          long long v = 0;
          if (!n.IsScalar() || !YAML::convert<long long>::decode(n, v)) return false;
          *value = v;
          return true;
        },
        doc);
  }
}

// dic.continuity_<name>: a threshold of ContinuityCheckOptions (dic/options.h, kContinuityLimits).
void AddContinuityLimit(YamlOptionTable& t, ContinuityCheckOptions* c,
                        double ContinuityCheckOptions::*field, const std::string& doc) {
  const ContinuityLimit& limit = ContinuityLimitOf(field);
  double* value = &(c->*field);
  t.AddCustom(
      std::string("continuity_") + limit.name, limit.Expected(), ContinuityLimitText(*value),
      [value, &limit](const YAML::Node& n) {
        if (!n.IsScalar()) return false;
        try {
          *value = limit.FromString(n.Scalar(), "");
        } catch (const Error&) {
          return false;
        }
        return true;
      },
      doc);
}

void AddContinuityKeys(YamlOptionTable& t, ContinuityCheckOptions* c) {
  t.Add("continuity_check", &c->enabled,
        "Post-check: subsets straddling a body edge or shear band become discontinuous (NaN)");
  AddContinuityLimit(t, c, &ContinuityCheckOptions::misfit_ratio,
                     "Flag 1 - ZNCC above this times its 7x7 neighbourhood's median");
  t.Add("continuity_min_misfit", &c->min_misfit, kMinMisfitRange, "a 1 - ZNCC level",
        "...and above this as well");
  AddContinuityLimit(t, c, &ContinuityCheckOptions::max_second_difference_px,
                     "Flag a second difference of u, v along a grid row or column above it");
  AddContinuityLimit(t, c, &ContinuityCheckOptions::max_neighbour_difference_px,
                     "Flag a displacement differing from an adjacent subset's by more");
  AddContinuityLimit(t, c, &ContinuityCheckOptions::local_ratio,
                     "...and above this times the 7x7 median of the same");
}

void AddOutlierKeys(YamlOptionTable& t, OutlierCheckOptions* o) {
  t.Add("outlier_check", &o->enabled,
        "Normalized median test: spurious vectors become outlier (NaN)");
  t.Add("outlier_threshold", &o->threshold, kOutlierThresholdRange, "a normalized residual",
        "Flag |d - median| / (neighbours' median residual + noise) above it");
  t.Add("outlier_noise_px", &o->noise_px, kOutlierNoiseRange, "a noise level",
        "The noise level epsilon of the normalized median test");
  t.Add("outlier_sigma_factor", &o->sigma_factor, kOutlierSigmaFactorRange, "a factor",
        "...and |d - median| above this times the subset's own sigma");
  t.Add("outlier_min_neighbours", &o->min_neighbours, kOutlierNeighboursRange, "neighbour count",
        "Converged neighbours (of 8, in opposite pairs) needed to judge a subset");
}

// The fields of DicOptions (dic/options.h) that no dic.* key reaches, and why. Every other field
// is a key of DicTable, or dic.roi / dic.mask (SceneDic); the test
// SceneFlags.EveryDicOptionIsASceneKeyOrInternal holds each field to one or the other.
const std::vector<InternalOption>& InternalDicOptions() {
  static const std::vector<InternalOption> kInternal = {
      {"dic.init.seed_spacing",
       "Where the integer-pixel search seeds the propagation: it decides which subsets start from "
       "a "
       "search rather than from a solved neighbour, not what a converged subset measures (IC-GN "
       "from either start, judged by min_zncc); the search's reach is dic.search_radius_px"},
      {"dic.init.min_search_zncc",
       "The search's own acceptance of an integer-pixel start; IC-GN refines it and min_zncc "
       "judges the result"},
      {"dic.data_bits",
       "A property of the frames, not a choice: the camera file states it, else it is measured "
       "from the first reference (frames stage)"},
  };
  return kInternal;
}

YamlOptionTable DicTable(Scene* s) {
  YamlOptionTable t("dic");
  DicOptions& o = s->dic.options;
  AddOdd(t, "subset_size", &o.grid.subset_size, kSubsetSizeRange, "Subset side S");
  t.Add("step", &o.grid.step, kGridStepRange, "grid step", "Grid spacing");
  t.AddChoice(
      "interpolation", kInterpolationNames.Names(), ToString(o.icgn.interpolation),
      [&o](const std::string& v) { o.icgn.interpolation = InterpolationFromString(v); },
      "B-spline interpolation of the deformed image");
  t.AddChoice(
      "shape", kShapeFunctionNames.Names(), ToString(o.icgn.shape),
      [&o](const std::string& v) { o.icgn.shape = ShapeFunctionFromString(v); },
      "Subset shape function");
  t.AddCustom(
      "reference_update", ReferenceUpdatePolicyUsage(), ReferenceUpdateText(o.update),
      [&o](const YAML::Node& n) {
        if (!n.IsScalar()) return false;
        try {
          ReferenceUpdatePolicyFromString(n.Scalar(), o.update);
        } catch (const Error&) {
          return false;
        }
        o.update.policy = n.Scalar();
        return true;
      },
      "When the reference image changes (docs/dic.md)");
  t.Add("min_zncc", &o.icgn.min_zncc, kMinZnccRange, "a ZNCC threshold",
        "A converged subset below it is low_correlation (failed); not the auto threshold");
  t.Add("auto_min_zncc", &o.update.auto_min_zncc, kAutoMinZnccRange, "a ZNCC threshold",
        "reference_update auto: the reference moves on once a tracked subset falls below it");
  t.Add("auto_rescue_decorrelation", &o.update.auto_rescue_decorrelation,
        kAutoRescueDecorrelationRange, "a share of 1 - ZNCC",
        "reference_update auto: a subset that matched the reference counts as rescued by the last "
        "frame only with at most this share of its decorrelation left");
  t.AddNumber(
      "max_uncertainty_px", "an uncertainty limit >= 0 [px], or none (0 and none: no limit)",
      MaxUncertaintyText(o.icgn.max_uncertainty_px),
      [&o](const YAML::Node& n) {
        if (!n.IsScalar()) return false;
        try {
          o.icgn.max_uncertainty_px = MaxUncertaintyFromString(n.Scalar(), "");
        } catch (const Error&) {
          return false;
        }
        return std::isfinite(o.icgn.max_uncertainty_px) || n.Scalar() == "none";
      },
      "Converged subsets with sigma_u or sigma_v above it are uncertain (NaN)");
  t.Add("max_predicted_uncertainty_px", &o.icgn.max_predicted_uncertainty_px,
        kMaxPredictedUncertaintyRange, "a predicted standard deviation",
        "Reference subsets whose displacement standard deviation, predicted from their gradients "
        "and the frame's noise before correlating, exceeds it are low_contrast (failed)");
  t.Add("min_contrast", &o.icgn.min_contrast, kMinContrastRange, "a grey-level standard deviation",
        "Reference subsets whose grey-level standard deviation is below it are low_contrast "
        "(failed); in 8-bit levels, scaled to the grey-level range the reference frame uses");
  t.Add("max_saturated_fraction", &o.icgn.max_saturated_fraction, kMaxSaturatedFractionRange,
        "a fraction of the subset",
        "Reference subsets with more than this fraction of pixels at 0 or full scale are "
        "saturated (failed)");
  t.Add("max_iterations", &o.icgn.max_iterations, kMaxIterationsRange, "iteration cap",
        "IC-GN iteration cap");
  t.Add("convergence_px", &o.icgn.convergence_px, kConvergenceRange, "a convergence threshold",
        "IC-GN stops when the update moves no subset point more");
  t.Add("convergence_sigma_fraction", &o.icgn.convergence_sigma_fraction,
        kConvergenceSigmaFractionRange, "a fraction of sigma",
        "...or less than this fraction of the subset's own sigma");
  t.Add("search_radius_px", &o.init.search_radius_px, kSearchRadiusRange, "search radius",
        "Integer-pixel initial-guess search radius");
  t.AddChoice(
      "mode", kSequenceModeNames.Names(), ToString(o.mode),
      [&o](const std::string& v) { o.mode = SequenceModeFromString(v, "dic.mode"); },
      "sequence | pairs: sequence = the frames of one recording, each predicted from the previous "
      "ones, the reference updated by reference_update; pairs = independent images, each "
      "correlated against the first alone (reference_update does not apply)");
  t.Add("keep_warp_gradient", &o.keep_warp_gradient,
        "Keep each subset's warp gradient since the first reference: /dic/dudx_warp, dudy_warp, "
        "dvdx_warp, dvdy_warp (docs/dic_accuracy.md, Warp gradient); on with strain.gradient warp");
  AddContinuityKeys(t, &o.continuity);
  AddOutlierKeys(t, &o.outliers);
  AddDicFrameKeys(t, s);
  return t;
}

// A list key's items: a YAML list of scalars, or one scalar of items separated by commas (the
// form its flag takes); null: none. False (nothing set) for another node or an empty item.
bool ReadListItems(const YAML::Node& n, std::vector<std::string>* items) {
  std::vector<std::string> read;
  if (n.IsSequence()) {
    for (const YAML::Node& c : n) read.push_back(c.IsScalar() ? c.Scalar() : "");
  } else if (n.IsScalar()) {
    std::stringstream ss(n.Scalar());
    for (std::string c; std::getline(ss, c, ',');) {
      const std::size_t first = c.find_first_not_of(' ');
      read.push_back(
          first == std::string::npos ? "" : c.substr(first, c.find_last_not_of(' ') - first + 1));
    }
  } else if (!n.IsNull()) {
    return false;
  }
  if (std::any_of(read.begin(), read.end(), [](const auto& c) { return c.empty(); })) return false;
  *items = std::move(read);
  return true;
}

// A list key of numbers in `range` (ReadListItems' forms), one per base force channel.
void AddNumberList(YamlOptionTable& t, const std::string& key, std::vector<double>* field,
                   const ValueRange& range, const std::string& what, const std::string& doc) {
  t.AddCustom(
      key,
      "numbers separated by commas, one per sensor.base_columns, each " + ExpectedText(what, range),
      fmt::format("{}", fmt::join(*field, ",")),
      [field, range](const YAML::Node& n) {
        std::vector<std::string> items;
        if (!ReadListItems(n, &items)) return false;
        std::vector<double> values;
        for (const std::string& item : items) {
          const std::optional<double> v = ParseNumber(item);
          if (!v || !range.Contains(*v)) return false;
          values.push_back(*v);
        }
        *field = std::move(values);
        return true;
      },
      doc);
}

// The base force channels (docs/wave.md): parallel lists, entry k of each describing column k of
// sensor.base_columns (SensorOptions::Check holds them to its length). Lists follow the other list
// keys (force_columns): a YAML list or comma-separated, so each is also one flag.
void AddBaseForceKeys(YamlOptionTable& t, SensorOptions* o) {
  t.AddCustom(
      "base_columns", "column names separated by commas (empty: none)",
      Join(o->columns.base_force, ","),
      [o](const YAML::Node& n) { return ReadListItems(n, &o->columns.base_force); },
      "Base force sensors under the bed (docs/wave.md): their CSV columns; the wave figures "
      "(summary.json wave, /wave) need them");
  std::vector<std::string> unit_names;
  for (const ForceUnit u : o->base.units) unit_names.emplace_back(ToString(u));
  t.AddCustom(
      "base_units", "N or kN for each of sensor.base_columns, separated by commas",
      Join(unit_names, ","),
      [o](const YAML::Node& n) {
        std::vector<std::string> items;
        if (!ReadListItems(n, &items)) return false;
        std::vector<ForceUnit> units;
        try {
          for (const std::string& item : items)
            units.push_back(kForceUnitNames.Parse(item, "sensor.base_units"));
        } catch (const Error&) {
          return false;
        }
        o->base.units = std::move(units);
        return true;
      },
      "Unit of each base column");
  AddNumberList(t, "base_offsets_mm", &o->base.offset_mm, kBaseOffsetRange, "a horizontal offset",
                "Horizontal offset of each base sensor from the pounder's centre line");
  AddNumberList(t, "base_depths_mm", &o->base.depth_mm, kBaseDepthRange,
                "a depth below the surface", "Depth of each base sensor below the sand surface");
  AddNumberList(t, "base_areas_mm2", &o->base.area_mm2, kBaseAreaRange, "a sensing area",
                "Sensing area of each base sensor (stress = force / area)");
}

YamlOptionTable SensorTable(Scene* s) {
  YamlOptionTable t("sensor");
  SensorOptions& o = s->sensor.options;
  t.Add("time_column", &o.columns.time, "Time column [s]");
  t.Add("accel_column", &o.columns.accel, "Acceleration column");
  t.AddChoice(
      "accel_unit", kAccelUnitNames.Names(), ToString(o.columns.accel_unit),
      [&o](const std::string& v) { o.columns.accel_unit = AccelUnitFromString(v); },
      "Unit of the acceleration column; auto = from its name");
  t.Add("exposure_column", &o.columns.exposure,
        "Camera exposure column (frame times from its rising edges); must be in the CSV when "
        "frames are timed; empty = none");
  t.Add("cutoff_hz", &o.cutoff_hz, kCutoffRange, "a cut-off frequency",
        "Low-pass cut-off (< fs / 2)");
  t.AddChoice(
      "integrate_from", kIntegrationStartNames.Names(), ToString(o.integrate_from),
      [&o](const std::string& v) { o.integrate_from = IntegrationStartFromString(v); },
      "Integrate from the release (v = 0) or the impact (v0 of the test)");
  t.Add("frame_time_offset_s", &s->sensor.frame_time_offset_s, kAnyTime, "a time of frame 0",
        "Time of frame 0 on the DAQ clock (no exposure channel)");
  t.Add("quiet_window_s", &o.quiet_window_s, kQuietWindowRange, "a window length",
        "Offset/noise window length");
  t.AddChoice(
      "offset_reference", kOffsetReferenceNames.Names(), ToString(o.offset_reference),
      [&o](const std::string& v) { o.offset_reference = OffsetReferenceFromString(v); },
      "What reads a known level: free-fall (the whole free fall reads 0 g), free-fall-window (the "
      "quiet window before the impact reads 0 g), rest (the record start reads 1 g) or none");
  t.AddNumber(
      "release_time_s", ExpectedText("a release time", kAnyTime), "detected",
      [&o](const YAML::Node& n) { return DecodeNumber(n, kAnyTime, &o.release_time_s); },
      "Release time on the DAQ clock, with integrate_from release (inside the record, before the "
      "impact); detected = the record starts at rest");
  t.Add("impact_threshold_g", &o.impact_threshold_g, kImpactThresholdRange, "an impact threshold",
        "Reading [g] that is certainly the impact; the onset is found before it");
  t.Add("quiet_guard_s", &o.quiet_guard_s, kQuietGuardRange, "a gap",
        "Gap left between the quiet (offset and noise) windows and the impact or release");
  t.Add("noise_band_sigma", &o.noise_band_sigma, kNoiseBandSigmaRange, "a number of sigmas",
        "Impact onset: walk back to the last sample inside this many noise sigmas of free fall");
  t.Add("stop_velocity_m_s", &o.stop_velocity_m_s, kStopVelocityRange, "a speed",
        "The pounder has stopped once its velocity falls to this after the peak");
  t.AddCustom(
      "force_columns", "column names separated by commas (empty: every force* column)",
      Join(o.columns.force, ","),
      [&o](const YAML::Node& n) { return ReadListItems(n, &o.columns.force); },
      "Force channels kept (filtered, /sensor/force); empty = every column named force*");
  AddBaseForceKeys(t, &o);
  return t;
}

// The fields of SensorOptions (sensor/sensor.h) that no key reaches, and why. g_m_s2 is
// test.g_m_s2, impact_velocity_m_s and expected_impact_velocity_* the test's v0
// (MakeSensorOptions); every other field is a key of SensorTable.
const std::vector<InternalOption>& InternalSensorOptions() {
  static const std::vector<InternalOption> kInternal = {
      {"sensor.max_step_deviation",
       "A check of the record, not a setting of the result: a time step further than this from "
       "the median is refused (naming the rows), and an accepted record gives the same result "
       "whatever it is"},
  };
  return kInternal;
}

YamlOptionTable MomentumTable(Scene* s) {
  YamlOptionTable t("momentum");
  SceneMomentum& m = s->momentum;
  AddOptional(t, "pounder_center_x_px", &m.pounder_center_x_px, kNonNegativePx, "a pixel column",
              "Footprint centre in the first frame");
  AddOptional(t, "surface_y_px", &m.surface_y_px, kNonNegativePx, "a pixel row",
              "Sand surface (pounder bottom at impact) in the first frame");
  t.Add("grid_cols", &m.options.grid_cols, kCount, "subset count", "Subsets across the footprint");
  t.Add("grid_rows", &m.options.grid_rows, kCount, "subset count", "Subset rows beneath it");
  t.Add("min_valid_fraction", &m.options.min_valid_fraction, kFraction,
        "a fraction of the grid's subsets", "Per frame: p_gran only where this much is valid");
  AddOptional(t, "max_sigma_px", &m.max_sigma_px, kPositivePx, "a standard deviation limit",
              "Subset samples above it are left out of kinematics and p_gran");
  t.AddNumber(
      "max_sigma_ratio", "a ratio > 1, or none",
      std::isfinite(m.max_sigma_ratio) ? Num(m.max_sigma_ratio) : std::string("none"),
      [&m](const YAML::Node& n) {
        if (!n.IsScalar()) return false;
        if (n.Scalar() == "none") {
          m.max_sigma_ratio = std::numeric_limits<double>::infinity();
          return true;
        }
        const std::optional<double> value = ParseNumber(n.Scalar());
        if (!value || !(*value > 1) || !std::isfinite(*value)) return false;
        m.max_sigma_ratio = *value;
        return true;
      },
      "Unless max_sigma_px: samples above this times the frame's median sigma are left out");
  MomentumOptions& o = m.options;
  t.Add("velocity_match_tolerance", &o.velocity_match_tolerance, kVelocityMatchToleranceRange,
        "a fraction of v_p,max", "t_e: v_p - v_sand at most this times v_p,max");
  t.Add("sand_accel_tolerance", &o.sand_accel_tolerance, kSandAccelToleranceRange,
        "a fraction of the peak soil acceleration",
        "t_e: ...and the soil's acceleration at most this times its peak");
  t.Add("fit_sigmoid", &o.fit_sigmoid, "Fit the sigmoid M, b, T to the added mass (Eq. 6)");
  t.Add("sigmoid_confidence", &o.sigmoid.confidence, kConfidenceRange, "a confidence level",
        "Level of the sigmoid fit's confidence intervals");
  t.Add("uncertainty_draws", &o.uncertainty.draws, kUncertaintyDrawsRange, "a number of draws",
        "Monte Carlo draws of the figures' uncertainty; 0 = none");
  return t;
}

// The fields of MomentumOptions (momentum/momentum.h) that no key reaches, and why. The pounder
// and soil are test.* and the footprint momentum.pounder_center_x_px / surface_y_px
// (MakeMomentumOptions); every other field is a key of MomentumTable (rect_mm read by ParseScene).
const std::vector<InternalOption>& InternalMomentumOptions() {
  static const std::vector<InternalOption> kInternal = {
      {"momentum.sigmoid.max_iterations",
       "The Levenberg-Marquardt fit's iteration cap: a fit that converges gives the same M, b, T "
       "whatever it is, and one that does not says so (converged, message)"},
      {"momentum.sigmoid.step_tolerance",
       "The fit's stopping rule on the relative parameter step (1e-10): it moves M, b, T far "
       "below their standard errors"},
  };
  return kInternal;
}

// A solver tolerance: NaN (unset) means the solver's rule, shown as `unset_text`.
void AddTolerance(YamlOptionTable& t, const std::string& key, double* field,
                  const ValueRange& range, const std::string& what, const std::string& unset_text,
                  const std::string& doc) {
  t.AddNumber(
      key, ExpectedText(what, range), std::isnan(*field) ? unset_text : Num(*field),
      [field, range](const YAML::Node& n) {
        double v = 0;
        if (!DecodeNumber(n, range, &v)) return false;
        *field = v;
        return true;
      },
      doc);
}

YamlOptionTable ModelTable(Scene* s) {
  YamlOptionTable t("model");
  ImpactModelParameters& m = s->model;
  t.AddNumber(
      "added_mass_kg", "an added mass M in " + kAddedMassRange.Text(), "Eq. 4",
      [&m](const YAML::Node& n) { return DecodeNumber(n, kAddedMassRange, &m.added_mass_kg); },
      "Added mass M; unset: Eq. 4");
  t.Add("K", &m.friction_K, kFrictionKRange, "a friction coefficient K",
        "Friction coefficient K (Eq. 8, Table 2)");
  t.Add("n", &m.damping_exponent_n, kDampingExponentNRange, "a damping exponent n",
        "Damping exponent n (Eq. 8, Table 2)");
  t.Add("u", &m.damping_factor_u, kDampingFactorURange,
        "a damping factor u (>= 1: F_dyn must resist the motion)",
        "Damping factor u (Eq. 8, Table 2)");
  t.Add("T_s", &m.sigmoid_delay_T_s, kSigmoidDelayRange, "a sigmoid delay T",
        "Sigmoid delay T (Eq. 6, Table 2)");
  t.Add("b_per_s", &m.sigmoid_rate_b_per_s, kSigmoidRateRange, "a sigmoid rate b",
        "Sigmoid rate b (Eq. 6, Table 2)");
  ImpactSolverOptions& o = s->solver;
  t.AddChoice(
      "solver", kImpactSolverNames.Names(), ToString(o.solver),
      [&o](const std::string& v) { o.solver = ImpactSolverFromString(v); }, "ODE solver");
  AddTolerance(t, "rtol", &o.rtol, kRelativeToleranceRange, "a relative tolerance", "1e-6",
               "Relative tolerance of the ODE solver");
  AddTolerance(t, "atol", &o.atol, kPositive, "an absolute tolerance", "1e-3 * rtol",
               "Absolute tolerance of the ODE solver");
  t.AddChoice(
      "error_estimator", kErrorEstimatorNames.Names(), ToString(o.error_estimator),
      [&o](const std::string& v) { o.error_estimator = ErrorEstimatorFromString(v); },
      "How a solve estimates its error: companion (a run at rtol/10) or local (summed local "
      "estimates)");
  t.Add("ode45_defaults", &o.ode45_defaults,
        "MATLAB ode45's rules and defaults (RelTol 1e-3, AbsTol 1e-6), the paper's setting; "
        "solver auto or dopri5");
  t.Add("t_max_s", &o.t_max_s, ValueRange{0, 1e300, "s", /*min_open=*/true}, "a time",
        "Give up (warning) if v has not reached 0 by then");
  return t;
}

// The fields of ImpactSolverOptions (model/impact_model.h) that no model.* key reaches, and why:
// they guard the integration, and the solution's accuracy is model.rtol / model.atol's. Every
// field of ImpactModelParameters is a test.* or model.* key (impact_velocity_m_s: the test's v0,
// or the sensor's measured one).
const std::vector<InternalOption>& InternalModelOptions() {
  static const std::vector<InternalOption> kInternal = {
      {"solver.sigmoid_window",
       "Step-size safeguard: the solver does not step over the sigmoid; the solution changes only "
       "within the tolerances model.rtol / model.atol"},
      {"solver.sigmoid_step",
       "Step-size safeguard (the largest step near the sigmoid); the solution changes only within "
       "the tolerances model.rtol / model.atol"},
      {"solver.switch_velocity_fraction",
       "When the solve changes to the end-phase variable: the same ODE in another variable, the "
       "solution the same within the tolerances model.rtol / model.atol"},
      {"solver.max_steps",
       "A guard against a runaway solve (2e6 steps per phase); a solve that hits it is reported as "
       "not usable, with the reason"},
      {"solver.error_warning_factor",
       "Only when a warning is given (error estimate above this times rtol), not what is solved"},
  };
  return kInternal;
}

}  // namespace

const char* ToString(FrameStorage storage) { return kFrameStorageNames.Name(storage); }

FrameStorage FrameStorageFromString(const std::string& text) {
  return kFrameStorageNames.Parse(text, "outputs.frames");
}

namespace {

// `strain.*`: StrainOptions (docs/strain.md).
YamlOptionTable StrainTable(Scene* s) {
  YamlOptionTable t("strain");
  StrainOptions& o = s->strain;
  t.Add("enabled", &o.enabled,
        "Strain, density, compacted zone and shear bands (/strain, strain.csv; docs/strain.md)");
  t.AddChoice(
      "gradient", kStrainGradientNames.Names(), kStrainGradientNames.Name(o.gradient),
      [&o](const std::string& v) { o.gradient = kStrainGradientNames.Parse(v, "strain.gradient"); },
      "Displacement gradient: fit = least-squares plane through the neighbours' displacements, "
      "warp = the subset warp's own");
  AddOdd(t, "window", &o.window, kStrainWindowRange,
         "gradient fit: neighbourhood side in grid points");
  t.Add("compaction_threshold", &o.compaction_threshold, kStrainCompactionRange,
        "a volumetric strain (compression positive)",
        "Compacted zone: samples whose eps_v exceeds it");
  t.Add("shear_band_threshold", &o.shear_band_threshold, kStrainShearRange, "a shear strain",
        "Shear bands: ridges of gamma_max above it");
  return t;
}

YamlOptionTable OutputsTable(Scene* s) {
  YamlOptionTable t("outputs");
  SceneOutputs& o = s->outputs;
  AddPath(t, "folder", &o.folder, s->folder, "Output folder (`impactdic run -o` overrides)");
  t.Add("hdf5", &o.hdf5, "results.h5");
  t.Add("xdmf", &o.xdmf,
        "results.xdmf for ParaView/VisIt: views of results.h5's fields, no copy (needs hdf5)");
  t.Add("csv", &o.csv, "summary.csv and the series CSVs");
  t.Add("figures", &o.figures, "Figures (gnuplot)");
  t.Add("animation", &o.animation, "Animation");
  t.Add("png_frames", &o.png_frames, "The animation's frames as PNG files");
  t.AddChoice(
      "frames", kFrameStorageNames.Names(), ToString(o.frames),
      [&o](const std::string& v) { o.frames = FrameStorageFromString(v); },
      "Frames stored in results.h5: none, a preview (at most 16, downsampled to <= 640 px) or all");
  return t;
}

// The display keys of a field drawn over its frames (the velocity and strain maps).
void AddDisplayKeys(YamlOptionTable& t, int* min_width_px, int* max_width_px, double* low,
                    double* high) {
  t.Add("min_width_px", min_width_px, kDisplayWidthRange, "display width",
        "Frames narrower than this are scaled up for display");
  t.Add("max_width_px", max_width_px, kDisplayWidthRange, "display width",
        "Frames wider than this are scaled down for display (>= min_width_px)");
  t.Add("contrast_low_percentile", low, kContrastPercentileRange, "a percentile",
        "16-bit and float frames: this percentile of the first frame is drawn black");
  t.Add("contrast_high_percentile", high, kContrastPercentileRange, "a percentile",
        "... and this one white (> contrast_low_percentile)");
}

// How the figures and animations are drawn (SceneOutputs: plot, video, velocity_map, strain_map).
std::vector<YamlOptionTable> RenderTables(Scene* s) {
  SceneOutputs& o = s->outputs;
  YamlOptionTable plot("outputs.plot");
  plot.Add("width_px", &o.plot.width_px, PlotOptions::kWidthRange, "figure width",
           "Width of the gnuplot figures (PNG)");
  plot.Add("height_px", &o.plot.height_px, PlotOptions::kHeightRange, "figure height",
           "Height of the gnuplot figures");
  plot.Add("font_size_pt", &o.plot.font_size_pt, PlotOptions::kFontSizeRange, "font size",
           "Base font size of the figures");
  plot.Add("font", &o.plot.font, "Font of the figures (a font name without quotes)");
  plot.Add("gnuplot", &o.plot.gnuplot_binary,
           "gnuplot program; empty: $IMPACTDIC_GNUPLOT, else gnuplot from PATH");
  YamlOptionTable video("outputs.video");
  video.Add("fps", &o.video.fps, AnimationOptions::kFpsRange, "a playback frame rate",
            "Playback rate of the animations (the footage plays in slow motion)");
  video.AddCustom(
      "h264_fourccs", "four-character codes separated by commas", Join(o.video.h264_fourccs, ","),
      [&o](const YAML::Node& n) {
        std::vector<std::string> codes;
        const bool ok =
            ReadListItems(n, &codes) && !codes.empty() &&
            std::all_of(codes.begin(), codes.end(), [](const auto& c) { return c.size() == 4; });
        if (ok) o.video.h264_fourccs = codes;
        return ok;
      },
      "The H.264 encoders tried in order (OpenCV fourccs)");
  video.AddChoice(
      "codec", kVideoCodecNames.Names(), ToString(o.video.codec),
      [&o](const std::string& v) { o.video.codec = VideoCodecFromString(v); },
      "auto (H.264 MP4, else MJPG AVI), h264 (or fail) or mjpg");
  YamlOptionTable velocity("outputs.velocity_map");
  VelocityOverlayOptions& v = o.velocity_map;
  velocity.Add("opacity", &v.opacity, kOverlayOpacityRange, "an opacity",
               "Opacity of the colour map over the frame");
  AddAutoNumber(velocity, "max_speed_mm_s", &v.max_speed_mm_s,
                ValueRange{0, 1e300, "mm/s", /*min_open=*/true}, "a speed",
                "Top of the colour scale; auto: the 99th percentile of the valid speeds");
  velocity.AddChoice(
      "unit", {"auto", "mm/s", "m/s"}, ToString(v.unit),
      [&v](const std::string& u) { v.unit = VelocityDisplayUnitFromString(u); },
      "Unit of the colour bar; auto: m/s when the scale's top is >= 1000 mm/s");
  velocity.Add("arrows", &v.arrows, "Arrows of the displacement direction");
  velocity.Add("arrow_spacing_px", &v.arrow_spacing_display_px,
               VelocityOverlayOptions::kArrowSpacingRange, "an arrow spacing",
               "Least distance between arrows on the display (denser grids are thinned)");
  AddDisplayKeys(velocity, &v.min_width_px, &v.max_width_px, &v.contrast_low_percentile,
                 &v.contrast_high_percentile);
  YamlOptionTable strain("outputs.strain_map");
  StrainOverlayOptions& m = o.strain_map;
  strain.Add("opacity", &m.opacity, kOverlayOpacityRange, "an opacity",
             "Opacity of the colour maps over the frame");
  AddAutoNumber(strain, "eps_v_limit", &m.eps_v_limit, ValueRange{0, 1e300, "", true},
                "a volumetric strain", "Colour limits of eps_v (+-); auto: from `percentile`");
  AddAutoNumber(strain, "gamma_max_limit", &m.gamma_max_limit, ValueRange{0, 1e300, "", true},
                "a shear strain", "Top of the gamma_max colours; auto: from `percentile`");
  strain.Add("percentile", &m.percentile, StrainOverlayOptions::kPercentileRange, "a percentile",
             "auto limits: this percentile of |eps_v| (of gamma_max) over every frame");
  strain.Add("shear_bands", &m.shear_bands, "Dots at the shear-band ridges");
  AddDisplayKeys(strain, &m.min_width_px, &m.max_width_px, &m.contrast_low_percentile,
                 &m.contrast_high_percentile);
  return {plot, video, velocity, strain};
}

// `stages:` in pipeline order whatever order the file lists them in.
void ReadStages(YamlSection& top, Scene* scene) {
  const auto& all = AllSceneStages();
  const YAML::Node stages = top.Get("stages");
  if (!stages.IsDefined() || stages.IsNull()) {
    scene->stages = all;
    return;
  }
  if (!stages.IsSequence()) {
    top.Problem("stages",
                fmt::format("got {}; expected a list of stage names", DescribeYaml(stages)));
    return;
  }
  if (stages.size() == 0) {
    top.Problem("stages", "got an empty list; expected at least one of " + Join(all) +
                              " (leave the key out to run them all)");
    return;
  }
  std::map<std::string, std::size_t> first_index;  // Stage -> its first item.
  for (std::size_t k = 0; k < stages.size(); ++k) {
    const YAML::Node st = stages[k];
    const std::string name = st.IsScalar() ? st.Scalar() : "";
    if (std::find(all.begin(), all.end(), name) != all.end()) {
      const auto [first, inserted] = first_index.emplace(name, k);
      if (!inserted) {
        top.problems()->Add(st, fmt::format("stages[{}]", k),
                            fmt::format("got '{}' a second time (first as stages[{}]); expected "
                                        "each stage at most once (they run once each, in "
                                        "pipeline order)",
                                        name, first->second));
      }
      continue;
    }
    const std::string close = ClosestMatch(name, all);
    top.problems()->Add(st, "stages",
                        fmt::format("unknown stage {}{}", DescribeYaml(st),
                                    close.empty() ? "" : " (did you mean '" + close + "'?)"));
  }
  for (const auto& name : all)
    if (first_index.count(name)) scene->stages.push_back(name);
}

// A number of a list read by ReadList, reported by its own key path and value when bad
// ("dic.roi[1]: got '.nan'; must be a finite number: ...").
template <typename T>
bool ReadElement(YamlProblems* problems, const YAML::Node& n, const std::string& path,
                 const ValueRange& range, const std::string& expected, T* out) {
  if (DecodeNumber(n, range, out)) return true;
  problems->Add(n, path, NumberProblemText(n, expected));
  return false;
}

// The list `n` at `path` (absent or null: false, nothing reported): `count` items (at least
// `count` if `at_least`), else reported as a whole ("got a list of 3; expected `expected`"); each
// item is read by `item(node, its path, index)`, which reports its own problems. True if valid.
bool ReadList(YamlProblems* problems, const YAML::Node& n, const std::string& path,
              std::size_t count, bool at_least, const std::string& expected,
              const std::function<bool(const YAML::Node&, const std::string&, std::size_t)>& item) {
  if (!n.IsDefined() || n.IsNull()) return false;
  if (!n.IsSequence() || (at_least ? n.size() < count : n.size() != count)) {
    problems->Add(n, path, fmt::format("got {}; expected {}", DescribeYaml(n), expected));
    return false;
  }
  bool valid = true;
  for (std::size_t i = 0; i < n.size(); ++i)
    valid = item(n[i], fmt::format("{}[{}]", path, i), i) && valid;
  return valid;
}

// A rectangle [x0, y0, x1, y1] at `key` of `section`: four numbers (ReadElement), then x0 < x1 and
// y0 < y1 (reported with the four values). True if valid.
template <typename T>
bool ReadRectangle(YamlSection& section, const std::string& key, const ValueRange& range,
                   const std::string& element_expected, const std::string& expected,
                   std::array<T, 4>* rect) {
  YamlProblems* problems = section.problems();
  std::array<T, 4> r{};
  if (!ReadList(problems, section.Get(key), section.PathOf(key), 4, /*at_least=*/false, expected,
                [&](const YAML::Node& n, const std::string& path, std::size_t i) {
                  return ReadElement(problems, n, path, range, element_expected, &r[i]);
                }))
    return false;
  if (!(r[0] < r[2] && r[1] < r[3])) {
    section.Problem(key, fmt::format("got [{}]; expected {}", fmt::join(r, ", "), expected));
    return false;
  }
  *rect = r;
  return true;
}

// The keys that are not one field: roi, roi_polygon (dic), rect_mm (momentum).
void ReadDicRegions(YamlSection& dic, SceneDic* d) {
  std::array<int, 4> roi{};
  if (ReadRectangle(dic, "roi", ValueRange{0, 1e300, "px"}, "an integer pixel coordinate >= 0",
                    "[x0, y0, x1, y1] in pixels with 0 <= x0 < x1 and 0 <= y0 < y1", &roi))
    d->roi = roi;
  YamlProblems* problems = dic.problems();
  std::vector<std::array<double, 2>> vertices;
  const auto vertex = [&](const YAML::Node& n, const std::string& path, std::size_t) {
    std::array<double, 2> v{};
    const bool valid = ReadList(
        problems, n, path, 2, /*at_least=*/false, "a vertex [x, y] in pixels (>= 0)",
        [&](const YAML::Node& c, const std::string& c_path, std::size_t i) {
          return ReadElement(problems, c, c_path, kNonNegativePx, "a pixel coordinate >= 0", &v[i]);
        });
    vertices.push_back(v);
    return valid;
  };
  if (ReadList(problems, dic.Get("roi_polygon"), dic.PathOf("roi_polygon"), 3, /*at_least=*/true,
               "a list of at least 3 vertices [x, y] in pixels (>= 0)", vertex))
    d->roi_polygon = vertices;
}

void ReadMomentumRect(YamlSection& momentum, MomentumOptions* m) {
  std::array<double, 4> rect{};
  if (ReadRectangle(momentum, "rect_mm", ValueRange{-1e300, 1e300, "mm"}, "a position in mm",
                    "[x0, y0, x1, y1] in mm with x0 < x1 and y0 < y1", &rect))
    m->rect_mm = rect;
}

// outputs.xdmf needs outputs.hdf5: results.xdmf holds no data, its fields are views of results.h5's
// datasets (/xdmf), so it cannot be written without that file (CheckSceneOutputs).
bool XdmfWithoutHdf5(const SceneOutputs& o) { return o.xdmf && !o.hdf5; }
constexpr const char* kXdmfWithoutHdf5 = "true with outputs.hdf5 false";
constexpr const char* kXdmfNeedsHdf5 =
    "outputs.hdf5: true with it (results.xdmf's fields are views of results.h5's datasets, "
    "written only with outputs.hdf5) or outputs.xdmf: false";

// Rules across keys, and the library structs' own Check() as a last guard (it names the struct
// field; every key's range above is the struct's, so it should never fire). A key already
// reported (a bad value) is not judged again: it is not also "missing".
void CheckScene(const Scene& scene, const YAML::Node& root, YamlProblems* problems) {
  const auto reported = [problems](std::initializer_list<const char*> keys) {
    return std::any_of(keys.begin(), keys.end(),
                       [problems](const char* key) { return problems->Has(key); });
  };
  if (scene.inputs.frames.empty() && !reported({"inputs", "inputs.frames"}))
    problems->Add(root["inputs"], "inputs.frames",
                  "missing; expected a frames folder, glob or video file");
  if (!scene.test.impact_velocity_m_s && scene.test.drop_height_m <= 0 &&
      !reported({"test", "test.impact_velocity_m_s"}))
    problems->Add(root["test"], "test.drop_height_m",
                  "is 0 and no test.impact_velocity_m_s is given; expected one of them > 0");
  const SceneDic& d = scene.dic;
  if (d.last_frame >= 0 && d.last_frame <= d.first_frame &&
      !reported({"dic", "dic.first_frame", "dic.last_frame"}))
    problems->Add(
        root["dic"], "dic.last_frame",
        fmt::format("got {}; expected > dic.first_frame ({}) or -1", d.last_frame, d.first_frame));
  if (XdmfWithoutHdf5(scene.outputs) && !reported({"outputs", "outputs.hdf5", "outputs.xdmf"}))
    problems->Add(root["outputs"], "outputs.xdmf",
                  fmt::format("got {}; expected {}", kXdmfWithoutHdf5, kXdmfNeedsHdf5));
  // The momentum stage runs after the correlation: its grid must be known now.
  const SceneMomentum& m = scene.momentum;
  const bool momentum_runs = !scene.inputs.sensor.empty() && scene.HasStage("correlate") &&
                             scene.HasStage("kinematics") && scene.HasStage("sensor") &&
                             scene.HasStage("momentum");
  if (reported({"momentum", "momentum.pounder_center_x_px", "momentum.surface_y_px",
                "momentum.rect_mm", "inputs.sensor", "stages"})) {
    // Judged once the keys themselves are valid.
  } else if (m.pounder_center_x_px.has_value() != m.surface_y_px.has_value()) {
    problems->Add(root["momentum"],
                  m.pounder_center_x_px ? "momentum.surface_y_px" : "momentum.pounder_center_x_px",
                  "missing; expected both momentum.pounder_center_x_px and momentum.surface_y_px "
                  "(the pounder's position in the first frame, px) or neither");
  } else if (momentum_runs && !m.pounder_center_x_px && !m.options.rect_mm) {
    problems->Add(root["momentum"], "momentum.pounder_center_x_px / surface_y_px",
                  "missing; expected the pounder's position in the first frame (px), or "
                  "momentum.rect_mm (the momentum stage runs: a sensor CSV is given)");
  }
  if (!problems->empty()) return;
  try {
    scene.dic.options.Check();
    scene.preprocess.Check();
    MakeSensorOptions(scene);
    MakeModelParameters(scene, scene.ImpactVelocity());
    scene.solver.Check();
    scene.strain.Check();
    SceneRenderOptions(scene).Check();
  } catch (const Error& e) {
    problems->Add(root, "(options)", e.what());
  }
}

}  // namespace

void CheckSceneOutputs(const Scene& scene) {
  if (XdmfWithoutHdf5(scene.outputs))
    throw Error(ErrorKind::kInvalidValue, "outputs.xdmf", kXdmfWithoutHdf5, kXdmfNeedsHdf5)
        .WithFile(scene.path);
}

double Scene::ImpactVelocity() const {
  if (test.impact_velocity_m_s) return *test.impact_velocity_m_s;
  return std::sqrt(2.0 * model.gravity_m_s2 * test.drop_height_m);
}

bool Scene::HasStage(const std::string& stage) const {
  return std::find(stages.begin(), stages.end(), stage) != stages.end();
}

const std::vector<std::string>& AllSceneStages() {
  static const std::vector<std::string> kStages = {"calibrate",  "frames", "correlate",
                                                   "kinematics", "sensor", "momentum",
                                                   "model",      "strain", "outputs"};
  return kStages;
}

const std::vector<InternalOption>& InternalLibraryOptions() {
  static const std::vector<InternalOption> kAll = [] {
    std::vector<InternalOption> all;
    for (const auto* list : {&InternalDicOptions(), &InternalSensorOptions(),
                             &InternalMomentumOptions(), &InternalModelOptions()})
      all.insert(all.end(), list->begin(), list->end());
    return all;
  }();
  return kAll;
}

std::vector<YamlOptionTable> SceneOptionTables(Scene* scene) {
  std::vector<YamlOptionTable> tables = {InputsTable(scene), TestTable(scene)};
  for (YamlOptionTable& t : PreprocessTables(scene)) tables.push_back(std::move(t));
  for (auto make : {DicTable, SensorTable, MomentumTable, ModelTable, StrainTable, OutputsTable})
    tables.push_back(make(scene));
  for (YamlOptionTable& t : RenderTables(scene)) tables.push_back(std::move(t));
  return tables;
}

Scene LoadScene(const std::string& path) {
  return ParseScene(ReadInputFile(path, kSceneFileWhat, kMaxTextFileBytes), path);
}

Scene ParseScene(const std::string& yaml_text, const std::string& path) {
  Scene scene;
  scene.path = path;
  scene.yaml_text = yaml_text;
  scene.folder = fs::path(path).parent_path().string();
  if (scene.folder.empty()) scene.folder = ".";
  scene.name = fs::path(path).stem().string();
  scene.outputs.folder = (fs::path(scene.folder) / "results").lexically_normal().string();

  const YAML::Node root = LoadYaml(yaml_text, path, kSceneFileWhat);
  YamlProblems problems(path);
  YamlSection top(root, "", &problems);
  top.Read("name", &scene.name);
  ReadStages(top, &scene);
  // A nested table ("outputs.plot") is read from its parent's section, which is finished after
  // its children (its unknown keys reported then).
  std::map<std::string, YamlSection> parents;
  for (const YamlOptionTable& table : SceneOptionTables(&scene)) {
    const std::string& name = table.section();
    const std::size_t dot = name.find('.');
    const std::string head = name.substr(0, dot);
    YamlSection& parent = parents.try_emplace(head, top.Sub(head)).first->second;
    YamlSection nested = dot == std::string::npos ? parent : parent.Sub(name.substr(dot + 1));
    YamlSection& section = dot == std::string::npos ? parent : nested;
    table.Read(section);
    if (name == "dic") ReadDicRegions(section, &scene.dic);
    if (name == "momentum") ReadMomentumRect(section, &scene.momentum.options);
    if (dot != std::string::npos) section.Finish();
  }
  for (auto& [head, section] : parents) section.Finish();
  top.Finish();
  CheckScene(scene, root, &problems);
  problems.ThrowIfAny("scene file");
  scene.model.impact_velocity_m_s = scene.ImpactVelocity();
  return scene;
}

RenderResultsOptions SceneRenderOptions(const Scene& scene) {
  const SceneOutputs& o = scene.outputs;
  RenderResultsOptions r;
  r.figures = o.figures;
  r.snapshot = o.figures;
  r.animation = o.animation;
  r.png_frames = o.animation && o.png_frames;
  r.plot = o.plot;
  r.animation_options = o.video;
  r.animation_options.overlay = o.velocity_map;
  r.snapshot_overlay = o.velocity_map;
  r.strain_overlay = o.strain_map;
  return r;
}

SensorOptions MakeSensorOptions(const Scene& scene) {
  SensorOptions o = scene.sensor.options;
  o.g_m_s2 = scene.model.gravity_m_s2;
  if (o.integrate_from == IntegrationStart::kImpact) o.impact_velocity_m_s = scene.ImpactVelocity();
  o.expected_impact_velocity_m_s = scene.ImpactVelocity();
  o.expected_impact_velocity_source =
      scene.test.impact_velocity_m_s
          ? std::string("test.impact_velocity_m_s")
          : fmt::format("a free fall from test.drop_height_m = {:.4g} m (sqrt(2 g h))",
                        scene.test.drop_height_m);
  o.Check();
  return o;
}

WaveOptions MakeWaveOptions(const Scene& scene) {
  WaveOptions w;
  w.pounder_mass_kg = scene.model.pounder_mass_kg;
  w.pounder_width_m = scene.model.width_m;
  w.pounder_depth_m = scene.model.depth_m;
  w.g_m_s2 = scene.model.gravity_m_s2;
  w.Check();
  return w;
}

MomentumOptions MakeMomentumOptions(const Scene& scene, double mm_per_px) {
  MomentumOptions m = scene.momentum.options;
  m.pounder_mass_kg = scene.model.pounder_mass_kg;
  m.pounder_width_m = scene.model.width_m;
  m.depth_m = scene.model.depth_m;
  m.density_kg_m3 = scene.model.density_kg_m3;
  m.uncertainty.subset_size_mm = scene.dic.options.grid.subset_size * mm_per_px;
  m.uncertainty.scale_u_fraction = mm_per_px > 0 ? scene.inputs.mm_per_px_u / mm_per_px : 0.0;
  const SceneMomentum& sm = scene.momentum;
  if (sm.pounder_center_x_px && sm.surface_y_px) {
    const double cx_mm = *sm.pounder_center_x_px * mm_per_px;
    m.footprint.x_left_mm = cx_mm - 500 * scene.model.width_m;
    m.footprint.x_right_mm = cx_mm + 500 * scene.model.width_m;
    m.footprint.bottom_y_mm = *sm.surface_y_px * mm_per_px;
  } else if (!m.rect_mm) {
    throw Error(ErrorKind::kInvalidValue, "momentum.pounder_center_x_px / surface_y_px", "missing",
                "the pounder's position in the first frame (px), or momentum.rect_mm")
        .WithFile(scene.path);
  }
  m.Check();
  return m;
}

ImpactModelParameters MakeModelParameters(const Scene& scene, double impact_velocity_m_s) {
  ImpactModelParameters p = scene.model;
  p.impact_velocity_m_s = impact_velocity_m_s;
  p.Check();
  return p;
}

}  // namespace impactdic
