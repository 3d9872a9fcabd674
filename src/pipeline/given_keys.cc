#include "impactdic/pipeline/given_keys.h"

#include <string>

#include "impactdic/core/error.h"
#include "impactdic/pipeline/scene_flags.h"

namespace impactdic {
namespace {

bool IsSceneKey(const std::string& key) {
  const auto dot = key.find('.');
  if (dot == std::string::npos) return false;
  for (const SceneKeyFlag& f : SceneKeyFlags({key.substr(0, dot)}))
    if (f.key == key) return true;
  return false;
}

}  // namespace

std::string GivenKeys::Name(const std::string& key) const {
  const auto it = flags.find(key);
  return it != flags.end() ? it->second : SceneFlagShortName(command, key);
}

void GivenKeys::Add(const std::string& key, const std::string& flag) {
  const auto [first, inserted] = flags.emplace(key, flag);
  CheckValue(inserted, first->second + "/" + flag, "both given", "one name of " + key);
}

std::string SceneKeyOfFlag(const std::string& command, const std::string& flag) {
  for (const SceneFlagAlias& a : SceneFlagAliases())
    if (command == a.command && flag == a.alias) return a.key;
  if (flag.rfind("--", 0) == 0 && IsSceneKey(flag.substr(2))) return flag.substr(2);
  return "";
}

void RethrowNamingFlags(const Error& e, const GivenKeys& given, const FieldKeys& field_keys,
                        bool name_defaults) {
  std::string key = e.where();
  for (const auto& [field, field_key] : field_keys)
    if (field == key) key = field_key;
  if (given.Has(key) || (name_defaults && IsSceneKey(key))) {
    Error renamed(e.kind(), given.Name(key), e.found(), e.expected());
    if (!e.file().empty()) renamed.WithFile(e.file(), e.line(), e.column());
    throw renamed;
  }
  throw e;
}

}  // namespace impactdic
