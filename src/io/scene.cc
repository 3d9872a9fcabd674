#include "impactdic/io/scene.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <set>

#include "impactdic/core/error.h"
#include "impactdic/core/range.h"
#include "impactdic/core/threads.h"
#include "impactdic/io/input_file.h"
#include "impactdic/io/yaml.h"

namespace impactdic {
namespace fs = std::filesystem;
namespace {

// Collects every problem of a scene file, so the user sees all of them at once.
struct Problems {
  std::string file;
  std::vector<std::string> lines;
  void Add(const YAML::Node& node, const std::string& key_path, const std::string& text) {
    std::string where = file;
    if (node.IsDefined() && node.Mark().line >= 0)
      where += fmt::format(":{}", node.Mark().line + 1);
    lines.push_back(fmt::format("{}: {}: {}", where, key_path, text));
  }
};

std::string Describe(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return fmt::format("a list of {}", node.size());
  return "a map";
}

// One YAML map of the scene: typed accessors register known keys, Finish() reports the rest.
class Section {
 public:
  Section(YAML::Node node, std::string prefix, Problems* problems)
      : node_(std::move(node)), prefix_(std::move(prefix)), problems_(problems) {
    if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap()) {
      problems_->Add(node_, prefix_.empty() ? "(top level)" : prefix_,
                     fmt::format("got {}; expected a map of keys", Describe(node_)));
      node_ = YAML::Node();
    }
  }

  bool Has(const char* key) const { return node_.IsMap() && node_[key].IsDefined(); }
  std::string PathOf(const char* key) const { return prefix_.empty() ? key : prefix_ + "." + key; }

  YAML::Node Get(const char* key) {
    known_.insert(key);
    if (!node_.IsMap()) return YAML::Node();
    return node_[key];
  }

  void Number(const char* key, double* out, const std::function<bool(double)>& ok,
              const char* expected) {
    YAML::Node n = Get(key);
    if (!n.IsDefined() || n.IsNull()) return;
    double value;
    if (!n.IsScalar() || !YAML::convert<double>::decode(n, value) || !std::isfinite(value) ||
        !ok(value)) {
      problems_->Add(n, PathOf(key), fmt::format("got {}; expected {}", Describe(n), expected));
      return;
    }
    *out = value;
  }

  // A number in `range`; `what` names the quantity ("a pounder mass").
  void Number(const char* key, double* out, const ValueRange& range, const char* what) {
    const std::string expected = std::string(what) + " in " + range.Text();
    Number(
        key, out, [&range](double v) { return range.Contains(v); }, expected.c_str());
  }

  void OptionalNumber(const char* key, std::optional<double>* out,
                      const std::function<bool(double)>& ok, const char* expected) {
    double value = 0;
    const std::size_t before = problems_->lines.size();
    YAML::Node n = node_.IsMap() ? node_[key] : YAML::Node();
    Number(key, &value, ok, expected);
    if (n.IsDefined() && !n.IsNull() && problems_->lines.size() == before) *out = value;
  }

  void Integer(const char* key, int* out, const std::function<bool(int)>& ok,
               const char* expected) {
    YAML::Node n = Get(key);
    if (!n.IsDefined() || n.IsNull()) return;
    int value;
    if (!n.IsScalar() || !YAML::convert<int>::decode(n, value) || !ok(value)) {
      problems_->Add(n, PathOf(key), fmt::format("got {}; expected {}", Describe(n), expected));
      return;
    }
    *out = value;
  }

  void Bool(const char* key, bool* out) {
    YAML::Node n = Get(key);
    if (!n.IsDefined() || n.IsNull()) return;
    bool value;
    if (!n.IsScalar() || !YAML::convert<bool>::decode(n, value)) {
      problems_->Add(n, PathOf(key), fmt::format("got {}; expected true or false", Describe(n)));
      return;
    }
    *out = value;
  }

  void String(const char* key, std::string* out) {
    YAML::Node n = Get(key);
    if (!n.IsDefined() || n.IsNull()) return;
    if (!n.IsScalar()) {
      problems_->Add(n, PathOf(key), fmt::format("got {}; expected a text value", Describe(n)));
      return;
    }
    *out = n.Scalar();
  }

