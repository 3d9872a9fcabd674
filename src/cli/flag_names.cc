// RethrowWithFlagNames, RethrowWithPartialFlag (commands.h): library field names -> command-line
// flags.
#include <fmt/format.h>

#include <string>
#include <vector>

#include "commands.h"
#include "impactdic/core/error.h"
#include "impactdic/pipeline/pipeline.h"

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

void RethrowWithPartialFlag(const PartialResultsError& e, const std::string& command) {
  throw Error(ErrorKind::kNumerical, fmt::format("{}; `impactdic {} {}` {}", e.problem(), command,
                                                 kAllowPartialFlag, e.remedy()));
}

}  // namespace impactdic::cli
