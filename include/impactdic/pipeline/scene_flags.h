// The scene's keys as command-line flags: every key of the option tables (SceneOptionTables) is a
// flag named as its key path, and a command may keep the short alias it always had, listed here
// once (docs/command_line.md and `--help` show both names):
//
//   impactdic correlate --frames 'f/*.png' --dic.max_iterations 20 --subset 25 -o d.h5
//
// `--subset` is the alias of `--dic.subset_size` in `correlate`. A flag's value is read by the
// key's own parser, exactly as the key in a scene file (SetSceneKey), so the flag and the key
// accept the same values and say the same thing when refusing one.
#ifndef IMPACTDIC_PIPELINE_SCENE_FLAGS_H_
#define IMPACTDIC_PIPELINE_SCENE_FLAGS_H_

#include <string>
#include <vector>

#include "impactdic/pipeline/scene.h"

namespace impactdic {

// `alias` is the short name of scene key `key` in `command`'s flags.
struct SceneFlagAlias {
  const char* command;     // "correlate"
  const char* key;         // "dic.subset_size"
  const char* alias;       // "--subset"
  bool is_switch = false;  // Of an on/off key: given without a value, it sets true.
};
const std::vector<SceneFlagAlias>& SceneFlagAliases();

// The flag names of `key` in `command`, the key's own first: "--dic.subset_size,--subset"
// (CLI11's list of names), or "--dic.max_iterations" when it has no alias.
std::string SceneFlagNames(const std::string& command, const std::string& key);
// The name errors use for `key` in `command`: its alias ("--subset"), else "--" + key.
std::string SceneFlagShortName(const std::string& command, const std::string& key);

// One scene key as a flag: its key path, its meaning and expected values, and its default.
struct SceneKeyFlag {
  std::string key;           // "dic.max_iterations"
  std::string help;          // "IC-GN iteration cap; an integer iteration cap in [1, 10000]"
  std::string default_text;  // The library default, as the scene template shows it.
};
// The keys of the tables named `sections` or nested in them ("preprocess": preprocess.gaussian.*
// and preprocess.clahe.*), in table order.
std::vector<SceneKeyFlag> SceneKeyFlags(const std::vector<std::string>& sections);
// The same for any option tables (a command's own, e.g. calib's CalibrationOptionTables), all of
// their keys; the defaults are the bound fields' values.
std::vector<SceneKeyFlag> OptionTableFlags(const std::vector<YamlOptionTable>& tables);

// Sets `key` of `scene` from the text given to its flag `flag`, parsed as the key's value in a
// scene file (relative paths against scene->folder); dic.roi (a list in a scene file) as
// "X0,Y0,X1,Y1" [px]. Error(kInvalidValue) "FLAG: invalid value
// (got 'VALUE'); expected <the key's expected values>" otherwise; an unknown key is a programming
// error (std::logic_error).
void SetSceneKey(Scene* scene, const std::string& key, const std::string& value,
                 const std::string& flag);
// The same for the fields bound by `tables`.
void SetOptionTableKey(const std::vector<YamlOptionTable>& tables, const std::string& key,
                       const std::string& value, const std::string& flag);

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_SCENE_FLAGS_H_
