// The CLI's subcommands. Each Register* function adds one subcommand to the app: it declares and
// validates the options (naming the option, the value given and what is allowed), then calls a
// library function that tests can call directly. Errors are impactdic::Error, caught in main().
#ifndef IMPACTDIC_CLI_COMMANDS_H_
#define IMPACTDIC_CLI_COMMANDS_H_

#include <CLI/CLI.hpp>
#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"

namespace impactdic {
class PartialResultsError;  // pipeline/pipeline.h
}  // namespace impactdic

namespace impactdic::cli {

void RegisterRunCommand(CLI::App& app);
void RegisterSynthCommand(CLI::App& app);
void RegisterCalibrateCommand(CLI::App& app);
void RegisterCorrelateCommand(CLI::App& app);
void RegisterAnalyzeCommand(CLI::App& app);
void RegisterModelCommand(CLI::App& app);
void RegisterRenderCommand(CLI::App& app);
void RegisterCampaignCommand(CLI::App& app);
void RegisterValidateDemCommand(CLI::App& app);
void RegisterVersionCommand(CLI::App& app);
void RegisterInitCommand(CLI::App& app);

// Library errors name option struct fields and YAML keys ("sensor.cutoff_hz"); a command maps the
// ones it exposes as flags ({"sensor.cutoff_hz", "--cutoff"}). Throws `e` again, naming the flag
// (file and line kept) when its `where` is in `flags`, unchanged otherwise.
using FlagNames = std::vector<std::pair<std::string, std::string>>;
[[noreturn]] void RethrowWithFlagNames(const Error& e, const FlagNames& flags);

// Runs `f` (a library check, parser or stage) and returns what it returns; an Error it throws is
// thrown again naming the flag (RethrowWithFlagNames). A flag's value is thus judged by the
// library's one definition of the option:
//   WithFlagNames({{"rtol", "--rtol"}}, [&] { options.Check(); });
template <typename F>
auto WithFlagNames(const FlagNames& flags, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const Error& e) {
    RethrowWithFlagNames(e, flags);
  }
}

// The flag of `run` and `analyze` that allows partial output (the library's allow_partial).
inline constexpr const char* kAllowPartialFlag = "--allow-partial";

// The library names the option that allows partial output by its field name (`allow_partial`);
// `command` ("run", "analyze") exposes it as kAllowPartialFlag. Throws Error(kNumerical)
// "PROBLEM; `impactdic COMMAND --allow-partial` REMEDY" (PartialResultsError's two texts).
[[noreturn]] void RethrowWithPartialFlag(const PartialResultsError& e, const std::string& command);

}  // namespace impactdic::cli

#endif  // IMPACTDIC_CLI_COMMANDS_H_
