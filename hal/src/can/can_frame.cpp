#include "hal/can/can_frame.hpp"

#include <cstdio>

#include "hal/can/can_bus.hpp"
#include "hal/can/hex.hpp"

namespace hal {

std::string to_cansend(const CanFrame& f) {
  char buf[40];
  int n = f.extended || f.error
              ? std::snprintf(buf, sizeof(buf), "%08X#", f.id | (f.error ? 0x20000000U : 0U))
              : std::snprintf(buf, sizeof(buf), "%03X#", f.id);
  std::string s(buf, static_cast<size_t>(n));
  if (f.remote) {
    s += 'R';
    if (f.dlc > 0) s += static_cast<char>('0' + f.dlc);
    return s;
  }
  hex::append_bytes(s, f.data.data(), f.dlc > 8 ? 8 : f.dlc);
  return s;
}

std::string_view to_string(CanSendResult r) {
  switch (r) {
    case CanSendResult::kOk:
      return "ok";
    case CanSendResult::kQueueFull:
      return "tx queue full (frame dropped)";
    case CanSendResult::kBusOff:
      return "bus-off";
    case CanSendResult::kError:
      return "write error";
    case CanSendResult::kClosed:
      return "closed";
  }
  return "?";
}

std::string_view to_string(CanBusState s) {
  switch (s) {
    case CanBusState::kActive:
      return "error-active";
    case CanBusState::kWarning:
      return "error-warning";
    case CanBusState::kPassive:
      return "error-passive";
    case CanBusState::kBusOff:
      return "bus-off";
    case CanBusState::kClosed:
      return "closed";
  }
  return "?";
}

}  // namespace hal
