// GeoPIV-RG's analysis schemes by name (docs/dic.md, "GeoPIV-RG's analysis
// schemes"): "sequential", "leapfrog[:Z]" and "preconditioned" are the policies incremental, auto
// and fixed under GeoPIV-RG's names, and the random-walk comparison of the schemes on a long
// sequence (the table in docs/dic.md comes from bench/reference_update_benchmark.cc, which builds
// the same sequences).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <span>
#include <string>
#include <vector>

#include "dic_test_util.h"
#include "impactdic/core/error.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/dic/options.h"
#include "impactdic/dic/reference_update.h"
#include "impactdic/synth/fields.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {
namespace {

using testing::Errors;
using testing::ErrorStats;

TEST(GeopivSchemes, NamesAreAcceptedListedAndCheckedLikeTheOthers) {
  for (const char* name : {"sequential", "leapfrog", "leapfrog:0.75", "preconditioned"}) {
    EXPECT_EQ(ReferenceUpdatePolicyFromString(name)->Name(), name);
    DicOptions options;
    options.update.policy = name;
    EXPECT_NO_THROW(options.Check()) << name;
  }
  const std::string usage = ReferenceUpdatePolicyUsage();
  for (const char* listed : {"sequential", "leapfrog[:Z] (Z in (-1, 1])", "preconditioned"})
    EXPECT_NE(usage.find(listed), std::string::npos) << listed << " in " << usage;
  // Arguments where there are none, a threshold that is not a number or outside (-1, 1]: the
  // message names the text and says what is expected.
  for (const char* bad : {"sequential:1", "preconditioned:2", "leapfrog:", "leapfrog:x",
                          "leapfrog:0.9x", "leapfrog:1.5", "leapfrog:-1", "leap"}) {
    try {
      ReferenceUpdatePolicyFromString(bad);
      FAIL() << bad;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
  try {
    ReferenceUpdatePolicyFromString("leapfrog:2");
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("leapfrog[:Z] (Z in (-1, 1])"), std::string::npos)
        << e.what();
  }
}

TEST(GeopivSchemes, EachSchemeDecidesAsThePolicyItNames) {
  const std::vector<SubsetStatus> status = {SubsetStatus::kConverged, SubsetStatus::kConverged,
                                            SubsetStatus::kLowCorrelation, SubsetStatus::kMasked,
                                            SubsetStatus::kNotFound};
  const std::vector<float> zncc = {0.99f, 0.90f, 0.5f, 0.0f, 0.0f};
  const std::vector<char> trackable = {1, 1, 1, 0, 0};
  const SolvedFrame frame{
      .frame = 7, .reference_frame = 3, .status = status, .zncc = zncc, .trackable = trackable};
  UpdateOptions options;
  options.auto_min_zncc = 0.95;
  const struct {
    const char* scheme;
    const char* policy;
  } pairs[] = {{"sequential", "incremental"}, {"leapfrog", "auto"}, {"preconditioned", "fixed"}};
  for (const auto& p : pairs) {
    const auto scheme = ReferenceUpdatePolicyFromString(p.scheme, options);
    const auto policy = ReferenceUpdatePolicyFromString(p.policy, options);
    EXPECT_EQ(scheme->KeepsLastFrame(), policy->KeepsLastFrame()) << p.scheme;
    EXPECT_EQ(scheme->MakesFrameTheReference(frame), policy->MakesFrameTheReference(frame))
        << p.scheme;
    if (policy->KeepsLastFrame()) {
      EXPECT_EQ(scheme->RedoCandidates(frame), policy->RedoCandidates(frame)) << p.scheme;
      for (const float z : {0.94f, 0.96f}) {
        // Without a result against the reference, after a failed check there, and after a match
        // there (converged below the threshold: the share of the decorrelation left decides).
        for (const RescueTrial& trial : {RescueTrial{.status = SubsetStatus::kConverged, .zncc = z},
                                         RescueTrial{.status = SubsetStatus::kConverged,
                                         .zncc = z,
                                         .reference_status = SubsetStatus::kLowCorrelation,
                                         .reference_zncc = 0.5f},
                                         RescueTrial{.status = SubsetStatus::kConverged,
                                         .zncc = z,
                                         .reference_status = SubsetStatus::kConverged,
                                         .reference_zncc = 0.85f},
                                         RescueTrial{.status = SubsetStatus::kConverged,
                                         .zncc = z,
                                         .reference_status = SubsetStatus::kConverged,
                                         .reference_zncc = 0.93f}}) {
          EXPECT_EQ(scheme->Rescues(trial), policy->Rescues(trial)) << p.scheme;
        }
      }
    }
  }
  EXPECT_TRUE(ReferenceUpdatePolicyFromString("sequential")->MakesFrameTheReference(frame));
  EXPECT_FALSE(ReferenceUpdatePolicyFromString("preconditioned")->MakesFrameTheReference(frame));
  // leapfrog:Z is auto with the threshold Z: at 0.8 the subset at 0.90 no longer asks for the
  // leap, the decorrelated one still does; a result at 0.85 now counts as rescued.
  const auto leapfrog = ReferenceUpdatePolicyFromString("leapfrog:0.8", options);
  EXPECT_EQ(leapfrog->RedoCandidates(frame), (std::vector<int>{2}));
  const RescueTrial at_085{.status = SubsetStatus::kConverged,
                           .zncc = 0.85f,
                           .reference_status = SubsetStatus::kLowCorrelation,
                           .reference_zncc = 0.5f};
  RescueTrial at_075 = at_085;
  at_075.zncc = 0.75f;
  EXPECT_TRUE(leapfrog->Rescues(at_085));
  EXPECT_FALSE(leapfrog->Rescues(at_075));
  EXPECT_FALSE(leapfrog->MakesFrameTheReference(frame));
}

// The long sequence of the random-walk comparison (bench/reference_update_benchmark.cc builds the
// same one with --size 240x160 --drift 20,-5): a 240 x 160 px speckle image; frame k has
// k/(frames-1) of the final field, a drift of (20, -5) px (0.1 px per frame over 201 frames) plus
// a settlement-like vertical compression (3 % at the top, decaying over 80 px; 2.1 px at the top);
// Gaussian noise sigma 2 grey levels, a new realisation in every image. `tone` > 0 also changes
// the tone curve, I -> I^(1 + tone k / (frames - 1)) on the normalised intensity (the texture
// darkens non-linearly, as wetting sand does; the speckle stays in place), so that the
// correlation with the first image decays while consecutive images still correlate.
constexpr int kWidth = 240, kHeight = 160;

struct LongSequence {
  DisplacementSequence fields;
  std::vector<cv::Mat> images;
};

LongSequence MakeLongSequence(int frames, double tone) {
  LongSequence s;
  s.fields = LinearSequence(
      Sum({Translation(20, -5), ExponentialCompression(/*surface_strain=*/0.03,
                                                       /*decay_length_px=*/80, /*y_surface_px=*/0,
                                                       /*y_fixed_px=*/kHeight)}),
      frames);
  SpeckleOptions speckle;
  speckle.blob_radius_px = 2.0;
  speckle.seed = 21;
  const SpecklePattern pattern(speckle, kWidth, kHeight);
  RenderOptions render;
  render.supersampling = 2;
  render.bits = 16;  // Noise-free; the tone curve, the noise and 8-bit rounding follow.
  cv::RNG rng(2021);
  for (int k = 0; k < frames; ++k) {
    cv::Mat image;
    RenderImage(pattern, kWidth, kHeight, s.fields.at(k), render)
        .convertTo(image, CV_32F, 1.0 / 65535);
    cv::pow(image, 1 + tone * k / (frames - 1), image);
    cv::Mat noise(image.size(), CV_32F);
    rng.fill(noise, cv::RNG::NORMAL, 0, 2);
    cv::Mat image8;
    cv::Mat(255 * image + noise).convertTo(image8, CV_8U);  // Rounds and saturates.
    s.images.push_back(image8);
  }
  return s;
}

DicOptions LongSequenceOptions(const std::string& scheme) {
  DicOptions options;
  options.grid.step = 10;
  // Every converged subset is reported: the comparison is of the errors, not of a cut.
  options.icgn.max_uncertainty_px = 0;
  options.update.policy = scheme;
  return options;
}

struct SchemeRun {
  std::vector<double> rms;    // Per frame (index k = frame k; rms[0] unused): RMS error [px].
  std::vector<double> valid;  // Fraction of the subsets converged.
  int updates = 0;
  DicResult result;
};

SchemeRun RunScheme(const LongSequence& s, const std::string& scheme) {
  SchemeRun run;
  run.result = CorrelateSequence(s.images, LongSequenceOptions(scheme));
  run.rms.assign(s.fields.frames, 0);
  run.valid.assign(s.fields.frames, 1);
  for (const FrameResult& f : run.result.frames) {
    const ErrorStats e = Errors(run.result.positions, f, s.fields.at(f.frame));
    run.rms[f.frame] = e.rms;
    run.valid[f.frame] = double(e.valid) / run.result.positions.size();
  }
  run.updates = run.result.summary.reference_updates;
  return run;
}

// Least-squares slope of log(rms) against log(k) over frames 10..last: 0.5 for a random walk,
// 1 for a drift, 0 for an error that does not grow.
double GrowthExponent(const std::vector<double>& rms) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (std::size_t k = 10; k < rms.size(); ++k) {
    const double x = std::log(double(k)), y = std::log(rms[k]);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    ++n;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

bool SameResults(const DicResult& a, const DicResult& b) {
  if (a.frames.size() != b.frames.size()) return false;
  for (std::size_t k = 0; k < a.frames.size(); ++k) {
    const FrameResult &fa = a.frames[k], &fb = b.frames[k];
    if (fa.reference_frame != fb.reference_frame || fa.status != fb.status) return false;
    for (std::size_t i = 0; i < fa.u_px.size(); ++i) {
      if (fa.status[i] != SubsetStatus::kConverged) continue;
      if (fa.u_px[i] != fb.u_px[i] || fa.v_px[i] != fb.v_px[i]) return false;
    }
  }
  return true;
}

TEST(GeopivSchemes, SequentialRandomWalksPreconditionedDoesNotOnALongSequence) {
  // 201 frames, 200 increments of 0.1 px; measured (2026-11-27): sequential 0.0135 / 0.0158 /
  // 0.0266 / 0.0484 px at frames 25 / 50 / 100 / 200 (exponent 0.60), preconditioned 0.0096 /
  // 0.0098 / 0.0087 / 0.0101 px (exponent 0.04); docs/dic.md, "GeoPIV-RG's analysis schemes".
  constexpr int kFrames = 201, kLast = kFrames - 1;
  const LongSequence s = MakeLongSequence(kFrames, /*tone=*/0);
  const SchemeRun sequential = RunScheme(s, "sequential");
  const SchemeRun leapfrog = RunScheme(s, "leapfrog");
  const SchemeRun preconditioned = RunScheme(s, "preconditioned");
  std::printf("scheme          updates  RMS error [px] at frame 25 / 50 / 100 / 200  exponent\n");
  const char* names[] = {"sequential", "leapfrog", "preconditioned"};
  const SchemeRun* runs[] = {&sequential, &leapfrog, &preconditioned};
  for (int j = 0; j < 3; ++j) {
    const SchemeRun& r = *runs[j];
    std::printf("%-15s %7d  %.4f / %.4f / %.4f / %.4f  %.2f\n", names[j], r.updates, r.rms[25],
                r.rms[50], r.rms[100], r.rms[kLast], GrowthExponent(r.rms));
  }
  // The subsets that stay inside the image are tracked throughout (20 px of drift).
  for (int k = 1; k < kFrames; ++k) {
    EXPECT_GT(sequential.valid[k], 0.8) << k;
    EXPECT_GT(preconditioned.valid[k], 0.8) << k;
  }
  EXPECT_EQ(sequential.updates, kFrames - 1);  // Every frame becomes the reference.
  EXPECT_EQ(preconditioned.updates, 0);
  // Nothing decorrelates: leapfrog never leaps, and is the preconditioned analysis, result for
  // result.
  EXPECT_EQ(leapfrog.updates, 0);
  EXPECT_TRUE(SameResults(leapfrog.result, preconditioned.result));
  // Preconditioned: the error of one correlation, whatever the frame (no growth).
  EXPECT_LT(preconditioned.rms[kLast], 0.02);
  EXPECT_LT(std::abs(GrowthExponent(preconditioned.rms)), 0.15);
  // Sequential: the increments' errors add up, at least as fast as a random walk's sqrt(k) over
  // most of the range (exponent 0.5; the systematic part of the increments adds up linearly).
  EXPECT_GT(GrowthExponent(sequential.rms), 0.4);
  EXPECT_LT(GrowthExponent(sequential.rms), 1.0);
  EXPECT_GT(sequential.rms[kLast], 2 * sequential.rms[25]);
  EXPECT_GT(sequential.rms[kLast], 3 * preconditioned.rms[kLast]);
}

// The tone curve steepens to I^3 over 101 frames: the ZNCC with the first image falls below 0.95
// near the end, consecutive frames stay above it. Made once for the tests below.
const LongSequence& DecorrelatingSequence() {
  static const LongSequence s = MakeLongSequence(/*frames=*/101, /*tone=*/2);
  return s;
}

TEST(GeopivSchemes, LeapfrogLeapsToThePreviousFrameWhenTheFirstDecorrelates) {
  const LongSequence& s = DecorrelatingSequence();
  const SchemeRun leapfrog = RunScheme(s, "leapfrog");
  const SchemeRun eager = RunScheme(s, "leapfrog:0.99");
  std::printf("tone curve I^1..I^3: leapfrog %d leaps, leapfrog:0.99 %d leaps\n", leapfrog.updates,
              eager.updates);
  EXPECT_GE(leapfrog.updates, 1);
  EXPECT_LE(leapfrog.updates, 5);
  EXPECT_GT(eager.updates, leapfrog.updates);  // A higher threshold leaps sooner and more often.
  for (const SchemeRun* run : {&leapfrog, &eager}) {
    int reference = 0, leaps = 0;
    for (const FrameResult& f : run->result.frames) {
      if (f.reference_updated) {
        // The leap is to the last image that correlated, and this image is solved against it.
        EXPECT_EQ(f.reference_frame, f.frame - 1);
        reference = f.reference_frame;
        ++leaps;
      }
      EXPECT_EQ(f.reference_frame, reference) << f.frame;  // Kept between leaps.
      EXPECT_GT(run->valid[f.frame], 0.8) << f.frame;
    }
    EXPECT_EQ(leaps, run->updates);
  }
}

TEST(GeopivSchemes, SchemesGiveTheResultsOfThePoliciesTheyName) {
  // On the decorrelating sequence, where leapfrog and auto leap.
  const LongSequence& s = DecorrelatingSequence();
  const struct {
    const char* scheme;
    const char* policy;
  } pairs[] = {{"sequential", "incremental"}, {"leapfrog", "auto"}, {"preconditioned", "fixed"}};
  for (const auto& p : pairs) {
    const DicResult a = CorrelateSequence(s.images, LongSequenceOptions(p.scheme));
    const DicResult b = CorrelateSequence(s.images, LongSequenceOptions(p.policy));
    EXPECT_EQ(a.summary.reference_updates, b.summary.reference_updates) << p.scheme;
    EXPECT_TRUE(SameResults(a, b)) << p.scheme << " vs " << p.policy;
    if (std::string(p.scheme) == "leapfrog") {
      EXPECT_GE(a.summary.reference_updates, 1);
    }
  }
}

}  // namespace
}  // namespace impactdic
