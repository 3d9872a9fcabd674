// "fixed" and "incremental", the policies whose answer does not depend on the frame: every frame
// is correlated against the first image, or against the previous frame (docs/dic.md, "Reference
// updating").
#include <memory>
#include <string>
#include <utility>

#include "impactdic/dic/options.h"
#include "impactdic/dic/reference_update.h"
#include "reference_update_policies.h"

namespace impactdic::internal {
namespace {

class ConstantUpdate final : public ReferenceUpdatePolicy {
 public:
  ConstantUpdate(std::string name, bool makes_frame_the_reference)
      : name_(std::move(name)), makes_frame_the_reference_(makes_frame_the_reference) {}
  std::string Name() const override { return name_; }
  bool MakesFrameTheReference(const SolvedFrame& /*frame*/) const override {
    return makes_frame_the_reference_;
  }

 private:
  std::string name_;
  bool makes_frame_the_reference_;
};

// The policy `name`, without an argument, answering `makes_frame_the_reference` for every frame.
ReferenceUpdatePolicyInfo ConstantPolicy(const std::string& name, bool makes_frame_the_reference) {
  return {name, name,
          [name, makes_frame_the_reference](const std::string& argument, const UpdateOptions&) {
            CheckNoArgument(argument);
            return std::make_unique<ConstantUpdate>(name, makes_frame_the_reference);
          }};
}

}  // namespace

ReferenceUpdatePolicyInfo FixedPolicy() {
  return ConstantPolicy("fixed", /*makes_frame_the_reference=*/false);
}

ReferenceUpdatePolicyInfo IncrementalPolicy() {
  return ConstantPolicy("incremental", /*makes_frame_the_reference=*/true);
}

}  // namespace impactdic::internal
