// The scene keys a command line set, by the flag typed, so that an error about a key's value
// names what the user wrote ("--impact-velocity", "--sensor.cutoff_hz") rather than the library's
// field:
//
//   GivenKeys given{"analyze", {{"sensor.cutoff_hz", "--cutoff"}}};
//   given.Name("sensor.cutoff_hz");          // "--cutoff" (typed)
//   given.Name("sensor.impact_threshold_g");  // "--impact-threshold" (analyze's short flag)
#ifndef IMPACTDIC_PIPELINE_GIVEN_KEYS_H_
#define IMPACTDIC_PIPELINE_GIVEN_KEYS_H_

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"

namespace impactdic {

struct GivenKeys {
  std::string command;                       // "analyze": whose short flags (SceneFlagAliases)
  std::map<std::string, std::string> flags;  // Scene key -> the flag typed.

  bool Has(const std::string& key) const { return flags.count(key) > 0; }
  // The flag typed for `key`, else its short flag in `command` (SceneFlagShortName).
  std::string Name(const std::string& key) const;
  // Records that `flag` set `key`; Error naming both flags if another flag set it already.
  void Add(const std::string& key, const std::string& flag);
};

// The scene key flag `flag` of `command` sets: "--KEY" for a key of the option tables, or the key
// an alias stands for (SceneFlagAliases); empty for any other flag.
std::string SceneKeyOfFlag(const std::string& command, const std::string& flag);

// Library errors name option fields ("sensor.columns.time"); `field_keys` maps those that are not
// themselves a scene key to theirs ({"sensor.columns.time", "sensor.time_column"}). Throws `e`
// again naming given.Name(key) (file and line kept) when its field's key was given, or, with
// name_defaults, when it is any scene key (a command without a scene file: the flag is the only
// way to set it); unchanged otherwise.
using FieldKeys = std::vector<std::pair<std::string, std::string>>;
[[noreturn]] void RethrowNamingFlags(const Error& e, const GivenKeys& given,
                                     const FieldKeys& field_keys, bool name_defaults);

// Runs `f` and returns what it returns, an Error it throws renamed by RethrowNamingFlags.
template <typename F>
auto WithGivenNames(const GivenKeys& given, const FieldKeys& field_keys, bool name_defaults, F&& f)
    -> decltype(f()) {
  try {
    return f();
  } catch (const Error& e) {
    RethrowNamingFlags(e, given, field_keys, name_defaults);
  }
}

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_GIVEN_KEYS_H_
