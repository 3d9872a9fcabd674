// RethrowWithFlagNames, RethrowWithPartialFlag, the scene key flags and CheckFormat (commands.h):
// library field names and scene keys -> command-line flags.
#include <fmt/format.h>

#include <cstddef>
#include <string>
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
        cmd->add_flag(name, text, "Short for " + names[0].first + " true");
        continue;
      }
      cmd->add_option(name, text, name == names[0].first ? f.help : "Short for " + names[0].first)
          ->default_str(on_off ? (f.default_text == "true" ? "on" : "off") : f.default_text);
    }
  }
}

void ApplyKeyFlags(const CLI::App& cmd, const SceneKeyValues& values, const SetKey& set) {
  std::map<std::string, std::string> given;  // Key -> the flag that set it.
  for (const auto& [flag, key_text] : values) {
    const auto& [key, text] = key_text;
    if (cmd.count(flag) == 0) continue;
    const auto [first, inserted] = given.emplace(key, flag);
    CheckValue(inserted, first->second + "/" + flag, "both given", "one name of " + key);
    set(key, text, flag);
  }
}

void CheckFormat(const std::string& format) {
  CheckValue(format == "text" || format == "json", "--format", format, "text or json");
}

}  // namespace impactdic::cli
