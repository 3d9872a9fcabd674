// Reference-update policies as an extension point (docs/development.md, "Extension points"): a
// policy written here, registered at run time and selected by name like the built-in ones.
#include "impactdic/dic/reference_update.h"

#include <gtest/gtest.h>

#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "dic_test_util.h"
#include "impactdic/core/error.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/synth/fields.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {
namespace {

// The worked example: "once:K" makes frame K the reference, once, and keeps it afterwards (e.g.
// the first frame after a known event). One class and one registration call.
class OnceUpdate final : public ReferenceUpdatePolicy {
 public:
  explicit OnceUpdate(int k) : k_(k) {}
  std::string Name() const override { return "once:" + std::to_string(k_); }
  bool MakesFrameTheReference(const SolvedFrame& frame) const override { return frame.frame == k_; }

 private:
  int k_;
};

void RegisterOnce() {
  static const bool registered = [] {
    RegisterReferenceUpdatePolicy(
        {"once", "once:K (K >= 1)", [](const std::string& argument, const UpdateOptions&) {
           const int k = std::stoi(argument);
           CheckValue(k >= 1, "once:K", argument, "K >= 1");
           return std::make_unique<OnceUpdate>(k);
         }});
    return true;
  }();
  (void)registered;
}

TEST(ReferenceUpdate, ATestOnlyPolicyIsSelectedByNameAndDrivesTheCorrelator) {
  RegisterOnce();
  testing::Scene scene(160, 120, /*noise_sigma=*/1, /*seed=*/5, /*supersampling=*/2);
  const DisplacementSequence seq = LinearSequence(Translation(2.5, -1.5), 6);
  std::vector<cv::Mat> images;
  images.reserve(seq.frames);
  for (int k = 0; k < seq.frames; ++k) images.push_back(scene.Render(seq.at(k), 300 + k));
  DicOptions options;
  options.grid.step = 10;
  options.update.policy = "once:2";
  options.Check();  // The registered name passes the options' check.
  const DicResult result = CorrelateSequence(images, options);
  ASSERT_EQ(result.frames.size(), 5u);
  EXPECT_EQ(result.summary.reference_updates, 1);
  // Frames 1 and 2 against the first image; after frame 2 became the reference, the rest
  // against it. Displacements stay relative to the first image (accumulated), so they match the
  // field throughout.
  for (const FrameResult& f : result.frames) {
    EXPECT_EQ(f.reference_frame, f.frame <= 2 ? 0 : 2) << f.frame;
    const testing::ErrorStats e = testing::Errors(result.positions, f, seq.at(f.frame));
    EXPECT_GT(e.valid, 0.9 * result.positions.size()) << f.frame;
    EXPECT_LT(e.rms, 0.02) << f.frame;
  }
}

TEST(ReferenceUpdate, RegistryListsPoliciesAndRefusesBadNames) {
  RegisterOnce();
  EXPECT_EQ(ReferenceUpdatePolicyFromString("once:3")->Name(), "once:3");
  EXPECT_NE(ReferenceUpdatePolicyUsage().find("once:K (K >= 1)"), std::string::npos);
  for (const char* name : {"fixed", "incremental", "auto", "every:4"})
    EXPECT_EQ(ReferenceUpdatePolicyFromString(name)->Name(), name);
  // A name given twice, a ':' in a name.
  EXPECT_THROW(RegisterReferenceUpdatePolicy({"once", "once",
                                              [](const std::string&, const UpdateOptions&) {
                                                return std::make_unique<OnceUpdate>(1);
                                              }}),
               Error);
  EXPECT_THROW(RegisterReferenceUpdatePolicy({"a:b", "a:b", nullptr}), Error);
  // Unknown names and bad arguments name the text and list what is registered.
  for (const char* bad : {"sometimes", "fixed:2", "every:", "every:x", "once:0", "auto:"}) {
    try {
      ReferenceUpdatePolicyFromString(bad);
      FAIL() << bad;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

TEST(ReferenceUpdate, BuiltinPoliciesAreListedInTheOrderOfTheirRegistrationList) {
  // src/dic/reference_update_policies.def: fixed, incremental, auto, every, then GeoPIV-RG's
  // scheme names. A policy registered at run time comes after them (once:K, when this program's
  // first tests ran in this process).
  const std::string builtin =
      "fixed, incremental, auto, every:N (N >= 1), sequential, leapfrog[:Z] (Z in (-1, 1])";
  const std::string usage = ReferenceUpdatePolicyUsage();
  EXPECT_TRUE(usage == builtin + " or preconditioned" ||
              usage == builtin + ", preconditioned or once:K (K >= 1)")
      << usage;
}

TEST(ReferenceUpdate, BuiltinPoliciesDecideAsDocumented) {
  const std::vector<SubsetStatus> status = {SubsetStatus::kConverged, SubsetStatus::kConverged,
                                            SubsetStatus::kLowCorrelation, SubsetStatus::kMasked,
                                            SubsetStatus::kNotFound};
  const std::vector<float> zncc = {0.99f, 0.90f, 0.5f, 0.0f, 0.0f};
  const std::vector<char> trackable = {1, 1, 1, 0, 0};
  const SolvedFrame frame{
      .frame = 7, .reference_frame = 3, .status = status, .zncc = zncc, .trackable = trackable};
  UpdateOptions options;
  options.auto_min_zncc = 0.95;
  const auto automatic = ReferenceUpdatePolicyFromString("auto", options);
  EXPECT_TRUE(automatic->KeepsLastFrame());
  // Below the threshold or decorrelated, among trackable subsets only.
  EXPECT_EQ(automatic->RedoCandidates(frame), (std::vector<int>{1, 2}));
  // A candidate's result against the last frame (converged at `zncc` unless said otherwise) and
  // against the reference (none: IC-GN did not iterate there).
  const auto trial = [](float last_zncc, SubsetStatus reference_status,
                        std::optional<float> reference_zncc,
                        SubsetStatus last_status = SubsetStatus::kConverged) {
    return RescueTrial{.status = last_status,
                       .zncc = last_zncc,
                       .reference_status = reference_status,
                       .reference_zncc = reference_zncc};
  };
  const auto rescues = [&](const RescueTrial& t) { return automatic->Rescues(t); };
  // Converged at or above the threshold, with no result against the reference to compare with.
  EXPECT_TRUE(rescues(trial(0.96f, SubsetStatus::kNotFound, std::nullopt)));
  EXPECT_FALSE(rescues(trial(0.94f, SubsetStatus::kNotFound, std::nullopt)));
  EXPECT_FALSE(
      rescues(trial(0.99f, SubsetStatus::kNotFound, std::nullopt, SubsetStatus::kMaxIterations)));
  // Against a match at the reference (converged, or the iteration cap): at most a third of its
  // decorrelation (1 - ZNCC) is left. 0.85 -> 0.96 removes 73 % of it; 0.93 -> 0.96 (two draws of
  // the noise) 43 %; a subset that hit the iteration cap at 0.99 is not rescued by converging at
  // 0.99.
  EXPECT_TRUE(rescues(trial(0.96f, SubsetStatus::kConverged, 0.85f)));
  EXPECT_FALSE(rescues(trial(0.96f, SubsetStatus::kConverged, 0.93f)));
  EXPECT_FALSE(rescues(trial(0.99f, SubsetStatus::kMaxIterations, 0.99f)));
  // A subset that failed a check against the reference has no value there: passing suffices.
  EXPECT_TRUE(rescues(trial(0.96f, SubsetStatus::kUncertain, 0.99f)));
  EXPECT_TRUE(rescues(trial(0.96f, SubsetStatus::kLowCorrelation, 0.7f)));
  // The share left is an option: at 0.5, 0.93 -> 0.97 (43 % left) is a rescue.
  UpdateOptions half = options;
  half.auto_rescue_decorrelation = 0.5;
  EXPECT_TRUE(ReferenceUpdatePolicyFromString("auto", half)
                  ->Rescues(trial(0.97f, SubsetStatus::kConverged, 0.93f)));
  half.auto_rescue_decorrelation = 0;
  EXPECT_THROW(half.Check(), Error);
  EXPECT_FALSE(automatic->MakesFrameTheReference(frame));
  EXPECT_FALSE(ReferenceUpdatePolicyFromString("fixed")->MakesFrameTheReference(frame));
  EXPECT_TRUE(ReferenceUpdatePolicyFromString("incremental")->MakesFrameTheReference(frame));
  EXPECT_TRUE(ReferenceUpdatePolicyFromString("every:4")->MakesFrameTheReference(frame));
  EXPECT_FALSE(ReferenceUpdatePolicyFromString("every:5")->MakesFrameTheReference(frame));
}

}  // namespace
}  // namespace impactdic