  void Choice(const char* key, std::string* out, const std::vector<std::string>& allowed) {
    YAML::Node n = Get(key);
    if (!n.IsDefined() || n.IsNull()) return;
    const std::string value = n.IsScalar() ? n.Scalar() : "";
    if (std::find(allowed.begin(), allowed.end(), value) == allowed.end()) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      std::string hint;
      const std::string close = ClosestMatch(value, allowed);
      if (!close.empty()) hint = fmt::format(" (did you mean '{}'?)", close);
      problems_->Add(n, PathOf(key),
                     fmt::format("got {}; expected one of {}{}", Describe(n), list, hint));
      return;
    }
    *out = value;
  }

  // A path resolved against the scene file's folder.
  void Path(const char* key, std::string* out, const std::string& folder) {
    std::string value;
    String(key, &value);
    if (value.empty()) return;
    fs::path p(value);
    *out = p.is_absolute() ? p.lexically_normal().string()
                           : (fs::path(folder) / p).lexically_normal().string();
  }

  template <std::size_t N, typename T>
  bool Array(const char* key, std::array<T, N>* out, const char* expected) {
    YAML::Node n = Get(key);
    if (!n.IsDefined() || n.IsNull()) return false;
    std::array<T, N> values{};
    bool ok = n.IsSequence() && n.size() == N;
    for (std::size_t i = 0; ok && i < N; ++i) {
      ok = n[i].IsScalar() && YAML::convert<T>::decode(n[i], values[i]);
      if constexpr (std::is_floating_point_v<T>) ok = ok && std::isfinite(values[i]);
    }
    if (!ok) {
      problems_->Add(n, PathOf(key), fmt::format("got {}; expected {}", Describe(n), expected));
      return false;
    }
    *out = values;
    return true;
  }

  Section Sub(const char* key) { return Section(Get(key), PathOf(key), problems_); }

  void Problem(const char* key, const std::string& text) {
    problems_->Add(node_.IsMap() ? node_[key] : node_, PathOf(key), text);
  }

  // Reports keys that no accessor asked for, with a "did you mean" suggestion.
  void Finish() {
    if (!node_.IsMap()) return;
    const std::vector<std::string> known(known_.begin(), known_.end());
    for (const auto& entry : node_) {
      const std::string key = entry.first.as<std::string>();
      if (known_.count(key)) continue;
      const std::string close = ClosestMatch(key, known);
      std::string text = "unknown key";
      if (!close.empty()) text += fmt::format(" (did you mean '{}'?)", close);
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      text += "; known keys here: " + list;
      problems_->Add(entry.first, prefix_.empty() ? key : prefix_ + "." + key, text);
    }
  }

 private:
  YAML::Node node_;
  std::string prefix_;
  Problems* problems_;
  std::set<std::string> known_;
};

constexpr const char* kSceneFileWhat = "a scene file (YAML)";

bool Positive(double v) { return v > 0; }
bool NonNegative(double v) { return v >= 0; }

// Optimal-string-alignment distance: insertions, deletions, substitutions and transpositions of
// neighbouring letters each cost 1 (so "tset" is one edit from "test").
std::size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[a.size()][b.size()];
}

bool ValidReferenceUpdate(const std::string& value) {
  if (value == "fixed" || value == "incremental" || value == "auto") return true;
  if (value.rfind("every:", 0) != 0) return false;
  const std::string n = value.substr(6);
  return !n.empty() && n.size() < 7 && std::all_of(n.begin(), n.end(), ::isdigit) &&
         std::stoi(n) >= 1;
}

}  // namespace

double SceneTest::ImpactVelocity() const {
  if (impact_velocity_m_s) return *impact_velocity_m_s;
  return std::sqrt(2.0 * g_m_s2 * drop_height_m);
}

bool Scene::HasStage(const std::string& stage) const {
  return std::find(stages.begin(), stages.end(), stage) != stages.end();
}

const std::vector<std::string>& AllSceneStages() {
  static const std::vector<std::string> kStages = {
      "calibrate", "frames", "correlate", "kinematics", "sensor", "momentum", "model", "outputs"};
  return kStages;
}

