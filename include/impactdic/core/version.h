// Tool version and the git revision it was built from (for provenance in every output).
#ifndef IMPACTDIC_CORE_VERSION_H_
#define IMPACTDIC_CORE_VERSION_H_

namespace impactdic {

const char* Version();  // e.g. "0.1.0"
const char*
GitRevision();  // short hash, with "-dirty" for uncommitted changes; "unknown" outside git

}  // namespace impactdic

#endif  // IMPACTDIC_CORE_VERSION_H_
