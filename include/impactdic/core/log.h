// The one logging wrapper: everything goes to stderr through spdlog.
//
//   impactdic::LogInfo("correlated {} subsets in {:.2f} s", n, seconds);
#ifndef IMPACTDIC_CORE_LOG_H_
#define IMPACTDIC_CORE_LOG_H_

#include <fmt/format.h>

#include <string>
#include <utility>

namespace impactdic {

enum class LogLevel { kDebug, kInfo, kWarning, kError, kOff };

// Sets the level below which messages are dropped (default kInfo). --verbose = kDebug,
// --quiet = kWarning.
void SetLogLevel(LogLevel level);
LogLevel GetLogLevel();

void LogMessage(LogLevel level, const std::string& text);

template <typename... Args>
void LogDebug(fmt::format_string<Args...> format, Args&&... args) {
  if (GetLogLevel() <= LogLevel::kDebug)
    LogMessage(LogLevel::kDebug, fmt::format(format, std::forward<Args>(args)...));
}
template <typename... Args>
void LogInfo(fmt::format_string<Args...> format, Args&&... args) {
  if (GetLogLevel() <= LogLevel::kInfo)
    LogMessage(LogLevel::kInfo, fmt::format(format, std::forward<Args>(args)...));
}
template <typename... Args>
void LogWarning(fmt::format_string<Args...> format, Args&&... args) {
  if (GetLogLevel() <= LogLevel::kWarning)
    LogMessage(LogLevel::kWarning, fmt::format(format, std::forward<Args>(args)...));
}

}  // namespace impactdic

#endif  // IMPACTDIC_CORE_LOG_H_
