#pragma once
// systemd notification protocol (sd_notify over the NOTIFY_SOCKET unix datagram socket).
// Every call is a no-op returning false when not started by systemd (no NOTIFY_SOCKET).
#include <chrono>
#include <optional>
#include <string_view>

namespace hal {

class SystemdNotifier {
 public:
  // True when NOTIFY_SOCKET is set, i.e. systemd (or a test) listens.
  [[nodiscard]] bool enabled() const;

  bool ready();                        // READY=1
  bool watchdog();                     // WATCHDOG=1
  bool status(std::string_view line);  // STATUS=<line>
  bool stopping();                     // STOPPING=1
  bool ready_with_status(std::string_view line);

  // WatchdogSec of the unit (from WATCHDOG_USEC / WATCHDOG_PID), if the watchdog is enabled
  // for this process.
  [[nodiscard]] static std::optional<std::chrono::microseconds> watchdog_interval();

 private:
  bool send(std::string_view message);
};

}  // namespace hal
