// A progress bar for long loops. It draws on stderr only when stderr is a terminal and the log
// level is kInfo or lower, so logs and CI output stay clean.
//
//   ProgressBar bar("correlate", frames.size());
//   for (...) { ...; bar.Advance(); }
#ifndef IMPACTDIC_CORE_PROGRESS_H_
#define IMPACTDIC_CORE_PROGRESS_H_

#include <chrono>
#include <cstddef>
#include <string>

namespace impactdic {

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
