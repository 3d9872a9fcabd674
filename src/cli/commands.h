// The CLI's subcommands. Each Register* function adds one subcommand to the app: it declares and
// validates the options (naming the option, the value given and what is allowed), then calls a
// library function that tests can call directly. Errors are impactdic::Error, caught in main().
#ifndef IMPACTDIC_CLI_COMMANDS_H_
#define IMPACTDIC_CLI_COMMANDS_H_

#include <CLI/CLI.hpp>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/pipeline/scene_flags.h"

namespace impactdic {
class PartialResultsError;  // pipeline/pipeline.h
struct Scene;               // pipeline/scene.h
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

// What `impactdic --version` prints: the version, the git commit the build was configured from
// ("unknown" outside a checkout) and the IC-GN SIMD kernels built, run by this CPU and in use.
std::string VersionText();
// What `impactdic` without arguments prints: each subcommand of `app` with its one-line
// description, and where the help and the documentation are.
std::string CommandTable(const CLI::App& app);

// Library errors name option struct fields and YAML keys ("sensor.cutoff_hz"); a command maps the
// ones it exposes as flags ({"sensor.cutoff_hz", "--cutoff"}). Throws `e` again, naming the flag
// (file and line kept) when its `where` is in `flags`, or a free-form message with each "(FIELD)"
// of `flags` as "(FLAG)"; unchanged otherwise.
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

// One name per option. The scene keys a flag of a command sets (its own key, the key it is an
// alias of, or the keys a short form sets together: correlate's --gaussian sets
// preprocess.gaussian.*); a key names itself and the keys nested in it. AddKeyFlags and
// AddSceneKeyOption record theirs; a flag a command binds by hand records its own here.
void SetsKeys(const CLI::Option* flag, const std::vector<std::string>& keys);
// Call once, with every command registered: every option that takes one value (or none: a switch)
// keeps each value it is given, for CheckOneNamePerOption to judge (CLI11 would keep a switch's
// last silently, and say "At Most 1 required" of an option).
void PrepareOneNamePerOption(CLI::App* app);
// After parsing, before any command runs (the app's parse_complete_callback): Error(kInvalidValue)
// "A and B both given ..." when two flags given to the command set the same key (a key and its
// alias, two aliases, a short form and one of its keys), or "--X given twice" when one option that
// takes one value is given twice; each naming the flags as given, with their values. Whatever the
// order, no name silently wins over another.
void CheckOneNamePerOption(const CLI::App& app);

// Option-table keys as flags (pipeline/scene_flags.h): each key becomes a flag named as the key
// ("--dic.max_iterations") and one per alias of the command ("--search-radius"), unless `cmd`
// binds that name itself; their text is kept in `values` (flag -> key, text). ApplyKeyFlags
// passes the ones given to `set` (key, text, flag used: SetSceneKey, SetOptionTableKey); a key
// given under two names never gets here (CheckOneNamePerOption). The Scene forms: the scene's
// tables named `sections`.
using SceneKeyValues = std::map<std::string, std::pair<std::string, std::string>>;
using SetKey = std::function<void(const std::string&, const std::string&, const std::string&)>;
void AddKeyFlags(CLI::App* cmd, const std::vector<SceneKeyFlag>& keys, SceneKeyValues* values);
void ApplyKeyFlags(const CLI::App& cmd, const SceneKeyValues& values, const SetKey& set);
void AddSceneKeyFlags(CLI::App* cmd, const std::vector<std::string>& sections,
                      SceneKeyValues* values);
void ApplySceneKeyFlags(const CLI::App& cmd, const SceneKeyValues& values, Scene* scene);

// A scene key the command binds itself (its own type and checks): the flag "--KEY" and the
// command's aliases of it (SceneFlagAliases), all storing into `value`; giving two of them is an
// error (CheckOneNamePerOption). `default_text` (if any) is shown as their default.
template <typename T>
void AddSceneKeyOption(CLI::App* cmd, const std::string& key, T* value, const std::string& help,
                       const std::string& default_text = "") {
  std::vector<CLI::Option*> flags = {cmd->add_option("--" + key, *value, help)};
  for (const SceneFlagAlias& a : SceneFlagAliases()) {
    if (cmd->get_name() == a.command && key == a.key)
      flags.push_back(cmd->add_option(a.alias, *value, "Short for --" + key));
  }
  for (CLI::Option* flag : flags) {
    SetsKeys(flag, {key});
    if (!default_text.empty()) flag->default_str(default_text);
  }
}

// --format of a report on stdout: "text" or "json", else Error naming --format.
void CheckFormat(const std::string& format);

}  // namespace impactdic::cli

#endif  // IMPACTDIC_CLI_COMMANDS_H_
