#include "firmware/logging.hpp"

#include <spdlog/async.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/sinks/systemd_sink.h>

#include <cstdlib>

namespace firmware {

bool setup_logging(const std::string& level, LogSink sink) {
  const spdlog::level::level_enum lvl = spdlog::level::from_str(level);
  // from_str maps unknown names to "off": treat that as an error unless asked for.
  if (lvl == spdlog::level::off && level != "off") return false;

  if (sink == LogSink::kAuto) {
    // Read once at start-up, before any thread runs.
    const bool under_systemd =
        std::getenv("JOURNAL_STREAM") != nullptr ||  // NOLINT(concurrency-mt-unsafe)
        std::getenv("INVOCATION_ID") != nullptr;     // NOLINT(concurrency-mt-unsafe)
    sink = under_systemd ? LogSink::kJournald : LogSink::kConsole;
  }
  if (spdlog::thread_pool() == nullptr) spdlog::init_thread_pool(8192, 1);
  spdlog::sink_ptr s;
  if (sink == LogSink::kJournald) {
    s = std::make_shared<spdlog::sinks::systemd_sink_mt>();
  } else {
    s = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  }
  auto logger = std::make_shared<spdlog::async_logger>(
      "companion", s, spdlog::thread_pool(), spdlog::async_overflow_policy::overrun_oldest);
  logger->set_level(lvl);
  logger->flush_on(spdlog::level::warn);
  if (sink == LogSink::kJournald) {
    logger->set_pattern("%v");  // journald stamps and tags on its own
  } else {
    logger->set_pattern("%Y-%m-%d %H:%M:%S.%e %^%-5l%$ %v");
  }
  spdlog::set_default_logger(logger);
  return true;
}

void shutdown_logging() {
  if (auto l = spdlog::default_logger()) l->flush();
  spdlog::shutdown();
}

}  // namespace firmware
