#include "hal/sd_notify.hpp"

#include <systemd/sd-daemon.h>

#include <cstdint>
#include <cstdlib>
#include <string>

namespace hal {

bool SystemdNotifier::enabled() const {
  // Read-only use of the environment; nothing in the daemon modifies it after start-up.
  return std::getenv("NOTIFY_SOCKET") != nullptr;  // NOLINT(concurrency-mt-unsafe)
}

bool SystemdNotifier::send(std::string_view message) {
  if (!enabled()) return false;
  const std::string msg(message);
  return sd_notify(0, msg.c_str()) > 0;
}

bool SystemdNotifier::ready() {
  return send("READY=1");
}
bool SystemdNotifier::watchdog() {
  return send("WATCHDOG=1");
}
bool SystemdNotifier::stopping() {
  return send("STOPPING=1");
}

bool SystemdNotifier::status(std::string_view line) {
  std::string msg = "STATUS=";
  // STATUS is one line: newlines would end the assignment early.
  for (const char c : line)
    msg.push_back(c == '\n' ? ' ' : c);
  return send(msg);
}

bool SystemdNotifier::ready_with_status(std::string_view line) {
  std::string msg = "READY=1\nSTATUS=";
  for (const char c : line)
    msg.push_back(c == '\n' ? ' ' : c);
  return send(msg);
}

std::optional<std::chrono::microseconds> SystemdNotifier::watchdog_interval() {
  uint64_t usec = 0;
  if (sd_watchdog_enabled(0, &usec) > 0 && usec > 0) {
    return std::chrono::microseconds(static_cast<int64_t>(usec));
  }
  return std::nullopt;
}

}  // namespace hal
