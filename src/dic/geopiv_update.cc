// GeoPIV-RG's analysis schemes by name (Stanier, Blaber, Take & White 2016, "Improved image-based
// deformation measurement for geotechnical applications", Can. Geotech. J. 53(5):727-739,
// doi:10.1139/cgj-2015-0253): "sequential", "leapfrog[:Z]" and "preconditioned", each the
// impactdic policy that does the same thing, under GeoPIV-RG's name (docs/dic.md, "GeoPIV-RG's
// analysis schemes"):
//   sequential      = incremental: every frame against the previous one (random walk);
//   leapfrog[:Z]    = auto with its threshold auto_min_zncc = Z when given: the reference is kept
//                     until a subset decorrelates (ZNCC < Z), then leaps to the last good frame;
//   preconditioned  = fixed: every frame against the first image, each subset starting from its
//                     warp in the previous frame (impactdic's initial guess for every policy).
// The aliases delegate every decision to the policy they name, so they cannot drift apart.
#include <cstddef>
#include <exception>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/range.h"
#include "impactdic/dic/options.h"
#include "impactdic/dic/reference_update.h"
#include "reference_update_policies.h"

namespace impactdic::internal {
namespace {

// A built-in policy under another name: Name() is the alias as written, every decision is the
// wrapped policy's.
class AliasUpdate final : public ReferenceUpdatePolicy {
 public:
  AliasUpdate(std::string name, std::unique_ptr<ReferenceUpdatePolicy> policy)
      : name_(std::move(name)), policy_(std::move(policy)) {}
  std::string Name() const override { return name_; }
  bool KeepsLastFrame() const override { return policy_->KeepsLastFrame(); }
  std::vector<int> RedoCandidates(const SolvedFrame& frame) const override {
    return policy_->RedoCandidates(frame);
  }
  bool Rescues(const RescueTrial& trial) const override { return policy_->Rescues(trial); }
  bool MakesFrameTheReference(const SolvedFrame& frame) const override {
    return policy_->MakesFrameTheReference(frame);
  }

 private:
  std::string name_;
  std::unique_ptr<ReferenceUpdatePolicy> policy_;
};

// The argument-free alias `name` of the built-in policy made by `target`.
ReferenceUpdatePolicyInfo ArgumentFreeAlias(const std::string& name,
                                            ReferenceUpdatePolicyInfo (*target)()) {
  return {name, name, [name, target](const std::string& argument, const UpdateOptions& options) {
            CheckNoArgument(argument);
            return std::make_unique<AliasUpdate>(name, target().make("", options));
          }};
}

// "leapfrog" or "leapfrog:Z": auto, with auto_min_zncc = Z when Z is given.
std::unique_ptr<ReferenceUpdatePolicy> MakeLeapfrog(const std::string& argument,
                                                    const UpdateOptions& options) {
  UpdateOptions threshold = options;
  if (!argument.empty()) {
    std::size_t used = 0;
    double z = 0;
    try {
      z = std::stod(argument, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    CheckValue(used > 0 && used == argument.size() && kAutoMinZnccRange.Contains(z), "leapfrog:Z",
               argument, "a ZNCC threshold Z in " + kAutoMinZnccRange.Text());
    threshold.auto_min_zncc = z;
  }
  return std::make_unique<AliasUpdate>(argument.empty() ? "leapfrog" : "leapfrog:" + argument,
                                       AutoPolicy().make("", threshold));
}

}  // namespace

// GeoPIV-RG "sequential": image i is correlated against image i-1 and the increments are summed,
// so the random errors of the increments add up as a random walk.
ReferenceUpdatePolicyInfo SequentialPolicy() {
  return ArgumentFreeAlias("sequential", IncrementalPolicy);
}

// GeoPIV-RG "leapfrog": the reference is kept until the correlation coefficient of a subset falls
// below a threshold, then it leaps forward to the last image that correlated and the image is
// solved again against it. "leapfrog" uses UpdateOptions::auto_min_zncc (0.95); "leapfrog:Z" sets
// the threshold to Z (GeoPIV-RG's user-defined value; geopyv's default tolerance is 0.75).
ReferenceUpdatePolicyInfo LeapfrogPolicy() {
  return {"leapfrog", "leapfrog[:Z] (Z in " + kAutoMinZnccRange.Text() + ")", MakeLeapfrog};
}

// GeoPIV-RG "preconditioned optimisation": every image against the first, each subset's
// optimisation started from its deformation (the whole warp) found in the previous image.
ReferenceUpdatePolicyInfo PreconditionedPolicy() {
  return ArgumentFreeAlias("preconditioned", FixedPolicy);
}

}  // namespace impactdic::internal
