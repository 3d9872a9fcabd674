// "incremental": every frame is correlated against the previous one (docs/dic.md, "Reference
// updates").
#include <memory>
#include <string>

#include "reference_update_policies.h"

namespace impactdic::internal {
namespace {

class IncrementalUpdate final : public ReferenceUpdatePolicy {
 public:
  std::string Name() const override { return "incremental"; }
  bool MakesFrameTheReference(const SolvedFrame& /*frame*/) const override { return true; }
};

}  // namespace

ReferenceUpdatePolicyInfo IncrementalPolicy() {
  return {"incremental", "incremental", [](const std::string& argument, const UpdateOptions&) {
            CheckNoArgument(argument);
            return std::make_unique<IncrementalUpdate>();
          }};
}

}  // namespace impactdic::internal
