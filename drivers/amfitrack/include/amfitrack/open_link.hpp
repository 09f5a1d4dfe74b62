#pragma once
// Tracker links from a device URI (the `devices.tracker` config key and the tools' --device):
//   hid:auto | hid:/dev/hidrawN | hid:serial=<serial> | hid:<serial>  (USB HID, hidapi)
//   serial:<port>[@baud]                                               (UART, COBS, 8N1)
#include <cstdint>
#include <optional>
#include <string>

#include "amfitrack/packet_link.hpp"

namespace amfitrack {

inline constexpr uint16_t kUsbVendorId = 0x0C17;
inline constexpr std::array<uint16_t, 2> kUsbProductIds = {0x0D01 /*source*/, 0x0D12 /*sensor*/};
inline constexpr int kDefaultBaud = 115200;

struct LinkUri {
  enum class Kind : uint8_t { kHid, kSerial } kind = Kind::kHid;
  std::string target;  // HID selector, or serial port path
  int baud = kDefaultBaud;
};
// nullopt (and `error`) for anything else, e.g. a bad baud rate.
std::optional<LinkUri> parse_link_uri(const std::string& uri, std::string* error);

// Opens the link once (for the tools and the daemon's opener).
OpenedLink open_link(const LinkUri& uri);

// HID devices of Amfitech (source and sensor product ids).
std::vector<hal::HidDeviceInfo> list_hid_devices(std::string* error = nullptr);

}  // namespace amfitrack
