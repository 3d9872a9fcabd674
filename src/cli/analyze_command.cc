// impactdic analyze: the accelerometer record alone (--sensor CSV), or a scene's analysis from its
// correlation results (SCENE.yaml: the stages of `run` after the correlation, through the one
// stage graph, pipeline/scene_analysis.h; exit 1 when a stage produced nothing usable, as `run`,
// unless --allow-partial).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <system_error>

#include "commands.h"
#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/range.h"
#include "impactdic/core/strings.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/json.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/momentum/momentum.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/pipeline/scene_analysis.h"
#include "impactdic/sensor/sensor.h"
#include "impactdic/sensor/sensor_results.h"

namespace impactdic::cli {
namespace {

// Defaults: the sensor library's SensorOptions, except --accel-column (empty: the first of
// accel_g, accel_m_s2 in the file).
struct AnalyzeArgs {
  std::string scene;
  std::string sensor;
  bool from_release = false;
  std::optional<double> impact_velocity;
  double cutoff = SensorOptions{}.cutoff_hz;
  std::string format = "text";
  std::string time_column = SensorOptions{}.columns.time;
  std::string accel_column;
  std::string accel_unit = ToString(SensorOptions{}.columns.accel_unit);
  std::string exposure_column = SensorOptions{}.columns.exposure;
  std::string offset_reference = ToString(SensorOptions{}.offset_reference);
  std::optional<double> release_time;
  double quiet_window = SensorOptions{}.quiet_window_s;
  double impact_threshold = SensorOptions{}.impact_threshold_g;
  std::string output;
  std::string results;
  bool allow_partial = false;
};

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

// The library's names of the options `analyze --sensor` exposes as flags.
const FlagNames kSensorFlags = {{"sensor.cutoff_hz", "--cutoff"},
                                {"sensor.quiet_window_s", "--quiet-window"},
                                {"sensor.impact_threshold_g", "--impact-threshold"},
                                {"sensor.impact_velocity_m_s", "--impact-velocity"},
                                {"sensor.release_time_s", "--release-time"},
                                {"sensor.columns.time", "--time-column"},
                                {"accel_unit", "--accel-unit"},
                                {"offset_reference", "--offset-reference"}};

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
  SensorOptions o;
  o.columns.time = a.time_column;
  o.columns.accel = a.accel_column;
  o.columns.exposure = a.exposure_column;
  o.cutoff_hz = a.cutoff;
  o.quiet_window_s = a.quiet_window;
  o.impact_threshold_g = a.impact_threshold;
  if (a.from_release) {
    o.integrate_from = IntegrationStart::kRelease;
    if (a.release_time) o.release_time_s = *a.release_time;
  } else {
    o.integrate_from = IntegrationStart::kImpact;
    o.impact_velocity_m_s = *a.impact_velocity;
  }
  // The library's parsers and checks (the allowed values are defined there), naming the flags.
  WithFlagNames(kSensorFlags, [&] {
    o.columns.accel_unit = AccelUnitFromString(a.accel_unit);
    o.offset_reference = OffsetReferenceFromString(a.offset_reference);
    o.Check();
  });
  return o;
}

void RunSensorForm(const AnalyzeArgs& a, const SensorOptions& o) {
  if (!std::filesystem::exists(a.sensor)) {
    throw Error(ErrorKind::kFileNotFound, "--sensor", a.sensor, "an existing DAQ CSV file")
        .WithFile(a.sensor);
  }
  const SensorResult r = WithFlagNames(kSensorFlags, [&] { return AnalyzeSensorCsv(a.sensor, o); });
  const SensorSummary& s = r.summary;
  if (!a.output.empty()) {
    // Only /sensor is replaced: /dic, /frames, ... of an existing results file stay.
    H5Writer out(a.output, /*owned_groups=*/{results_layout::kSensorGroup});
    WriteSensor(out, r);
    out.Commit();
  }
  if (a.format == "json") {
    JsonObject j;
    // The contract's keys first, in this order; more keys after them.
    j.Add("impact_time_s", s.impact_time_s)
        .Add("impact_velocity_m_s", s.impact_velocity_m_s)
        .Add("final_penetration_m", s.final_penetration_m)
        .Add("peak_deceleration_g", s.peak_deceleration_g)
        .Add("t_peak_s", s.t_peak_s)
        .Add("sample_rate_hz", s.sample_rate_hz)
        .Add("warnings", s.warnings)
        .Add("peak_time_daq_s", s.peak_time_s)
        .Add("stop_time_s", s.stop_time_s)
        .Add("stopped", s.stopped)
        .Add("release_time_s", s.release_time_s)
        .Add("offset_g", s.offset_g)
        .Add("noise_g", s.noise_g)
        .Add("cutoff_hz", s.cutoff_hz)
        .Add("integrate_from", ToString(o.integrate_from))
        .Add("offset_reference", ToString(o.offset_reference))
        .Add("samples", static_cast<std::int64_t>(s.samples))
        .Add("seconds", s.seconds);
    std::cout << j.Dump() << "\n";
  } else {
    std::cout << "sensor record " << a.sensor << "\n"
              << "integration from " << ToString(o.integrate_from) << ", offset from "
              << ToString(o.offset_reference) << "\n"
              << s.FullReport();
  }
}

void RunSceneForm(const AnalyzeArgs& a, const CLI::App& cmd) {
  for (const char* sensor_only :
       {"--from-release", "--impact-velocity", "--cutoff", "--release-time", "--accel-column",
        "--accel-unit", "--time-column", "--exposure-column", "--offset-reference",
        "--quiet-window", "--impact-threshold"}) {
    if (cmd.count(sensor_only) > 0) {
      throw Error(ErrorKind::kInvalidValue, sensor_only, "with SCENE.yaml",
                  "this option only with --sensor (the scene file sets the sensor options)");
    }
  }
  if (!a.results.empty() && !EndsWith(a.results, ".h5") && !EndsWith(a.results, ".hdf5")) {
    throw Error(ErrorKind::kInvalidValue, "--results", a.results, "an HDF5 file (.h5, .hdf5)");
  }
  const Scene scene = LoadScene(a.scene);
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
  const SensorSummary& s = run.data.sensor->summary;
  const MomentumSummary& m = run.data.momentum->summary;
  if (a.format == "json") {
    JsonObject j = m.ToJson();
    j.Add("impact_time_s", s.impact_time_s)
        .Add("impact_velocity_m_s", s.impact_velocity_m_s)
        .Add("final_penetration_m", s.final_penetration_m)
        .Add("results", run.results_path)
        .Add("usable", run.summary.IsUsable())
        // The analysis' key figures as `run`'s summary.json has them (measured and modelled).
        .Add("summary", run.summary.ToJson());
    std::cout << j.Dump() << "\n";
  } else {
    std::cout << "scene " << scene.path << " -> " << run.results_path << "\n"
              << s.FullReport() << m.FullReport();
    if (run.data.model) std::cout << "model: " << run.data.model->summary.BriefReport() << "\n";
  }
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
  cmd->add_option("--cutoff", args->cutoff, "low-pass cut-off [Hz]")->capture_default_str();
  cmd->add_option("--format", args->format, "output format: text or json (default text)");
  cmd->add_option("--time-column", args->time_column, "time column [s]")->capture_default_str();
  cmd->add_option("--accel-column", args->accel_column,
                  "acceleration column (default: accel_g, else accel_m_s2)");
  cmd->add_option("--accel-unit", args->accel_unit, "auto (from the column name), g or m/s^2")
      ->capture_default_str();
  cmd->add_option("--exposure-column", args->exposure_column,
                  "camera exposure column (ignored when absent)")
      ->capture_default_str();
  cmd->add_option("--offset-reference", args->offset_reference,
                  "what reads a known level: free-fall (the whole free fall reads 0 g), "
                  "free-fall-window (the quiet window before the impact reads 0 g), rest (the "
                  "record start reads 1 g) or none")
      ->capture_default_str();
  cmd->add_option("--release-time", args->release_time,
                  "release time on the DAQ clock [s] (with --from-release, instead of the "
                  "detected one; inside the record and before the impact)");
  cmd->add_option("--quiet-window", args->quiet_window, "length of the offset/noise window [s]")
      ->capture_default_str();
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
  cmd->callback([args, cmd] {
    const AnalyzeArgs& a = *args;
    if (a.format != "text" && a.format != "json") {
      throw Error(ErrorKind::kInvalidValue, "--format", a.format, "text or json");
    }
    if (a.scene.empty() == a.sensor.empty()) {
      throw Error(ErrorKind::kInvalidValue, "SCENE / --sensor",
                  a.scene.empty() ? "neither given" : "both given",
                  "either a scene file (momentum analysis) or --sensor CSV (accelerometer only)");
    }
    if (!a.sensor.empty()) {
      const SensorOptions o = ValidatedSensorOptions(a, *cmd);
      RunSensorForm(a, o);
    } else {
      RunSceneForm(a, *cmd);
    }
  });
}

}  // namespace impactdic::cli
