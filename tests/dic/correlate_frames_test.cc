// The one correlation driver (CorrelateFrames): the same results as the correlator's own loop on
// an in-memory known-shift sequence, each frame handed to a sink in order, errors reading a frame
// naming it (the reference's first), and the source's frame numbers and time stamps carried to
// the results table.
#include "impactdic/dic/correlate_frames.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "../core/expect_error.h"
#include "impactdic/core/error.h"
#include "impactdic/core/progress.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/dic/dic_io.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/frame_source.h"
#include "impactdic/synth/fields.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {
namespace {

// Frame k moves by (0.4 k, -0.3 k) px: 96 x 80 px of rendered speckle.
std::vector<cv::Mat> ShiftedFrames(int count) {
  SpeckleOptions speckle;
  speckle.blob_radius_px = 2.5;
  SpecklePattern pattern(speckle, 96, 80);
  RenderOptions render;
  render.supersampling = 2;
  std::vector<cv::Mat> frames;
  frames.reserve(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k)
    frames.push_back(RenderImage(pattern, 96, 80, Translation(0.4 * k, -0.3 * k), render));
  return frames;
}

DicOptions SmallOptions() {
  DicOptions o;
  o.grid.subset_size = 21;
  o.grid.step = 12;
  return o;
}

// Frames in memory whose frame `bad` cannot be read.
class FailingSource : public FrameSource {
 public:
  FailingSource(std::vector<cv::Mat> frames, int bad) : frames_(std::move(frames)), bad_(bad) {}
  int frame_count() const override { return static_cast<int>(frames_.size()); }
  cv::Mat Read(int index) override {
    if (index == bad_) throw Error(ErrorKind::kFileFormat, "image", Name(index), "readable");
    return frames_[static_cast<std::size_t>(index)];
  }
  std::string Name(int index) const override { return "frame_" + std::to_string(index) + ".png"; }
  long long FrameNumber(int index) const override { return 100 + index; }
  std::string description() const override { return "failing frames"; }

 private:
  std::vector<cv::Mat> frames_;
  int bad_;
};

// The loop CorrelateSequence ran before the driver: SetReference, then Correlate frame by frame.
TEST(CorrelateFrames, SameResultsAsTheCorrelatorsOwnLoop) {
  const std::vector<cv::Mat> frames = ShiftedFrames(5);
  const DicOptions options = SmallOptions();
  Correlator correlator(options);
  correlator.SetReference(frames[0]);
  std::vector<FrameResult> expected;
  for (std::size_t k = 1; k < frames.size(); ++k)
    expected.push_back(correlator.Correlate(frames[k]));

  const auto source = MakeMemoryFrameSource(frames);
  const DicResult result = CorrelateFrames(*source, options);
  ASSERT_EQ(result.frames.size(), expected.size());
  EXPECT_EQ(result.positions, correlator.positions());
  int converged = 0;
  for (std::size_t k = 0; k < expected.size(); ++k) {
    const FrameResult& a = result.frames[k];
    const FrameResult& b = expected[k];
    EXPECT_EQ(a.frame, b.frame);
    EXPECT_EQ(a.reference_frame, b.reference_frame);
    EXPECT_EQ(a.status, b.status) << "frame " << k;
    for (std::size_t i = 0; i < a.u_px.size(); ++i) {
      if (a.status[i] != SubsetStatus::kConverged) continue;
      ++converged;
      EXPECT_EQ(a.u_px[i], b.u_px[i]);  // Bit for bit.
      EXPECT_EQ(a.v_px[i], b.v_px[i]);
      EXPECT_NEAR(a.u_px[i], 0.4 * a.frame, 0.02);
      EXPECT_NEAR(a.v_px[i], -0.3 * a.frame, 0.02);
    }
  }
  EXPECT_GT(converged, 0);
  EXPECT_EQ(result.summary.frames, 4);
  EXPECT_EQ(result.frame_numbers, (std::vector<long long>{0, 1, 2, 3, 4}));
  EXPECT_TRUE(result.time_s.empty());  // The source has no time stamps.

  const DicResult sequence = CorrelateSequence(frames, options);  // The library's entry.
  ASSERT_EQ(sequence.frames.size(), expected.size());
  for (std::size_t k = 0; k < expected.size(); ++k)
    EXPECT_EQ(sequence.frames[k].u_px, result.frames[k].u_px);
}

// Counts the steps and the stop points; stops at stop point `stop_at` (0: never).
class CountingObserver : public ProgressObserver {
 public:
  explicit CountingObserver(int stop_at) : stop_at_(stop_at) {}
  void Advanced(const std::string& label, std::size_t done, std::size_t total) override {
    if (label == "correlate") steps.push_back(static_cast<int>(done * 100 + total));
  }
  bool ShouldStop() override { return ++asked == stop_at_; }

