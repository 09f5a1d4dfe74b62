#include <string>

#include "hal/can/can_bus.hpp"
#include "hal/can/slcan_bus.hpp"
#include "hal/can/socketcan_bus.hpp"
#include "hal/can/virtual_can.hpp"

namespace hal {

CanOpenResult open_can(std::string_view uri, Clock& clock,
                       const std::vector<uint32_t>& receive_ids) {
  const auto colon = uri.find(':');
  if (colon == std::string_view::npos || colon + 1 >= uri.size()) {
    return {nullptr, "CAN URI '" + std::string(uri) +
                         "' must be socketcan:<ifname>, slcan:<device>[@baud] or virtual:<name>"};
  }
  const std::string scheme(uri.substr(0, colon));
  std::string target(uri.substr(colon + 1));
  if (scheme == "virtual") return {std::make_unique<VirtualCanBus>(target, clock), ""};
  if (scheme == "socketcan") return SocketCanBus::open(target, receive_ids, clock);
  if (scheme == "slcan") {
    int baud = 115200;  // ignored by USB-CDC adapters, used by UART ones
    if (const auto at = target.find('@'); at != std::string::npos) {
      try {
        baud = std::stoi(target.substr(at + 1));
      } catch (const std::exception&) {
        return {nullptr, "slcan: bad baud rate in '" + std::string(uri) + "'"};
      }
      target.resize(at);
    }
    return SlcanBus::open(target, baud, 500, clock);
  }
  return {nullptr, "unknown CAN transport '" + scheme + "' (socketcan, slcan, virtual)"};
}

}  // namespace hal
