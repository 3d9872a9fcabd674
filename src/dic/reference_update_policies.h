// Internal: the built-in reference-update policies, one function per policy returning its name,
// usage and factory, declared from the list reference_update_policies.def.
#ifndef IMPACTDIC_SRC_DIC_REFERENCE_UPDATE_POLICIES_H_
#define IMPACTDIC_SRC_DIC_REFERENCE_UPDATE_POLICIES_H_

#include <string>

#include "impactdic/dic/reference_update.h"

namespace impactdic::internal {

#define IMPACTDIC_REFERENCE_UPDATE_POLICY(factory, file) ReferenceUpdatePolicyInfo factory();
#include "reference_update_policies.def"
#undef IMPACTDIC_REFERENCE_UPDATE_POLICY

// An argument-free policy refuses an argument ("fixed:3"): throws Error naming it.
void CheckNoArgument(const std::string& argument);

}  // namespace impactdic::internal

#endif  // IMPACTDIC_SRC_DIC_REFERENCE_UPDATE_POLICIES_H_
