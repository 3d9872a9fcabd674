// The built-in reference-update policies (docs/dic.md, "Reference updates").
#include "reference_update_policies.h"

#include <memory>
#include <string>
#include <vector>

#include "impactdic/core/error.h"

namespace impactdic::internal {
namespace {

// An argument-free policy refuses an argument ("fixed:3").
void CheckNoArgument(const std::string& argument) {
  CheckValue(argument.empty(), "reference update argument", argument, "none");
}

class FixedUpdate final : public ReferenceUpdatePolicy {
 public:
  std::string Name() const override { return "fixed"; }
  bool MakesFrameTheReference(const SolvedFrame& /*frame*/) const override { return false; }
};

class IncrementalUpdate final : public ReferenceUpdatePolicy {
 public:
  std::string Name() const override { return "incremental"; }
  bool MakesFrameTheReference(const SolvedFrame& /*frame*/) const override { return true; }
};

class EveryNUpdate final : public ReferenceUpdatePolicy {
 public:
  explicit EveryNUpdate(int n) : n_(n) {}
  std::string Name() const override { return "every:" + std::to_string(n_); }
  bool MakesFrameTheReference(const SolvedFrame& frame) const override {
    return frame.frame - frame.reference_frame >= n_;
  }

 private:
  int n_;
};

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

ReferenceUpdatePolicyInfo FixedPolicy() {
  return {"fixed", "fixed", [](const std::string& argument, const UpdateOptions&) {
            CheckNoArgument(argument);
            return std::make_unique<FixedUpdate>();
          }};
}

ReferenceUpdatePolicyInfo IncrementalPolicy() {
  return {"incremental", "incremental", [](const std::string& argument, const UpdateOptions&) {
            CheckNoArgument(argument);
            return std::make_unique<IncrementalUpdate>();
          }};
}

ReferenceUpdatePolicyInfo AutoPolicy() {
  return {"auto", "auto", [](const std::string& argument, const UpdateOptions& options) {
            CheckNoArgument(argument);
            return std::make_unique<AutoUpdate>(options.auto_min_zncc);
          }};
}

ReferenceUpdatePolicyInfo EveryNPolicy() {
  return {"every", "every:N (N >= 1)", [](const std::string& argument, const UpdateOptions&) {
            std::size_t used = 0;
            int n = 0;
            try {
              n = std::stoi(argument, &used);
            } catch (const std::exception&) {
              used = 0;
            }
            CheckValue(used > 0 && used == argument.size() && n >= 1, "every:N", argument,
                       "an integer N >= 1");
            return std::make_unique<EveryNUpdate>(n);
          }};
}

}  // namespace impactdic::internal