  std::vector<int> steps;  // done * 100 + total.
  int asked = 0;

 private:
  int stop_at_;
};

// Stop points ask the observer several times per frame (the reference's precomputation, each
// phase and propagation wave), change no result, and a stop at any of them ends the correlation
// with Stopped.
TEST(CorrelateFrames, AnObserverSeesEachFrameAndCanStopAtAnyStopPoint) {
  const std::vector<cv::Mat> frames = ShiftedFrames(4);
  const DicResult plain = CorrelateSequence(frames, SmallOptions());
  CountingObserver watch_all(/*stop_at=*/0);
  DicResult watched;
  {
    const ScopedProgressObserver scope(&watch_all);
    watched = CorrelateSequence(frames, SmallOptions());
  }
  EXPECT_EQ(watch_all.steps, (std::vector<int>{103, 203, 303}));
  const int stop_points = watch_all.asked;
  EXPECT_GE(stop_points, 3 * 4);  // At least a few per frame.
  ASSERT_EQ(watched.frames.size(), plain.frames.size());
  for (std::size_t k = 0; k < plain.frames.size(); ++k)
    EXPECT_EQ(watched.frames[k].u_px, plain.frames[k].u_px);
  for (const int stop_at : {1, stop_points / 2, stop_points}) {
    CountingObserver stopper(stop_at);
    const ScopedProgressObserver scope(&stopper);
    EXPECT_THROW(CorrelateSequence(frames, SmallOptions()), Stopped) << "stop point " << stop_at;
    EXPECT_EQ(stopper.asked, stop_at);
  }
}

TEST(CorrelateFrames, HandsEachFrameToTheSinkInOrder) {
  const auto source = MakeMemoryFrameSource(ShiftedFrames(4), {-0.002, -0.001, 0.0, 0.001}, 1000);
  std::vector<int> seen;
  const DicResult result = CorrelateFrames(*source, SmallOptions(), [&](FrameResult&& f) {
    EXPECT_FALSE(f.u_px.empty());
    seen.push_back(f.frame);
  });
  EXPECT_EQ(seen, (std::vector<int>{1, 2, 3}));
  EXPECT_TRUE(result.frames.empty());
  EXPECT_EQ(result.summary.frames, 3);
  EXPECT_EQ(result.time_s, (std::vector<double>{-0.002, -0.001, 0.0, 0.001}));
}

TEST(CorrelateFrames, AFrameThatCannotBeReadIsNamedTheReferenceFirst) {
  const std::vector<cv::Mat> frames = ShiftedFrames(4);
  for (int bad : {0, 1, 3}) {
    FailingSource source(frames, bad);
    ExpectErrorContaining([&] { CorrelateFrames(source, SmallOptions()); },
                          "frame_" + std::to_string(bad) + ".png");
  }
  FailingSource none(frames, -1);
  const DicResult ok = CorrelateFrames(none, SmallOptions());
  EXPECT_EQ(ok.frame_numbers, (std::vector<long long>{100, 101, 102, 103}));
  // Fewer than two frames.
  const auto one = MakeMemoryFrameSource({frames[0]});
  ExpectErrorContaining([&] { CorrelateFrames(*one, SmallOptions()); }, "at least one deformed");
}

TEST(CorrelateFrames, TimeStampsReachTheResultsTable) {
  const auto source = MakeMemoryFrameSource(ShiftedFrames(3), {0.5, 0.75, 1.0}, 4);
  const DicOptions options = SmallOptions();
  const DicResultsTable table = MakeDicResultsTable(CorrelateFrames(*source, options), options, -1);
  EXPECT_EQ(table.time_s, (std::vector<double>{0.5, 0.75, 1.0}));
  EXPECT_EQ(table.frame_number, (std::vector<double>{0, 1, 2}));
  const auto untimed = MakeMemoryFrameSource(ShiftedFrames(2));
  EXPECT_TRUE(MakeDicResultsTable(CorrelateFrames(*untimed, options), options, -1).time_s.empty());
}

}  // namespace
}  // namespace impactdic
