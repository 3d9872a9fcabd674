// impactdic analyze: the accelerometer record alone (--sensor CSV), or a scene's analysis from its
// correlation results (SCENE.yaml: the stages of `run` after the correlation, through the one
// stage graph, pipeline/scene_analysis.h; exit 1 when a stage produced nothing usable, as `run`,
// unless --allow-partial).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <system_error>

#include "commands.h"
#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/range.h"
#include "impactdic/core/strings.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/pipeline/scene_analysis.h"
#include "impactdic/sensor/sensor.h"
#include "impactdic/sensor/sensor_results.h"

namespace impactdic::cli {
namespace {

// Defaults: the sensor library's SensorOptions, except --accel-column (empty: the first of
// accel_g, accel_m_s2 in the file). The scene's sensor.* and momentum.* keys are flags (`keys`);
// --cutoff and --accel-column are bound here (the library's check of the cut-off, the column's
// automatic choice).
struct AnalyzeArgs {
  std::string scene;
  std::string sensor;
  bool from_release = false;
  std::optional<double> impact_velocity;
  double cutoff = SensorOptions{}.cutoff_hz;
  std::string format = "text";
  std::string accel_column;
  std::string offset_reference = ToString(SensorOptions{}.offset_reference);
  std::optional<double> release_time;
  double impact_threshold = SensorOptions{}.impact_threshold_g;
  std::string output;
  std::string results;
  bool allow_partial = false;
  SceneKeyValues keys;  // --sensor.*, --momentum.* and their aliases.
};

// The name `key` was given under in `cmd` ("--cutoff" or "--sensor.cutoff_hz"), empty if none.
std::string GivenName(const CLI::App& cmd, const std::string& key) {
  if (cmd.count("--" + key) > 0) return "--" + key;
  const std::string alias = SceneFlagShortName(cmd.get_name(), key);
  return cmd.count(alias) > 0 ? alias : "";
}

// The keys bound in AnalyzeArgs, set into `scene` when given.
void ApplyBoundKeys(const AnalyzeArgs& a, const CLI::App& cmd, Scene* scene) {
  if (!GivenName(cmd, "sensor.cutoff_hz").empty()) scene->sensor.options.cutoff_hz = a.cutoff;
  if (!GivenName(cmd, "sensor.accel_column").empty())
    scene->sensor.options.columns.accel = a.accel_column;
}

// A folder of outputs written as one generation (`run`'s, a campaign test's results/: its
// summary.json, figures and results.h5 describe one analysis) is never changed file by file:
// analyze writes its own file instead. Error naming `option` if `path` (the file analyze would
// write) lies in such a folder.
void CheckNotInAGeneration(const std::string& path, const std::string& option) {
  namespace fs = std::filesystem;
  const fs::path folder = fs::absolute(path).parent_path();
  std::error_code ec;
  const bool summary = fs::exists(folder / "summary.json", ec);
  if (!summary && !fs::exists(folder / kOutputMarkerName, ec)) return;
  throw Error(ErrorKind::kInvalidValue, option,
              path + ", in a folder of outputs written together by impactdic (" +
                  (summary ? "with its summary.json" : "one generation") +
                  "): writing one file of it alone would leave the other files describing another "
                  "analysis",
              "a file of its own for this analysis (--output NEW.h5 outside that folder), or "
              "`impactdic run` to redo the whole folder");
}

// The library's names of the sensor options -> the flags of `cmd` that set them (the name given
// for a scene key, else its alias).
FlagNames SensorFlagNames(const CLI::App& cmd) {
  FlagNames names = {{"sensor.impact_threshold_g", "--impact-threshold"},
                     {"sensor.impact_velocity_m_s", "--impact-velocity"},
                     {"sensor.release_time_s", "--release-time"},
                     {"offset_reference", "--offset-reference"}};
  for (const auto& [field, key] : FlagNames{{"sensor.cutoff_hz", "sensor.cutoff_hz"},
                                            {"sensor.quiet_window_s", "sensor.quiet_window_s"},
                                            {"sensor.columns.time", "sensor.time_column"},
                                            {"accel_unit", "sensor.accel_unit"}}) {
    const std::string given = GivenName(cmd, key);
    names.emplace_back(field, given.empty() ? SceneFlagShortName(cmd.get_name(), key) : given);
  }
  return names;
}

// The flags of the SCENE form only: the momentum.* keys and the sensor keys that need frames or
// a scene's test (--from-release / --impact-velocity say where the --sensor form integrates from).
bool IsSceneOnlyKey(const std::string& key) {
  return key.rfind("momentum.", 0) == 0 || key == "sensor.integrate_from" ||
         key == "sensor.frame_time_offset_s";
}

// The sensor-only form: every option checked before the file is read.
SensorOptions ValidatedSensorOptions(const AnalyzeArgs& a, const CLI::App& cmd) {
  if (a.from_release == a.impact_velocity.has_value()) {
    throw Error(ErrorKind::kInvalidValue, "--from-release / --impact-velocity",
                a.from_release ? "both given" : "neither given",
                "exactly one: integrate from the release (v = 0) or from the impact with the "
                "given impact velocity [m/s]");
  }
  if (a.impact_velocity)
    CheckRange(*a.impact_velocity, kImpactVelocityRange, "--impact-velocity", "an impact velocity");
  if (a.release_time && !a.from_release) {
    throw Error(ErrorKind::kInvalidValue, "--release-time", "without --from-release",
                "--release-time only with --from-release");
  }
  if (!a.output.empty()) {
    CheckOutputLocation(a.output, {"--output", {".h5", ".hdf5"}, {a.sensor}});
    CheckNotInAGeneration(a.output, "--output");
  }
  for (const char* scene_only : {"--results", "--allow-partial"}) {
    if (cmd.count(scene_only) > 0) {
      throw Error(ErrorKind::kInvalidValue, scene_only, "with --sensor",
                  std::string(scene_only) + " only with the SCENE.yaml form");
    }
  }
  for (const auto& [flag, key_text] : a.keys) {
    if (cmd.count(flag) > 0 && IsSceneOnlyKey(key_text.first)) {
      throw Error(ErrorKind::kInvalidValue, flag, "with --sensor",
                  flag + " only with the SCENE.yaml form");
    }
  }
  // The library defaults, the accelerometer column chosen from the file unless given.
  Scene defaults;
  defaults.sensor.options.columns.accel.clear();
  ApplySceneKeyFlags(cmd, a.keys, &defaults);
  ApplyBoundKeys(a, cmd, &defaults);
  SensorOptions o = defaults.sensor.options;
  o.impact_threshold_g = a.impact_threshold;
  if (a.from_release) {
    o.integrate_from = IntegrationStart::kRelease;
    if (a.release_time) o.release_time_s = *a.release_time;
  } else {
    o.integrate_from = IntegrationStart::kImpact;
    o.impact_velocity_m_s = *a.impact_velocity;
  }
  // The library's parsers and checks (the allowed values are defined there), naming the flags.
  WithFlagNames(SensorFlagNames(cmd), [&] {
    o.offset_reference = OffsetReferenceFromString(a.offset_reference);
    o.Check();
  });
  return o;
}

void RunSensorForm(const AnalyzeArgs& a, const CLI::App& cmd, const SensorOptions& o) {
  if (!std::filesystem::exists(a.sensor)) {
    throw Error(ErrorKind::kFileNotFound, "--sensor", a.sensor, "an existing DAQ CSV file")
        .WithFile(a.sensor);
  }
  const SensorResult r =
      WithFlagNames(SensorFlagNames(cmd), [&] { return AnalyzeSensorCsv(a.sensor, o); });
  const SensorSummary& s = r.summary;
  if (!a.output.empty()) {
    // Only /sensor is replaced: /dic, /frames, ... of an existing results file stay.
    H5Writer out(a.output, /*owned_groups=*/{results_layout::kSensorGroup});
    WriteSensor(out, r);
    out.Commit();
  }
  if (a.format == "json") {
    std::cout << SensorReportJson(s, o).Dump() << "\n";
  } else {
    std::cout << "sensor record " << a.sensor << "\n"
              << "integration from " << ToString(o.integrate_from) << ", offset from "
              << ToString(o.offset_reference) << "\n"
              << s.FullReport();
  }
}

void RunSceneForm(const AnalyzeArgs& a, const CLI::App& cmd) {
  for (const char* sensor_only : {"--from-release", "--impact-velocity", "--release-time",
                                  "--offset-reference", "--impact-threshold"}) {
    if (cmd.count(sensor_only) > 0) {
      throw Error(ErrorKind::kInvalidValue, sensor_only, "with SCENE.yaml",
                  "this option only with --sensor (the scene file and its sensor.* flags set "
                  "the sensor options)");
    }
  }
  if (!a.results.empty() && !EndsWith(a.results, ".h5") && !EndsWith(a.results, ".hdf5")) {
    throw Error(ErrorKind::kInvalidValue, "--results", a.results, "an HDF5 file (.h5, .hdf5)");
  }
  Scene scene = LoadScene(a.scene);
  // The sensor.* and momentum.* flags given override the scene file's values.
  ApplySceneKeyFlags(cmd, a.keys, &scene);
  ApplyBoundKeys(a, cmd, &scene);
  WithFlagNames(SensorFlagNames(cmd), [&] { MakeSensorOptions(scene); });
  const std::string results =
      a.results.empty() ? (std::filesystem::path(scene.outputs.folder) / "results.h5").string()
                        : a.results;
  const std::string results_option = a.results.empty() ? "outputs.folder" : "--results";
  CheckResultsAreOfScene(scene, results, results_option);
  if (a.output.empty()) {
    CheckNotInAGeneration(results, results_option);
  } else {
    CheckOutputLocation(a.output,
                        {"--output", {".h5", ".hdf5"}, {scene.path, scene.inputs.sensor, results}});
    CheckNotInAGeneration(a.output, "--output");
    // Replaced whole by the analysis: never another scene's file (nor one that is not HDF5).
    if (std::filesystem::exists(a.output)) CheckResultsAreOfScene(scene, a.output, "--output");
  }
  SceneAnalysisRun run;
  try {
    run = AnalyzeSceneResults(scene, results, a.allow_partial, a.output);
  } catch (const PartialResultsError& e) {
    RethrowWithPartialFlag(e, "analyze");
  }
  if (!run.summary.IsUsable())
    LogWarning("analyze: partial results (--allow-partial): {}", run.summary.FailureText());
  // The stages analyze requires ran (AnalyzeSceneResults checks that the scene lists them).
  std::cout << (a.format == "json" ? run.ToJson().Dump() + "\n" : run.FullReport(scene.path));
}

}  // namespace

void RegisterAnalyzeCommand(CLI::App& app) {
  auto args = std::make_shared<AnalyzeArgs>();
  auto* cmd = app.add_subcommand(
      "analyze",
      "Accelerometer analysis (--sensor CSV), or a scene's kinematics and momentum validation "
      "from its correlation results (SCENE.yaml)");
  cmd->add_option("SCENE", args->scene,
                  "scene YAML: reads the correlation results and the sensor CSV, writes "
                  "/sensor, /kinematics, /momentum (and /model, /strain when the scene has "
                  "them) into the results HDF5");
  cmd->add_option("--sensor", args->sensor, "DAQ CSV (time_s, accel_g [, exposure, force*])");
  cmd->add_flag("--from-release", args->from_release,
                "integrate from the release (v = 0; the record starts at rest, or give "
                "--release-time)");
  cmd->add_option("--impact-velocity", args->impact_velocity,
                  "integrate from the detected impact with this velocity [m/s]");
  AddSceneKeyOption(cmd, "sensor.cutoff_hz", &args->cutoff, "low-pass cut-off [Hz]",
                    fmt::format("{}", args->cutoff));
  cmd->add_option("--format", args->format, "output format: text or json (default text)");
  AddSceneKeyOption(cmd, "sensor.accel_column", &args->accel_column,
                    "acceleration column (default: accel_g, else accel_m_s2; SCENE: the scene's)");
  cmd->add_option("--offset-reference", args->offset_reference,
                  "what reads a known level: free-fall (the whole free fall reads 0 g), "
                  "free-fall-window (the quiet window before the impact reads 0 g), rest (the "
                  "record start reads 1 g) or none")
      ->capture_default_str();
  cmd->add_option("--release-time", args->release_time,
                  "release time on the DAQ clock [s] (with --from-release, instead of the "
                  "detected one; inside the record and before the impact)");
  cmd->add_option("--impact-threshold", args->impact_threshold,
                  "reading [g] that is certainly the impact; the onset is found before it")
      ->capture_default_str();
  cmd->add_option("--output", args->output,
                  "--sensor: also write the sensor series to this HDF5 file; SCENE: write the "
                  "analysis into this new HDF5 file (a copy of the results file with /sensor, "
                  "/kinematics, /momentum) instead of updating the results file");
  cmd->add_option("--results", args->results,
                  "correlation results HDF5 of the scene (default <outputs.folder>/results.h5)");
  cmd->add_flag(kAllowPartialFlag, args->allow_partial,
                "SCENE form: write the results (exit 0) even when t_e is not measurable, with the "
                "figures that depend on it NaN; without it such an analysis fails (exit 1) and "
                "the results file is left as it was, as with `impactdic run`");
  // The other sensor.* and momentum.* keys; in the SCENE form they override the scene file.
  AddSceneKeyFlags(cmd, {"sensor", "momentum"}, &args->keys);
  cmd->callback([args, cmd] {
    const AnalyzeArgs& a = *args;
    CheckFormat(a.format);
    if (a.scene.empty() == a.sensor.empty()) {
      throw Error(ErrorKind::kInvalidValue, "SCENE / --sensor",
                  a.scene.empty() ? "neither given" : "both given",
                  "either a scene file (momentum analysis) or --sensor CSV (accelerometer only)");
    }
    if (!a.sensor.empty()) {
      const SensorOptions o = ValidatedSensorOptions(a, *cmd);
      RunSensorForm(a, *cmd, o);
    } else {
      RunSceneForm(a, *cmd);
    }
  });
}

}  // namespace impactdic::cli
