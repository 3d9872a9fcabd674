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
//
// Rescued: converged against the last frame with ZNCC >= auto_min_zncc and, when against the
// reference it converged (below the threshold) or ran into the iteration cap, with at most
// UpdateOptions::auto_rescue_decorrelation (1/3) of the decorrelation it had there:
// 1 - ZNCC_last <= (1 - ZNCC_reference) / 3. On noise-limited frames (real 4k JPEG sand: 5-8 % of
// the subsets below 0.95 and ~1 % at the iteration cap in every static pair) the two results are
// two draws of the same noise: over 12,192 such candidates in 38 static frames the ratio of the
// two decorrelations had its 1st-99th percentiles at 0.65-1.3 and its minimum at 0.36, and the
// threshold alone switched the reference at 38 of 38 frames (a random walk: 0.78 px RMS after 39
// static frames against 0.145 px with the first reference kept, at twice the cost). A subset that
// failed a check against the reference (low correlation, uncertain) or had no result there is
// rescued by passing against the last frame: it has no value against the reference (docs/dic.md,
// "Reference updating").
class AutoUpdate final : public ReferenceUpdatePolicy {
 public:
  AutoUpdate(double min_zncc, double rescue_decorrelation)
      : min_zncc_(min_zncc), rescue_decorrelation_(rescue_decorrelation) {}
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
  bool Rescues(const RescueTrial& trial) const override {
    if (trial.status != SubsetStatus::kConverged || !(trial.zncc >= min_zncc_)) return false;
    // Against the reference the subset converged below the threshold or ran into the iteration
    // cap: its ZNCC there says how well it matched, and the last frame must remove most of that
    // decorrelation. A subset that failed a check there (low correlation, uncertain) or had no
    // result is rescued by converging at or above the threshold.
    const bool matched = trial.reference_status == SubsetStatus::kConverged ||
                         trial.reference_status == SubsetStatus::kMaxIterations;
    if (!matched || !trial.reference_zncc) return true;
    return 1.0 - trial.zncc <= rescue_decorrelation_ * (1.0 - *trial.reference_zncc);
  }
  bool MakesFrameTheReference(const SolvedFrame& /*frame*/) const override { return false; }

 private:
  double min_zncc_;
  double rescue_decorrelation_;
};

}  // namespace

ReferenceUpdatePolicyInfo AutoPolicy() {
  return {"auto", "auto", [](const std::string& argument, const UpdateOptions& options) {
            CheckNoArgument(argument);
            return std::make_unique<AutoUpdate>(options.auto_min_zncc,
                                                options.auto_rescue_decorrelation);
          }};
}

}  // namespace impactdic::internal
