// A progress bar for long loops. It draws on stderr only when stderr is a terminal and the log
// level is kInfo or lower, so logs and CI output stay clean.
//
//   ProgressBar bar("correlate", frames.size());
//   for (...) { ...; bar.Advance(); }
//
// A caller that cannot end the process to stop the library (the Python module: Ctrl-C raises
// KeyboardInterrupt, a progress callback) watches the thread that calls the library:
//
//   MyObserver observer;                           // a ProgressObserver
//   { ScopedProgressObserver watch(&observer); CorrelateSceneInMemory(...); }  // may throw Stopped
#ifndef IMPACTDIC_CORE_PROGRESS_H_
#define IMPACTDIC_CORE_PROGRESS_H_

#include <chrono>
#include <cstddef>
#include <stdexcept>
#include <string>

namespace impactdic {

// Watches the library's long loops on one thread: every ProgressBar of that thread reports its
// steps, and the library's stop points on that thread (StopPoint: between frames, phases and
// propagation waves of a correlation, a few per 0.1 s of work) ask whether to stop.
class ProgressObserver {
 public:
  virtual ~ProgressObserver() = default;
  // `label`'s loop (the ProgressBar's label: "frames", "correlate") has done `done` of `total`.
  virtual void Advanced(const std::string& label, std::size_t done, std::size_t total) = 0;
  // true: the computation stops (StopPoint throws Stopped).
  virtual bool ShouldStop() = 0;
};

// Makes `observer` the calling thread's observer while it lives (the previous one after).
class ScopedProgressObserver {
 public:
  explicit ScopedProgressObserver(ProgressObserver* observer);
  ~ScopedProgressObserver();
  ScopedProgressObserver(const ScopedProgressObserver&) = delete;
  ScopedProgressObserver& operator=(const ScopedProgressObserver&) = delete;

 private:
  ProgressObserver* previous_;
};

// A computation stopped because its observer asked (not an impactdic::Error: nothing that treats a
// bad input as a failed stage or test catches it).
class Stopped : public std::runtime_error {
 public:
  Stopped() : std::runtime_error("stopped by the caller") {}
};

// Throws Stopped if the calling thread's observer asks to stop; nothing without an observer.
void StopPoint();

class ProgressBar {
 public:
  ProgressBar(std::string label, std::size_t total);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  void Advance(std::size_t steps = 1);
  void Finish();
  bool enabled() const { return enabled_; }

 private:
  void Draw();

  std::string label_;
  std::size_t total_, done_ = 0;
  bool enabled_, finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace impactdic

#endif  // IMPACTDIC_CORE_PROGRESS_H_