std::string ClosestMatch(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_distance = std::string::npos;
  for (const auto& c : candidates) {
    const std::size_t d = EditDistance(word, c);
    if (d < best_distance) {
      best_distance = d;
      best = c;
    }
  }
  // Close enough: at most a third of the word's letters differ (at least 1, at most 3 edits).
  const std::size_t limit = std::clamp<std::size_t>(word.size() / 3, 1, 3);
  return best_distance <= limit ? best : "";
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
  Problems problems{path, {}};
  Section top(root, "", &problems);
  const std::string& folder = scene.folder;

  top.String("name", &scene.name);

  Section in = top.Sub("inputs");
  in.Path("frames", &scene.inputs.frames, folder);
  in.Number("fps", &scene.inputs.fps, kCameraFpsRange, "a camera frame rate");
  in.Path("calibration", &scene.inputs.calibration, folder);
  in.Number("mm_per_px", &scene.inputs.mm_per_px, kMmPerPxRange, "an image scale");
  in.Path("sensor", &scene.inputs.sensor, folder);
  in.Path("truth", &scene.inputs.truth, folder);
  in.Finish();
  if (scene.inputs.frames.empty()) {
    problems.Add(root["inputs"], "inputs.frames",
                 "missing; expected a frames folder, glob or video file");
  }

  Section t = top.Sub("test");
  SceneTest& test = scene.test;
  t.Number("mass_kg", &test.mass_kg, kPounderMassRange, "a pounder mass");
  t.Number("drop_height_m", &test.drop_height_m, kDropHeightRange, "a drop height");
  t.OptionalNumber(
      "impact_velocity_m_s", &test.impact_velocity_m_s,
      [](double v) { return kImpactVelocityRange.Contains(v); },
      ("an impact velocity in " + kImpactVelocityRange.Text()).c_str());
  t.Number("width_m", &test.width_m, kPounderSizeRange, "a pounder width D");
  t.Number("depth_m", &test.depth_m, kPounderSizeRange, "an out-of-plane depth t_z");
  t.Number("density_kg_m3", &test.density_kg_m3, kSoilDensityRange, "a dry density");
  t.Number("bed_height_m", &test.bed_height_m, kBedHeightRange, "a bed height");
  t.Number(
      "g_m_s2", &test.g_m_s2, [](double v) { return v > 0 && kGravityRange.Contains(v); },
      ("a gravitational acceleration > 0 in " + kGravityRange.Text()).c_str());
  t.Finish();
  if (!test.impact_velocity_m_s && test.drop_height_m <= 0) {
    problems.Add(root["test"], "test.drop_height_m",
                 "is 0 and no test.impact_velocity_m_s is given; expected one of them > 0");
  }

  YAML::Node stages = top.Get("stages");
  if (stages.IsDefined() && !stages.IsNull()) {
    if (!stages.IsSequence()) {
      problems.Add(stages, "stages",
                   fmt::format("got {}; expected a list of stage names", Describe(stages)));
    } else {
      for (const auto& s : stages) {
        const std::string name = s.IsScalar() ? s.Scalar() : "";
        const auto& all = AllSceneStages();
        if (std::find(all.begin(), all.end(), name) == all.end()) {
          std::string hint;
          const std::string close = ClosestMatch(name, all);
          if (!close.empty()) hint = fmt::format(" (did you mean '{}'?)", close);
          problems.Add(s, "stages", fmt::format("unknown stage {}{}", Describe(s), hint));
        } else {
          scene.stages.push_back(name);
        }
      }
    }
  } else {
    scene.stages = AllSceneStages();
  }
  // Keep pipeline order whatever order the file lists them in.
  std::vector<std::string> ordered;
  for (const auto& s : AllSceneStages())
    if (scene.HasStage(s)) ordered.push_back(s);
  scene.stages = ordered;

  Section pre = top.Sub("preprocess");
  {
    Section gauss = pre.Sub("gaussian");
    gauss.Bool("enabled", &scene.preprocess.gaussian);
    gauss.Number("sigma", &scene.preprocess.gaussian_sigma, Positive, "a sigma > 0 [px]");
    gauss.Integer(
        "kernel", &scene.preprocess.gaussian_kernel, [](int k) { return k >= 3 && k % 2 == 1; },
        "an odd kernel size >= 3 [px]");
    gauss.Finish();
    Section clahe = pre.Sub("clahe");
    clahe.Bool("enabled", &scene.preprocess.clahe);
    clahe.Number("clip_limit", &scene.preprocess.clahe_clip_limit, Positive, "a clip limit > 0");
    clahe.Integer(
        "tile_grid", &scene.preprocess.clahe_tile_grid, [](int k) { return k >= 1; },
        "tiles per side >= 1");
    clahe.Finish();
  }
  pre.Finish();

  Section dic = top.Sub("dic");
  SceneDic& d = scene.dic;
  dic.Integer(
      "subset_size", &d.subset_size, [](int s) { return s >= 5 && s % 2 == 1; },
      "an odd subset size >= 5 [px]");
  dic.Integer(
      "step", &d.step, [](int s) { return s >= 1; }, "a grid step >= 1 [px]");
  if (dic.Array<4, int>("roi", &d.roi, "[x0, y0, x1, y1] in pixels with x0 < x1, y0 < y1")) {
    if (!(d.roi[0] >= 0 && d.roi[1] >= 0 && d.roi[0] < d.roi[2] && d.roi[1] < d.roi[3])) {
      dic.Problem("roi", fmt::format("got [{}, {}, {}, {}]; expected 0 <= x0 < x1 and 0 <= y0 < y1",
                                     d.roi[0], d.roi[1], d.roi[2], d.roi[3]));
    }
  }
  {
    YAML::Node n = dic.Get("roi_polygon");
    if (n.IsDefined() && !n.IsNull()) {
      std::vector<std::array<double, 2>> vertices;
      bool ok = n.IsSequence() && n.size() >= 3;
      for (std::size_t i = 0; ok && i < n.size(); ++i) {
        std::array<double, 2> v{};
        ok = n[i].IsSequence() && n[i].size() == 2 && n[i][0].IsScalar() && n[i][1].IsScalar() &&
             YAML::convert<double>::decode(n[i][0], v[0]) &&
             YAML::convert<double>::decode(n[i][1], v[1]) && std::isfinite(v[0]) &&
             std::isfinite(v[1]) && v[0] >= 0 && v[1] >= 0;
        vertices.push_back(v);
      }
      if (ok) {
        d.roi_polygon = vertices;
      } else {
        problems.Add(n, "dic.roi_polygon",
                     fmt::format("got {}; expected a list of at least 3 vertices [x, y] in "
                                 "pixels (>= 0)",
                                 Describe(n)));
      }
    }
  }
  dic.Path("mask", &d.mask, folder);
  dic.Choice("interpolation", &d.interpolation, {"bicubic", "biquintic"});
  dic.Choice("shape", &d.shape, {"affine", "quadratic"});
  {
    YAML::Node n = dic.Get("reference_update");
    if (n.IsDefined() && !n.IsNull()) {
      if (n.IsScalar() && ValidReferenceUpdate(n.Scalar())) {
        d.reference_update = n.Scalar();
      } else {
        problems.Add(n, "dic.reference_update",
                     fmt::format("got {}; expected fixed, incremental, every:N (N >= 1) or auto",
                                 Describe(n)));
      }
    }
  }
  dic.Number(
      "min_zncc", &d.min_zncc, [](double v) { return v > 0 && v < 1; },
      "a ZNCC threshold in (0, 1)");
  {
    YAML::Node n = dic.Get("max_uncertainty_px");
    if (n.IsDefined() && !n.IsNull()) {
      double value = 0;
      if (n.IsScalar() && n.Scalar() == "none") {
        d.max_uncertainty_px = std::numeric_limits<double>::infinity();
      } else if (n.IsScalar() && YAML::convert<double>::decode(n, value) && std::isfinite(value) &&
                 value >= 0) {
        d.max_uncertainty_px = value;
      } else {
        problems.Add(n, "dic.max_uncertainty_px",
                     fmt::format("got {}; expected an uncertainty limit >= 0 [px], or none (0 "
                                 "and none: no limit)",
                                 Describe(n)));
      }
    }
  }
  dic.Integer(
      "max_iterations", &d.max_iterations, [](int v) { return v >= 1; }, "an iteration cap >= 1");
  dic.Number("convergence_px", &d.convergence_px, Positive, "a convergence threshold > 0 [px]");
  dic.Integer(
      "search_radius_px", &d.search_radius_px, [](int v) { return v >= 1; },
      "a search radius >= 1 [px]");
  dic.Integer("threads", &d.threads, IsValidThreadCount, kThreadCountExpected);
  dic.Integer(
      "first_frame", &d.first_frame, [](int v) { return v >= 0; }, "a frame index >= 0");
  dic.Integer(
      "last_frame", &d.last_frame, [](int v) { return v >= -1; },
      "a frame index >= 0, or -1 for the last frame");
  dic.Finish();
  if (d.last_frame >= 0 && d.last_frame <= d.first_frame) {
    problems.Add(
        root["dic"], "dic.last_frame",
        fmt::format("got {}; expected > dic.first_frame ({}) or -1", d.last_frame, d.first_frame));
  }

  Section sen = top.Sub("sensor");
  SceneSensor& s = scene.sensor;
  sen.String("time_column", &s.time_column);
  sen.String("accel_column", &s.accel_column);
  sen.Choice("accel_unit", &s.accel_unit, {"g", "m/s^2"});
  sen.String("exposure_column", &s.exposure_column);
  sen.Number("cutoff_hz", &s.cutoff_hz, Positive, "a cut-off frequency > 0 [Hz]");
  sen.Choice("integrate_from", &s.integrate_from, {"release", "impact"});
  sen.Number(
      "frame_time_offset_s", &s.frame_time_offset_s, [](double) { return true; },
      "a time [s] of frame 0 on the DAQ clock");
  sen.Number("quiet_window_s", &s.quiet_window_s, Positive, "a window length > 0 [s]");
  sen.Finish();

  Section mom = top.Sub("momentum");
  mom.OptionalNumber("pounder_center_x_px", &scene.momentum.pounder_center_x_px, NonNegative,
                     "a pixel column >= 0");
  mom.OptionalNumber("surface_y_px", &scene.momentum.surface_y_px, NonNegative, "a pixel row >= 0");
  mom.Integer(
      "grid_cols", &scene.momentum.grid_cols, [](int v) { return v >= 1; }, "a subset count >= 1");
  mom.Integer(
      "grid_rows", &scene.momentum.grid_rows, [](int v) { return v >= 1; }, "a subset count >= 1");
  std::array<double, 4> rect{};
  if (mom.Array<4, double>("rect_mm", &rect, "[x0, y0, x1, y1] in mm with x0 < x1, y0 < y1")) {
    if (rect[0] < rect[2] && rect[1] < rect[3]) {
      scene.momentum.rect_mm = rect;
    } else {
      mom.Problem("rect_mm", "expected x0 < x1 and y0 < y1");
    }
  }
  mom.OptionalNumber(
      "min_valid_fraction", &scene.momentum.min_valid_fraction,
      [](double v) { return v > 0 && v <= 1; }, "a fraction of the grid's subsets in (0, 1]");
  mom.OptionalNumber(
      "max_sigma_px", &scene.momentum.max_sigma_px, [](double v) { return v > 0; },
      "a standard deviation limit > 0 [px]");
  mom.Finish();

  Section mod = top.Sub("model");
  SceneModel& m = scene.model;
  mod.OptionalNumber(
      "added_mass_kg", &m.added_mass_kg, [](double v) { return kAddedMassRange.Contains(v); },
      ("an added mass M in " + kAddedMassRange.Text()).c_str());
  mod.Number("K", &m.K, NonNegative, "a friction coefficient K >= 0");
  mod.Number(
      "n", &m.n, [](double v) { return v >= 0 && v < 1; }, "a damping exponent n in [0, 1)");
  mod.Number("u", &m.u, NonNegative, "a damping factor u >= 0");
  mod.Number("T_s", &m.T_s, NonNegative, "a sigmoid time offset T >= 0 [s]");
  mod.Number("b_per_s", &m.b_per_s, Positive, "a sigmoid steepness b > 0 [1/s]");
  mod.Choice("solver", &m.solver, {"auto", "dopri5", "stiff"});
  mod.Number(
      "rtol", &m.rtol, [](double v) { return v > 0 && v < 1; }, "a relative tolerance in (0, 1)");
  mod.Number("atol", &m.atol, Positive, "an absolute tolerance > 0");
  mod.Finish();

  Section out = top.Sub("outputs");
  out.Path("folder", &scene.outputs.folder, folder);
  out.Bool("hdf5", &scene.outputs.hdf5);
  out.Bool("csv", &scene.outputs.csv);
  out.Bool("figures", &scene.outputs.figures);
  out.Bool("animation", &scene.outputs.animation);
  out.Bool("png_frames", &scene.outputs.png_frames);
  out.Finish();

  top.Finish();

  if (!problems.lines.empty()) {
    std::string text = fmt::format("{} problem{} in scene file {}:", problems.lines.size(),
                                   problems.lines.size() == 1 ? "" : "s", path);
    for (const auto& line : problems.lines) text += "\n  " + line;
    throw Error(ErrorKind::kInvalidValue, text);
  }
  return scene;
}

}  // namespace impactdic
