// RethrowWithFlagNames, RethrowWithPartialFlag, the scene key flags, one name per option and
// CheckFormat (commands.h): library field names and scene keys -> command-line flags.
#include <fmt/format.h>

#include <algorithm>
#include <cstddef>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "commands.h"
#include "impactdic/core/error.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene_flags.h"

namespace impactdic::cli {

void RethrowWithFlagNames(const Error& e, const FlagNames& flags) {
  std::string text = e.what();  // A free-form message names a field in parentheses: "(FIELD)".
  for (const auto& [field, flag] : flags) {
    if (e.where().empty()) {
      for (std::size_t at = 0; (at = text.find("(" + field + ")", at)) != std::string::npos;)
        text.replace(at + 1, field.size(), flag);
      continue;
    }
    if (e.where() != field) continue;
    Error renamed(e.kind(), flag, e.found(), e.expected());
    if (!e.file().empty()) renamed.WithFile(e.file(), e.line(), e.column());
    throw renamed;
  }
  if (text != e.what()) throw Error(e.kind(), text);
  throw e;
}

void RethrowWithPartialFlag(const PartialResultsError& e, const std::string& command) {
  throw Error(ErrorKind::kNumerical, fmt::format("{}; `impactdic {} {}` {}", e.problem(), command,
                                                 kAllowPartialFlag, e.remedy()));
}

void AddSceneKeyFlags(CLI::App* cmd, const std::vector<std::string>& sections,
                      SceneKeyValues* values) {
  AddKeyFlags(cmd, SceneKeyFlags(sections), values);
}

void ApplySceneKeyFlags(const CLI::App& cmd, const SceneKeyValues& values, Scene* scene) {
  ApplyKeyFlags(cmd, values,
                [scene](const std::string& key, const std::string& text, const std::string& flag) {
                  SetSceneKey(scene, key, text, flag);
                });
}

namespace {

// The scene keys each flag sets (SetsKeys). The commands are registered once per process.
std::map<const CLI::Option*, std::vector<std::string>>& FlagKeys() {
  static std::map<const CLI::Option*, std::vector<std::string>> keys;
  return keys;
}

// `a` is `b` or nested in it ("preprocess.gaussian.sigma" in "preprocess.gaussian"), or the
// reverse.
bool KeysOverlap(const std::string& a, const std::string& b) {
  const auto nested = [](const std::string& inner, const std::string& outer) {
    return inner.size() > outer.size() && inner.compare(0, outer.size(), outer) == 0 &&
           inner[outer.size()] == '.';
  };
  // One end of the frame range chosen by index or by the frames' own number: one option.
  static const std::vector<std::pair<std::string, std::string>> kTwoForms = {
      {"dic.first_frame", "dic.first_frame_number"}, {"dic.last_frame", "dic.last_frame_number"}};
  for (const auto& [index, number] : kTwoForms)
    if ((a == index && b == number) || (a == number && b == index)) return true;
  return a == b || nested(a, b) || nested(b, a);
}

// An option that takes one value, or none (a switch); a list (--deformed, IMAGES) takes many.
bool TakesOneValue(const CLI::Option& o) { return o.get_items_expected_max() <= 1; }

// Its names: "--subset", "-o/--output" (which of them was typed is not kept).
std::string NamesOf(const CLI::Option& o) {
  std::string names = o.get_name(/*positional=*/false, /*all=*/true);  // "-o,--output"
  std::replace(names.begin(), names.end(), ',', '/');
  return names;
}

// The flag as given on the command line: its names and, unless a switch, the value given
// (`--subset 25`, `--warp-gradient`).
std::string AsGiven(const CLI::Option& o, const std::string& value) {
  return o.get_expected_min() == 0 ? NamesOf(o) : NamesOf(o) + " " + value;
}

void CheckCommand(const CLI::App& cmd) {
  const std::vector<const CLI::Option*> given =
      cmd.get_options([](const CLI::Option* o) { return o->count() > 0; });
  for (const CLI::Option* o : given) {
    if (!TakesOneValue(*o) || o->count() < 2) continue;
    const std::vector<std::string>& values = o->results();
    throw Error(ErrorKind::kInvalidValue,
                fmt::format("{} and {}: {} given twice; expected it once (the value must not "
                            "depend on which comes last)",
                            AsGiven(*o, values[0]), AsGiven(*o, values[1]), NamesOf(*o)));
  }
  const auto& flag_keys = FlagKeys();
  for (std::size_t i = 0; i < given.size(); ++i) {
    const auto keys_i = flag_keys.find(given[i]);
    if (keys_i == flag_keys.end()) continue;
    for (std::size_t j = i + 1; j < given.size(); ++j) {
      const auto keys_j = flag_keys.find(given[j]);
      if (keys_j == flag_keys.end()) continue;
      for (const std::string& a : keys_i->second) {
        for (const std::string& b : keys_j->second) {
          if (!KeysOverlap(a, b)) continue;
          throw Error(ErrorKind::kInvalidValue,
                      fmt::format("{} and {}: both given, and both set {}; expected one of them "
                                  "(two names of one option)",
                                  AsGiven(*given[i], given[i]->results().front()),
                                  AsGiven(*given[j], given[j]->results().front()),
                                  a.size() > b.size() ? a : b));
        }
      }
    }
  }
}

}  // namespace

void SetsKeys(const CLI::Option* flag, const std::vector<std::string>& keys) {
  std::vector<std::string>& all = FlagKeys()[flag];
  all.insert(all.end(), keys.begin(), keys.end());
}

void PrepareOneNamePerOption(CLI::App* app) {
  for (CLI::Option* o : app->get_options())
    if (TakesOneValue(*o)) o->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  for (CLI::App* sub : app->get_subcommands({})) PrepareOneNamePerOption(sub);
}

void CheckOneNamePerOption(const CLI::App& app) {
  CheckCommand(app);
  for (const CLI::App* sub : app.get_subcommands()) CheckOneNamePerOption(*sub);
}

void AddKeyFlags(CLI::App* cmd, const std::vector<SceneKeyFlag>& keys, SceneKeyValues* values) {
  for (const SceneKeyFlag& f : keys) {
    std::vector<std::pair<std::string, bool>> names = {{"--" + f.key, false}};  // Name, switch.
    for (const SceneFlagAlias& a : SceneFlagAliases())
      if (cmd->get_name() == a.command && f.key == a.key) names.emplace_back(a.alias, a.is_switch);
    for (const auto& [name, is_switch] : names) {
      if (cmd->get_option_no_throw(name)) continue;  // The command binds it itself.
      const bool on_off = f.default_text == "true" || f.default_text == "false";
      auto& [key, text] = (*values)[name];
      key = f.key;
      if (is_switch) {
        SetsKeys(cmd->add_flag(name, text, "Short for " + names[0].first + " true"), {f.key});
        continue;
      }
      SetsKeys(
          cmd->add_option(name, text,
                          name == names[0].first ? f.help : "Short for " + names[0].first)
              ->default_str(on_off ? (f.default_text == "true" ? "on" : "off") : f.default_text),
          {f.key});
    }
  }
}

void ApplyKeyFlags(const CLI::App& cmd, const SceneKeyValues& values, const SetKey& set) {
  for (const auto& [flag, key_text] : values) {
    const auto& [key, text] = key_text;
    if (cmd.count(flag) > 0) set(key, text, flag);
  }
}

void CheckFormat(const std::string& format) {
  CheckValue(format == "text" || format == "json", "--format", format, "text or json");
}

}  // namespace impactdic::cli
