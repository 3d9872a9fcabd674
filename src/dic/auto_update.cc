// "auto": switch the reference when subsets decorrelate (docs/dic.md, "Reference updating").
#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "impactdic/dic/options.h"
#include "impactdic/dic/reference_update.h"
#include "reference_update_policies.h"

namespace impactdic::internal {
namespace {

// GeoPIV-RG's answer to random walk without its cost: keep the reference while every subset that
// is still tracked correlates at or above UpdateOptions::auto_min_zncc; when one does not (it
// decorrelated: low ZNCC, iteration cap, not found, uncertain), redo the frame against the last
// solved frame, but only if that rescues one of those subsets. Subsets that fail against both
// (covered by the pounder) keep the reference and are found again when they reappear.
class AutoUpdate final : public ReferenceUpdatePolicy {
 public:
  explicit AutoUpdate(double min_zncc) : min_zncc_(min_zncc) {}
  std::string Name() const override { return "auto"; }
  bool KeepsLastFrame() const override { return true; }
  std::vector<int> RedoCandidates(const SolvedFrame& frame) const override {
    std::vector<int> candidates;
    for (std::size_t i = 0; i < frame.status.size(); ++i) {
      if (!frame.trackable[i]) continue;
      const SubsetStatus s = frame.status[i];
      const bool decorrelated = s == SubsetStatus::kLowCorrelation ||
                                s == SubsetStatus::kMaxIterations || s == SubsetStatus::kNotFound ||
                                s == SubsetStatus::kUncertain;
      if (decorrelated || (s == SubsetStatus::kConverged && frame.zncc[i] < min_zncc_))
        candidates.push_back(static_cast<int>(i));
    }
    return candidates;
  }
  bool Rescues(SubsetStatus status, float zncc) const override {
    return status == SubsetStatus::kConverged && zncc >= min_zncc_;
  }
  bool MakesFrameTheReference(const SolvedFrame& /*frame*/) const override { return false; }

 private:
  double min_zncc_;
};

}  // namespace

ReferenceUpdatePolicyInfo AutoPolicy() {
  return {"auto", "auto", [](const std::string& argument, const UpdateOptions& options) {
            CheckNoArgument(argument);
            return std::make_unique<AutoUpdate>(options.auto_min_zncc);
          }};
}

}  // namespace impactdic::internal
