#include "amfitrack/open_link.hpp"

#include <charconv>

namespace amfitrack {

std::optional<LinkUri> parse_link_uri(const std::string& uri, std::string* error) {
  auto fail = [&](const std::string& why) -> std::optional<LinkUri> {
    if (error != nullptr) *error = "tracker device '" + uri + "': " + why;
    return std::nullopt;
  };
  constexpr std::string_view kHid = "hid:";
  constexpr std::string_view kSerial = "serial:";
  LinkUri u;
  if (uri.rfind(kHid, 0) == 0) {
    u.kind = LinkUri::Kind::kHid;
    u.target = uri.substr(kHid.size());
    if (u.target.empty()) u.target = "auto";
    return u;
  }
  if (uri.rfind(kSerial, 0) == 0) {
    u.kind = LinkUri::Kind::kSerial;
    std::string rest = uri.substr(kSerial.size());
    const size_t at = rest.rfind('@');
    if (at != std::string::npos) {
      const std::string baud = rest.substr(at + 1);
      int b = 0;
      const auto [p, ec] = std::from_chars(baud.data(), baud.data() + baud.size(), b);
      if (ec != std::errc() || p != baud.data() + baud.size() || b < 1200 || b > 4000000) {
        return fail("baud rate '" + baud + "' is not a number in 1200..4000000");
      }
      u.baud = b;
      rest.resize(at);
    }
    if (rest.empty()) return fail("no serial port given (serial:/dev/ttyUSB0[@115200])");
    u.target = rest;
    return u;
  }
  return fail("expected hid:auto, hid:<hidraw path or serial> or serial:<port>[@baud]");
}

OpenedLink open_link(const LinkUri& uri) {
  OpenedLink out;
  if (uri.kind == LinkUri::Kind::kSerial) {
    hal::SerialOpenResult r = hal::open_serial(uri.target, uri.baud);
    if (!r.port) {
      out.error = r.error;
      return out;
    }
    out.description = uri.target + " @" + std::to_string(uri.baud) + " (" + r.port->backend() + ")";
    out.link = std::make_unique<SerialCobsLink>(std::move(r.port));
    return out;
  }
  hal::HidOpenResult r =
      hal::open_hid(kUsbVendorId, kUsbProductIds, hal::parse_hid_selector(uri.target));
  if (!r.device) {
    out.error = r.error;
    return out;
  }
  out.description = r.info.path + " " + r.info.product +
                    (r.info.serial_number.empty() ? "" : " serial " + r.info.serial_number);
  out.link = std::make_unique<HidPacketLink>(std::move(r.device));
  return out;
}

std::vector<hal::HidDeviceInfo> list_hid_devices(std::string* error) {
  return hal::hid_enumerate(kUsbVendorId, kUsbProductIds, error);
}

}  // namespace amfitrack
