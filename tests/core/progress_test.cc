// The observer of the library's long loops (core/progress.h): a ProgressBar reports to the
// observer of its own thread only, StopPoint throws Stopped when the observer asks, and without
// an observer nothing happens.
#include "impactdic/core/progress.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

namespace impactdic {
namespace {

// Records the steps; asks to stop once `stop_after` questions were asked (-1: never).
class Recorder : public ProgressObserver {
 public:
  explicit Recorder(int stop_after = -1) : stop_after_(stop_after) {}
  void Advanced(const std::string& label, std::size_t done, std::size_t total) override {
    steps.emplace_back(label, done, total);
  }
  bool ShouldStop() override {
    ++asked;
    return stop_after_ >= 0 && asked > stop_after_;
  }

  std::vector<std::tuple<std::string, std::size_t, std::size_t>> steps;
  int asked = 0;

 private:
  int stop_after_;
};

TEST(ProgressObserver, SeesTheBarsOfItsThreadOnly) {
  Recorder recorder;
  {
    const ScopedProgressObserver watch(&recorder);
    ProgressBar bar("correlate", 3);
    bar.Advance();
    bar.Advance(2);
    std::thread elsewhere([] {  // Another thread's bar: not this observer's.
      ProgressBar other("frames", 2);
      other.Advance();
    });
    elsewhere.join();
  }
  ProgressBar after("correlate", 2);  // The observer's scope ended.
  after.Advance();
  using Step = std::tuple<std::string, std::size_t, std::size_t>;
  EXPECT_EQ(recorder.steps, (std::vector<Step>{{"correlate", 1, 3}, {"correlate", 3, 3}}));
  EXPECT_EQ(recorder.asked, 2);  // A stop point after each step.
}

TEST(ProgressObserver, StopPointThrowsStoppedWhenAsked) {
  EXPECT_NO_THROW(StopPoint());  // No observer: never.
  Recorder recorder(/*stop_after=*/2);
  const ScopedProgressObserver watch(&recorder);
  EXPECT_NO_THROW(StopPoint());
  ProgressBar bar("correlate", 5);
  EXPECT_NO_THROW(bar.Advance());
  EXPECT_THROW(bar.Advance(), Stopped);
  EXPECT_EQ(recorder.steps.size(), 2U);  // Reported, then stopped.
}

TEST(ProgressObserver, ScopesNest) {
  Recorder outer, inner(/*stop_after=*/0);
  const ScopedProgressObserver watch_outer(&outer);
  {
    const ScopedProgressObserver watch_inner(&inner);
    EXPECT_THROW(StopPoint(), Stopped);
  }
  EXPECT_NO_THROW(StopPoint());  // The outer one again.
  EXPECT_EQ(inner.asked, 1);
  EXPECT_EQ(outer.asked, 1);
}

}  // namespace
}  // namespace impactdic
