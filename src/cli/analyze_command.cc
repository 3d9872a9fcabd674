// impactdic analyze: the accelerometer record alone (--sensor CSV), or a scene's analysis from its
// correlation results (SCENE.yaml: the stages of `run` after the correlation, through the one
// stage graph; exit 1 when a stage produced nothing usable, as `run`, unless --allow-partial).
// Both forms are scenes: the flags set its keys (pipeline/scene_analysis.h).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "impactdic/core/log.h"
#include "impactdic/pipeline/given_keys.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/pipeline/scene_analysis.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic::cli {

void RegisterAnalyzeCommand(CLI::App& app) {
  // --cutoff and --accel-column are bound here (the library's check of the cut-off, the column's
  // automatic choice); --from-release is a flag for sensor.integrate_from release.
  struct Args {
    std::string scene, sensor, format = "text", accel_column;
    double cutoff = SensorOptions{}.cutoff_hz;
    bool from_release = false;
    AnalyzeRequest request;
    SceneKeyValues keys;  // The other scene keys and their aliases.
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "analyze",
      "Accelerometer analysis (--sensor CSV), or a scene's kinematics and momentum validation "
      "from its correlation results (SCENE.yaml)");
  cmd->add_option("SCENE", args->scene,
                  "scene YAML: reads the correlation results and the sensor CSV, writes "
                  "/sensor, /kinematics, /momentum (and /model, /strain when the scene has "
                  "them) into the results HDF5");
  cmd->add_option("--sensor", args->sensor, "DAQ CSV (time_s, accel_g [, exposure, force*])");
  SetsKeys(cmd->add_flag(
               "--from-release", args->from_release,
               "Short for --sensor.integrate_from release (--sensor: this or --impact-velocity)"),
           {"sensor.integrate_from"});
  AddSceneKeyOption(cmd, "sensor.cutoff_hz", &args->cutoff, "low-pass cut-off [Hz]",
                    fmt::format("{}", args->cutoff));
  AddSceneKeyOption(cmd, "sensor.accel_column", &args->accel_column,
                    "acceleration column (default: accel_g, else accel_m_s2; SCENE: the scene's)");
  cmd->add_option("--format", args->format, "output format: text or json (default text)");
  cmd->add_option("--output", args->request.output,
                  "--sensor: also write the sensor series to this HDF5 file; SCENE: write the "
                  "analysis into this new HDF5 file (a copy of the results file with /sensor, "
                  "/kinematics, /momentum) instead of updating the results file");
  cmd->add_option("--results", args->request.results,
                  "correlation results HDF5 of the scene (default <outputs.folder>/results.h5)");
  cmd->add_flag(kAllowPartialFlag, args->request.allow_partial,
                "SCENE form: write the results (exit 0) even when t_e is not measurable, with the "
                "figures that depend on it NaN; without it such an analysis fails (exit 1) and "
                "the results file is left as it was, as with `impactdic run`");
  // The sensor.*, momentum.* and test.* keys; in the SCENE form they override the scene file.
  AddSceneKeyFlags(cmd, {"sensor", "momentum", "test"}, &args->keys);
  cmd->callback([args, cmd] {
    Args& a = *args;
    AnalyzeRequest& r = a.request;
    CheckFormat(a.format);
    r.scene = AnalyzeCommandScene(a.scene, a.sensor);
    ApplySceneKeyFlags(*cmd, a.keys, &r.scene);
    if (a.from_release) SetSceneKey(&r.scene, "sensor.integrate_from", "release", "--from-release");
    r.given.command = cmd->get_name();
    for (const CLI::Option* o : cmd->get_options()) {
      if (o->count() == 0) continue;
      const std::string key = SceneKeyOfFlag(r.given.command, o->get_name());
      if (!key.empty()) r.given.Add(key, o->get_name());
    }
    if (r.given.Has("sensor.cutoff_hz")) r.scene.sensor.options.cutoff_hz = a.cutoff;
    if (r.given.Has("sensor.accel_column")) r.scene.sensor.options.columns.accel = a.accel_column;
    if (!a.sensor.empty()) {
      const SensorRecordAnalysis s = AnalyzeSensorRecord(r);
      std::cout << (a.format == "json" ? s.ToJson().Dump() + "\n" : s.FullReport());
      return;
    }
    SceneAnalysisRun run;
    try {
      run = AnalyzeSceneResults(r);
    } catch (const PartialResultsError& e) {
      RethrowWithPartialFlag(e, "analyze");
    }
    if (!run.summary.IsUsable())
      LogWarning("analyze: partial results (--allow-partial): {}", run.summary.FailureText());
    std::cout << (a.format == "json" ? run.ToJson().Dump() + "\n" : run.FullReport(r.scene.path));
  });
}

}  // namespace impactdic::cli
