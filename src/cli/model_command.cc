// impactdic model: the added-mass impact model (Eq. 9, docs/model.md) for one test, the
// work-precision study of its solvers, or the paper's 27 combinations (Table 1). The flags fill a
// ModelRequest (pipeline/model_runs.h), which the library checks and runs.
#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "impactdic/pipeline/model_runs.h"
#include "impactdic/pipeline/scene_flags.h"

namespace impactdic::cli {

void RegisterModelCommand(CLI::App& app) {
  auto request = std::make_shared<ModelRequest>();
  auto* cmd = app.add_subcommand(
      "model",
      "Simulate the added-mass impact model (Eq. 9): one test, the solvers' work-precision study "
      "(--work-precision) or the paper's 27 combinations (--table1)");
  // The test.* and model.* keys (the option table: name, help and default; the required inputs of
  // a single run show none): numbers, the solver's names as text, ode45_defaults as a switch.
  for (const SceneKeyFlag& f : SceneKeyFlags({"test", "model"})) {
    const bool required = f.key == "test.mass_kg" || f.key == "test.width_m" ||
                          f.key == "test.drop_height_m" || f.key == "test.impact_velocity_m_s";
    if (f.key == "model.solver" || f.key == "model.error_estimator") {
      AddSceneKeyOption(cmd, f.key,
                        f.key == "model.solver" ? &request->solver : &request->error_estimator,
                        f.help, f.default_text);
    } else if (f.key == "model.ode45_defaults") {
      SetsKeys(cmd->add_flag("--" + f.key, request->ode45_defaults, f.help), {f.key});
      SetsKeys(cmd->add_flag(SceneFlagShortName("model", f.key), request->ode45_defaults,
                             "Short for --" + f.key),
               {f.key});
    } else {
      AddSceneKeyOption(cmd, f.key, &request->keys[f.key], f.help, required ? "" : f.default_text);
    }
  }
  cmd->add_option("--format", request->format, "text | json (default text)");
  cmd->add_option("-o,--output", request->output,
                  "single run: time series SERIES.csv | SERIES.h5; --work-precision / --table1: "
                  "TABLE.csv");
  cmd->add_flag("--work-precision", request->work_precision,
                "error vs cost of every solver at rtol 1e-3 .. 1e-12 on the exact cases, the "
                "default case and the 27 combinations");
  cmd->add_option("--plot", request->plot, "with --work-precision: FIGURE.png (gnuplot)");
  cmd->add_option("--wp-solvers", request->wp_solvers,
                  "with --work-precision: solvers (default dopri5,stiff,auto,ode45)");
  cmd->add_option("--wp-cases", request->wp_cases,
                  "with --work-precision: cases (default exact,default,table1)");
  cmd->add_option("--wp-tolerances", request->wp_tolerances,
                  "with --work-precision: rtols, in [1e-14, 0.1] (default 1e-3,1e-4,...,1e-12)");
  cmd->add_option("--wp-timing-budget", request->wp_timing_budget_s,
                  "with --work-precision: repeat each run this long, keep the fastest [s]")
      ->capture_default_str();
  cmd->add_flag(
      "--table1", request->table1,
      "the paper's 27 combinations (m_p 7/10/13 kg, h 0.2/0.7/1.2 m, D 0.10/0.15/0.20 m)");
  cmd->callback([cmd, request] {
    // Errors name each key by the flag typed for it (the key's own, else the short alias).
    for (const SceneKeyFlag& f : SceneKeyFlags({"test", "model"}))
      request->key_names[f.key] =
          cmd->count("--" + f.key) > 0 ? "--" + f.key : SceneFlagShortName("model", f.key);
    RunModelRequest(*request, std::cout);
  });
}

}  // namespace impactdic::cli
