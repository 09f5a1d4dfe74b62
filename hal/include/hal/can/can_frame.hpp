#pragma once
// A classic CAN frame as every CAN transport, log file and codec in companion sees it.
#include <array>
#include <cstdint>
#include <string>

#include "hal/clock.hpp"

namespace hal {

struct CanFrame {
  uint32_t id = 0;        // 11-bit (standard) or 29-bit (extended) identifier, no flag bits
  bool extended = false;  // 29-bit identifier
  bool remote = false;    // remote transmission request (no data)
  bool error = false;     // error frame (id holds the CAN_ERR_* class bits, as in SocketCAN)
  uint8_t dlc = 0;        // 0..8
  std::array<uint8_t, 8> data{};

  bool operator==(const CanFrame& o) const {
    if (id != o.id || extended != o.extended || remote != o.remote || error != o.error ||
        dlc != o.dlc) {
      return false;
    }
    for (uint8_t i = 0; i < dlc && i < 8; ++i) {
      if (data[i] != o.data[i]) return false;
    }
    return true;
  }

  static CanFrame standard(uint32_t id, std::initializer_list<uint8_t> bytes) {
    CanFrame f;
    f.id = id;
    for (const uint8_t b : bytes) {
      if (f.dlc < 8) f.data[f.dlc++] = b;
    }
    return f;
  }
};

struct StampedCanFrame {
  CanFrame frame;
  Nanos stamp;  // monotonic reception time
};

// "111#0096000000000000" (candump/cansend notation).
std::string to_cansend(const CanFrame& f);

}  // namespace hal
