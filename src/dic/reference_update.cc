#include "impactdic/dic/reference_update.h"

#include <algorithm>
#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "reference_update_policies.h"

namespace impactdic {
namespace {

// The built-in policies, in the order of reference_update_policies.def (the order messages list
// them). A new policy adds one line there.
std::vector<ReferenceUpdatePolicyInfo> BuiltinPolicies() {
  return {
#define IMPACTDIC_REFERENCE_UPDATE_POLICY(factory, file) internal::factory(),
#include "reference_update_policies.def"
#undef IMPACTDIC_REFERENCE_UPDATE_POLICY
  };
}

struct Registry {
  std::mutex mutex;
  std::vector<ReferenceUpdatePolicyInfo> policies = BuiltinPolicies();
};

Registry& GetRegistry() {
  static Registry registry;
  return registry;
}

std::string Usage(const std::vector<ReferenceUpdatePolicyInfo>& policies) {
  std::string text;
  for (std::size_t i = 0; i < policies.size(); ++i) {
    if (i > 0) text += i + 1 == policies.size() ? " or " : ", ";
    text += policies[i].usage;
  }
  return text;
}

}  // namespace

void internal::CheckNoArgument(const std::string& argument) {
  CheckValue(argument.empty(), "reference update argument", argument, "none");
}

std::vector<int> ReferenceUpdatePolicy::RedoCandidates(const SolvedFrame& /*frame*/) const {
  return {};
}

bool ReferenceUpdatePolicy::Rescues(const RescueTrial& trial) const {
  return trial.status == SubsetStatus::kConverged;
}

std::unique_ptr<ReferenceUpdatePolicy> ReferenceUpdatePolicyFromString(
    const std::string& text, const UpdateOptions& options) {
  const std::size_t colon = text.find(':');
  const std::string name = text.substr(0, colon);
  const std::string argument = colon == std::string::npos ? "" : text.substr(colon + 1);
  if (colon != std::string::npos && argument.empty())
    throw Error(ErrorKind::kInvalidValue, "reference update", text, ReferenceUpdatePolicyUsage());
  ReferenceUpdateFactory make;
  std::string usage;
  {
    Registry& registry = GetRegistry();
    const std::lock_guard lock(registry.mutex);
    const auto it =
        std::find_if(registry.policies.begin(), registry.policies.end(),
                     [&](const ReferenceUpdatePolicyInfo& p) { return p.name == name; });
    if (it == registry.policies.end())
      throw Error(ErrorKind::kInvalidValue, "reference update", text, Usage(registry.policies));
    make = it->make;
    usage = it->usage;
  }
  try {
    return make(argument, options);
  } catch (const Error&) {
    throw Error(ErrorKind::kInvalidValue, "reference update", text, usage);
  }
}

std::string ReferenceUpdatePolicyUsage() {
  Registry& registry = GetRegistry();
  const std::lock_guard lock(registry.mutex);
  return Usage(registry.policies);
}

void RegisterReferenceUpdatePolicy(ReferenceUpdatePolicyInfo info) {
  CheckValue(!info.name.empty() && info.name.find(':') == std::string::npos,
             "reference update policy name", info.name, "a non-empty name without ':'");
  CheckValue(static_cast<bool>(info.make), "reference update policy factory", info.name,
             "a factory");
  Registry& registry = GetRegistry();
  const std::lock_guard lock(registry.mutex);
  CheckValue(std::none_of(registry.policies.begin(), registry.policies.end(),
                          [&](const ReferenceUpdatePolicyInfo& p) { return p.name == info.name; }),
             "reference update policy name", info.name, "a name not yet registered");
  registry.policies.push_back(std::move(info));
}

}  // namespace impactdic
