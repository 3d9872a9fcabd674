// Tool version and the git revision it was built from (for provenance in every output).
#ifndef IMPACTDIC_CORE_VERSION_H_
#define IMPACTDIC_CORE_VERSION_H_

namespace impactdic {

// The project version, e.g. "0.1.0".
const char* Version();
// The commit the build was configured from, as `git describe --always --dirty`: a short hash,
// with "-dirty" for uncommitted changes; "unknown" when built outside a git checkout.
const char* GitRevision();
// The same commit's full hash (40 hex digits); "unknown" outside a git checkout.
const char* GitCommit();

}  // namespace impactdic

#endif  // IMPACTDIC_CORE_VERSION_H_
