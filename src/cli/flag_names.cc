// RethrowWithFlagNames (commands.h): library field names -> command-line flags.
#include "commands.h"

namespace impactdic::cli {

void RethrowWithFlagNames(const Error& e, const FlagNames& flags) {
  for (const auto& [field, flag] : flags) {
    if (e.where() != field) continue;
    Error renamed(e.kind(), flag, e.found(), e.expected());
    if (!e.file().empty()) renamed.WithFile(e.file(), e.line(), e.column());
    throw renamed;
  }
  throw e;
}

}  // namespace impactdic::cli
