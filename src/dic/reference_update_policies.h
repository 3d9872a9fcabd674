// Internal: the built-in reference-update policies, one function per policy returning its name,
// usage and factory (listed in the table of reference_update.cc).
#ifndef IMPACTDIC_SRC_DIC_REFERENCE_UPDATE_POLICIES_H_
#define IMPACTDIC_SRC_DIC_REFERENCE_UPDATE_POLICIES_H_

#include "impactdic/dic/reference_update.h"

namespace impactdic::internal {

ReferenceUpdatePolicyInfo FixedPolicy();        // "fixed": always the first image.
ReferenceUpdatePolicyInfo IncrementalPolicy();  // "incremental": the previous frame.
ReferenceUpdatePolicyInfo AutoPolicy();         // "auto": switch when subsets decorrelate.
ReferenceUpdatePolicyInfo EveryNPolicy();       // "every:N": every N frames.

}  // namespace impactdic::internal

#endif  // IMPACTDIC_SRC_DIC_REFERENCE_UPDATE_POLICIES_H_
