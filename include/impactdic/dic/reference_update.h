// Reference-update policies of the correlator: when the reference image of a sequence changes.
//
// A policy is chosen by name in UpdateOptions::policy ("fixed", "incremental", "auto", "every:N",
// and GeoPIV-RG's scheme names "sequential", "leapfrog[:Z]" and "preconditioned", which are
// incremental, auto and fixed under another name: src/dic/geopiv_update.cc; scene key
// dic.reference_update, `correlate --reference-update`). The correlator asks it two questions per
// frame: after solving, which subsets ask for the frame to be redone against the last solved frame
// (only policies that keep that frame); and once the frame is final, whether it becomes the new
// reference. Adding a policy: a class deriving from ReferenceUpdatePolicy in one new file and one
// line in src/dic/reference_update_policies.def (docs/architecture.md, "Extension points");
// RegisterReferenceUpdatePolicy adds one at run time (tests/dic/reference_update_test.cc).
//
//   DicOptions options;
//   options.update.policy = "every:5";
//   std::unique_ptr<ReferenceUpdatePolicy> policy =
//       ReferenceUpdatePolicyFromString(options.update.policy, options.update);
#ifndef IMPACTDIC_DIC_REFERENCE_UPDATE_H_
#define IMPACTDIC_DIC_REFERENCE_UPDATE_H_

#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "impactdic/dic/options.h"

namespace impactdic {

// What a policy sees of a frame solved against the current reference (one entry per subset).
struct SolvedFrame {
  int frame = 0;            // Index of the frame (the first reference is 0).
  int reference_frame = 0;  // Index of the current reference.
  std::span<const SubsetStatus> status;
  std::span<const float> zncc;      // ZNCC of the IC-GN result (meaningless unless iterated).
  std::span<const char> trackable;  // 1: a tracked subset with a usable reference subset.
};

// A redo candidate solved against the last frame, beside its result against the current
// reference (Rescues).
struct RescueTrial {
  SubsetStatus status = SubsetStatus::kNotFound;  // Against the last frame.
  float zncc = 0;                                 // Against the last frame (if converged).
  SubsetStatus reference_status = SubsetStatus::kNotFound;  // Against the current reference.
  // ZNCC reached against the current reference; none when IC-GN did not iterate there (no guess,
  // unusable subset).
  std::optional<float> reference_zncc;
};

class ReferenceUpdatePolicy {
 public:
  virtual ~ReferenceUpdatePolicy() = default;

  // The policy as written in UpdateOptions::policy ("every:10").
  virtual std::string Name() const = 0;

  // True if the policy may redo a frame against the last solved frame as the new reference
  // (the correlator then keeps that frame: one frame of memory).
  virtual bool KeepsLastFrame() const { return false; }
  // The subsets of `frame` whose results ask for that redo; empty: keep the reference. The
  // correlator switches only if one of them is rescued (Rescues) against the last frame. Called
  // only when KeepsLastFrame() and a frame after the reference was solved.
  virtual std::vector<int> RedoCandidates(const SolvedFrame& frame) const;
  // Whether a candidate's result against the last frame counts as rescued (default: converged).
  virtual bool Rescues(const RescueTrial& trial) const;

  // Once `frame` is final: whether it becomes the reference for the next frames.
  virtual bool MakesFrameTheReference(const SolvedFrame& frame) const = 0;
};

// Builds a policy from the text after its name ("10" of "every:10"; empty if there is no ':'),
// reading other settings (auto_min_zncc) from the options. Error kInvalidValue on a bad argument.
using ReferenceUpdateFactory = std::function<std::unique_ptr<ReferenceUpdatePolicy>(
    const std::string& argument, const UpdateOptions& options)>;

struct ReferenceUpdatePolicyInfo {
  std::string name;   // "every"
  std::string usage;  // How to write it in messages: "every:N (N >= 1)".
  ReferenceUpdateFactory make;
};

// The one entry point from text to policy, for the options' Check(), the scene and the CLI:
// "name" or "name:argument" of a registered policy. Error kInvalidValue naming the text and
// listing the registered policies otherwise.
std::unique_ptr<ReferenceUpdatePolicy> ReferenceUpdatePolicyFromString(
    const std::string& text, const UpdateOptions& options = {});

// The registered policies in registration order ("fixed, incremental, auto or every:N (N >= 1)").
std::string ReferenceUpdatePolicyUsage();

// Adds a policy under info.name (Error kInvalidValue if the name is taken or contains ':').
// Thread-safe; policies cannot be removed.
void RegisterReferenceUpdatePolicy(ReferenceUpdatePolicyInfo info);

}  // namespace impactdic

#endif  // IMPACTDIC_DIC_REFERENCE_UPDATE_H_
