#include "impactdic/dic/correlate_frames.h"

#include <tbb/parallel_invoke.h>
#include <tbb/task_group.h>

#include <cmath>
#include <cstddef>
#include <exception>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/progress.h"

namespace impactdic {
namespace {

// Runs `read` on a worker while the caller correlates; wait() rethrows its error.
class Prefetch {
 public:
  template <typename Read>
  void Start(Read read) {
    group_.run([this, read] {
      try {
        frame_ = read();
      } catch (...) {
        error_ = std::current_exception();
      }
    });
  }
  cv::Mat Wait() {
    group_.wait();
    if (error_) std::rethrow_exception(error_);
    return std::move(frame_);
  }
  // After an error of the caller's own: the read finishes, its error is dropped.
  void Abandon() {
    group_.cancel();
    group_.wait();
  }

 private:
  tbb::task_group group_;
  cv::Mat frame_;
  std::exception_ptr error_;
};

// The frame numbers and (when the source has any) the time stamps of every frame.
void NumberFrames(const FrameSource& frames, DicResult* result) {
  bool timed = false;
  for (int k = 0; k < frames.frame_count(); ++k) {
    result->frame_numbers.push_back(frames.FrameNumber(k));
    result->time_s.push_back(frames.TimeS(k));
    timed = timed || std::isfinite(result->time_s.back());
  }
  if (!timed) result->time_s.clear();
}

}  // namespace

DicResult CorrelateFrames(FrameSource& frames, const DicOptions& options,
                          const FrameResultSink& sink) {
  options.Check();
  const int count = frames.frame_count();
  CheckValue(count >= 2, "images", std::to_string(count),
             "a reference and at least one deformed image");
  DicOptions own = options;
  // A camera file's bit depth, which the pixels cannot tell (10-bit data fits 0..4095 too).
  if (own.data_bits == 0 && frames.StatesDataBits()) own.data_bits = frames.data_bits();
  Correlator correlator(own);
  const cv::Mat reference = frames.Read(0);
  // The reference's precomputation while frame 1 is read; an error of the reference is reported
  // first (deterministic).
  Prefetch prefetch;
  prefetch.Start([&frames] { return frames.Read(1); });
  try {
    correlator.SetReference(reference);
  } catch (...) {
    prefetch.Abandon();
    throw;
  }
  cv::Mat current = prefetch.Wait();
  DicResult result;
  result.positions = correlator.positions();
  ProgressBar bar("correlate", static_cast<std::size_t>(count - 1));
  for (int k = 1; k < count; ++k) {
    if (k + 1 < count) prefetch.Start([&frames, k] { return frames.Read(k + 1); });
    try {
      FrameResult frame = correlator.Correlate(current);
      if (sink) {
        sink(std::move(frame));
      } else {
        result.frames.push_back(std::move(frame));
      }
    } catch (...) {  // The correlation's (or the sink's) error is the one to report.
      if (k + 1 < count) prefetch.Abandon();
      throw;
    }
    current = k + 1 < count ? prefetch.Wait() : cv::Mat();  // Rethrows a read error.
    bar.Advance();
  }
  bar.Finish();
  result.summary = correlator.summary();
  NumberFrames(frames, &result);
  result.warnings = frames.warnings();
  return result;
}

// The library's in-memory sequence: the driver on the frames as given.
DicResult CorrelateSequence(const std::vector<cv::Mat>& images, const DicOptions& options) {
  CheckValue(images.size() >= 2, "images", std::to_string(images.size()),
             "a reference and at least one deformed image");
  const std::unique_ptr<FrameSource> frames = MakeMemoryFrameSource(images);
  DicResult result = CorrelateFrames(*frames, options);
  result.frame_numbers.clear();  // Frames in memory: the indices (frames[k].frame) say it all.
  return result;
}

}  // namespace impactdic
