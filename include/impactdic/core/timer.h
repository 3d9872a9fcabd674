// Wall-clock timer for the cost side of every "error against run time" report.
#ifndef IMPACTDIC_CORE_TIMER_H_
#define IMPACTDIC_CORE_TIMER_H_

#include <chrono>

namespace impactdic {

class WallTimer {
 public:
  WallTimer() : start_(std::chrono::steady_clock::now()) {}
  void Restart() { start_ = std::chrono::steady_clock::now(); }
  double ElapsedSeconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace impactdic

#endif  // IMPACTDIC_CORE_TIMER_H_
