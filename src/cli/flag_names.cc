<<<<<<< HEAD
// RethrowWithFlagNames, RethrowWithPartialFlag (commands.h): library field names -> command-line
// flags.
#include <fmt/format.h>

#include "commands.h"
#include "impactdic/pipeline/pipeline.h"
=======
// RethrowWithFlagNames (commands.h): library field names -> command-line flags.
#include <string>
#include <vector>

#include "commands.h"
#include "impactdic/core/error.h"
>>>>>>> 61b6928 (include what you use: the includes iwyu asked to add (578 lines in 174 files; scripts/iwyu.sh))

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
