// "fixed": every frame is correlated against the first image (docs/dic.md, "Reference updates").
#include <memory>
#include <string>

#include "reference_update_policies.h"

namespace impactdic::internal {
namespace {

class FixedUpdate final : public ReferenceUpdatePolicy {
 public:
  std::string Name() const override { return "fixed"; }
  bool MakesFrameTheReference(const SolvedFrame& /*frame*/) const override { return false; }
};

}  // namespace

ReferenceUpdatePolicyInfo FixedPolicy() {
  return {"fixed", "fixed", [](const std::string& argument, const UpdateOptions&) {
            CheckNoArgument(argument);
            return std::make_unique<FixedUpdate>();
          }};
}

}  // namespace impactdic::internal
