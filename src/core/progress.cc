#include "impactdic/core/progress.h"

#include <unistd.h>

#include <cstdio>
#include <utility>

#include "impactdic/core/log.h"

namespace impactdic {
namespace {

thread_local ProgressObserver* t_observer = nullptr;

}  // namespace

ScopedProgressObserver::ScopedProgressObserver(ProgressObserver* observer) : previous_(t_observer) {
  t_observer = observer;
}

ScopedProgressObserver::~ScopedProgressObserver() { t_observer = previous_; }

void StopPoint() {
  if (t_observer != nullptr && t_observer->ShouldStop()) throw Stopped();
}

ProgressBar::ProgressBar(std::string label, std::size_t total)
    : label_(std::move(label)),
      total_(total),
      enabled_(isatty(fileno(stderr)) != 0 && GetLogLevel() <= LogLevel::kInfo && total > 1),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

ProgressBar::~ProgressBar() { Finish(); }

void ProgressBar::Advance(std::size_t steps) {
  done_ += steps;
  if (t_observer != nullptr) {
    t_observer->Advanced(label_, done_, total_);
    StopPoint();
  }
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (done_ >= total_ || now - last_draw_ > std::chrono::milliseconds(100)) {
    last_draw_ = now;
    Draw();
  }
}

void ProgressBar::Finish() {
  if (!enabled_ || finished_) return;
  finished_ = true;
  Draw();
  std::fputc('\n', stderr);
}

void ProgressBar::Draw() {
  constexpr int kWidth = 30;
  const double fraction = total_ ? static_cast<double>(done_) / total_ : 1.0;
  const int filled = static_cast<int>(fraction * kWidth);
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "\r%s [%.*s%*s] %zu/%zu %.1f s", label_.c_str(), filled,
               "##############################", kWidth - filled, "", done_, total_, elapsed);
  std::fflush(stderr);
}

}  // namespace impactdic
