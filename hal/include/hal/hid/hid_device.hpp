#pragma once
// USB HID devices through hidapi (hidraw backend on Linux): enumeration, open by path or serial
// number, non-blocking report reads and OUT report writes. Device-neutral: the caller names the
// vendor and product ids (amfitrack/ knows which).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace hal {

struct HidDeviceInfo {
  std::string path;  // /dev/hidrawN with the hidraw backend
  uint16_t vendor_id = 0;
  uint16_t product_id = 0;
  std::string serial_number;
  std::string manufacturer;
  std::string product;
  int interface_number = -1;
};

class HidDevice {
 public:
  virtual ~HidDevice() = default;
  // Non-blocking: bytes of one input report (0 when none is queued), -1 when the device failed
  // (unplugged): see last_error().
  virtual long read(std::span<uint8_t> report) = 0;
  // One output report (first byte = report id). Bytes written or -1.
  virtual long write(std::span<const uint8_t> report) = 0;
  [[nodiscard]] virtual std::string last_error() const = 0;
};

// Devices of `vendor_id` whose product id is in `product_ids` (all products when empty), in a
// stable order (by path). An error (e.g. hidapi cannot start) yields an empty list and `error`.
std::vector<HidDeviceInfo> hid_enumerate(uint16_t vendor_id, std::span<const uint16_t> product_ids,
                                         std::string* error = nullptr);

// What to open: "auto" (the first device found), a device path ("/dev/hidraw3"), or a serial
// number ("serial=ABC123" or just "ABC123").
struct HidSelector {
  enum class Kind : uint8_t { kAuto, kPath, kSerial } kind = Kind::kAuto;
  std::string value;
};
HidSelector parse_hid_selector(const std::string& text);
// A device path with its symbolic links followed (udev's /dev/amfitrack-sensor -> hidraw3), so it
// compares with the enumerated hidraw paths. Unchanged when it is not a link.
std::string resolve_device_path(const std::string& path);
// Picks from an enumeration; nullptr when nothing matches. A path is accepted only if it is one
// of the listed devices (so a wrong hidraw node is not opened by mistake).
const HidDeviceInfo* select_hid(const std::vector<HidDeviceInfo>& devices,
                                const HidSelector& selector);

struct HidOpenResult {
  std::unique_ptr<HidDevice> device;
  HidDeviceInfo info;
  std::string error;  // names the selector and why
};
HidOpenResult open_hid(uint16_t vendor_id, std::span<const uint16_t> product_ids,
                       const HidSelector& selector);

}  // namespace hal
