#pragma once
// Logging set-up: spdlog, to journald when started by systemd, to the console otherwise.
// The logger is asynchronous (a bounded queue drained by one background thread, oldest message
// dropped when full) so a slow journal or terminal never blocks a real-time task.
#include <spdlog/spdlog.h>

#include <string>
#include <utility>

#include "core/util/rate_limiter.hpp"

namespace firmware {

enum class LogSink { kAuto, kConsole, kJournald };

// Installs the default logger. kAuto picks journald when systemd started us (JOURNAL_STREAM or
// INVOCATION_ID set), the console otherwise. Returns false for an unknown level name.
bool setup_logging(const std::string& level, LogSink sink = LogSink::kAuto);
// Flushes and tears down the async logger (call before exit).
void shutdown_logging();

// A warning that may repeat every cycle: logged at most once per interval, with the number of
// repeats that were held back.
class RateLimitedLog {
 public:
  explicit RateLimitedLog(core::Nanos min_interval) : limiter_(min_interval) {}

  template <typename... Args>
  void warn(core::Nanos now, spdlog::format_string_t<Args...> fmt, Args&&... args) {
    const auto d = limiter_.check(now);
    if (!d.emit) return;
    if (d.suppressed > 0) {
      spdlog::warn("{} ({} similar suppressed)", fmt::format(fmt, std::forward<Args>(args)...),
                   d.suppressed);
    } else {
      spdlog::warn(fmt, std::forward<Args>(args)...);
    }
  }

 private:
  core::RateLimiter limiter_;
};

}  // namespace firmware
