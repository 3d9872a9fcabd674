#include "impactdic/core/log.h"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <memory>

namespace impactdic {
namespace {

std::atomic<LogLevel> g_level{LogLevel::kInfo};

spdlog::logger& Logger() {
  static std::shared_ptr<spdlog::logger> logger = [] {
    auto l = spdlog::stderr_color_mt("impactdic");
    l->set_pattern("%^[%l]%$ %v");
    l->set_level(spdlog::level::trace);
    return l;
  }();
  return *logger;
}

}  // namespace

void SetLogLevel(LogLevel level) { g_level = level; }
LogLevel GetLogLevel() { return g_level; }

void LogMessage(LogLevel level, const std::string& text) {
  if (level < g_level.load() || level == LogLevel::kOff) return;
  switch (level) {
    case LogLevel::kDebug: Logger().debug(text); break;
    case LogLevel::kInfo: Logger().info(text); break;
    case LogLevel::kWarning: Logger().warn(text); break;
    case LogLevel::kError: Logger().error(text); break;
    case LogLevel::kOff: break;
  }
}

}  // namespace impactdic
