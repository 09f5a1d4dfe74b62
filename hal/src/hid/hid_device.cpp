#include "hal/hid/hid_device.hpp"

#include <hidapi/hidapi.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <cwchar>
#include <filesystem>
#include <mutex>
#include <system_error>

namespace hal {
namespace {

std::string narrow(const wchar_t* w) {
  if (w == nullptr) return {};
  std::string out;
  for (; *w != L'\0'; ++w)
    out.push_back(*w >= 0x20 && *w < 0x7F ? static_cast<char>(*w) : '?');
  return out;
}

std::string hid_error_text(hid_device* dev) {
  const wchar_t* e = hid_error(dev);
  std::string s = narrow(e);
  return s.empty() ? std::string("unknown hidapi error") : s;
}

// hid_init is not thread-safe; every entry point calls it through here once.
bool ensure_init(std::string* error) {
  static std::once_flag once;
  static int rc = -1;
  std::call_once(once, [] { rc = hid_init(); });
  if (rc != 0 && error != nullptr) *error = "hidapi: hid_init failed";
  return rc == 0;
}

class HidapiDevice final : public HidDevice {
 public:
  explicit HidapiDevice(hid_device* dev) : dev_(dev) {}
  ~HidapiDevice() override { hid_close(dev_); }
  HidapiDevice(const HidapiDevice&) = delete;
  HidapiDevice& operator=(const HidapiDevice&) = delete;

  long read(std::span<uint8_t> report) override {
    const int n = hid_read(dev_, report.data(), report.size());
    if (n < 0) error_ = hid_error_text(dev_);
    return n;
  }
  long write(std::span<const uint8_t> report) override {
    const int n = hid_write(dev_, report.data(), report.size());
    if (n < 0) error_ = hid_error_text(dev_);
    return n;
  }
  [[nodiscard]] std::string last_error() const override { return error_; }

 private:
  hid_device* dev_;
  std::string error_;
};

}  // namespace

std::vector<HidDeviceInfo> hid_enumerate(uint16_t vendor_id, std::span<const uint16_t> product_ids,
                                         std::string* error) {
  std::vector<HidDeviceInfo> out;
  if (!ensure_init(error)) return out;
  hid_device_info* list = ::hid_enumerate(vendor_id, 0);
  for (const hid_device_info* d = list; d != nullptr; d = d->next) {
    if (!product_ids.empty() &&
        std::find(product_ids.begin(), product_ids.end(), d->product_id) == product_ids.end()) {
      continue;
    }
    HidDeviceInfo info;
    info.path = d->path != nullptr ? d->path : "";
    info.vendor_id = d->vendor_id;
    info.product_id = d->product_id;
    info.serial_number = narrow(d->serial_number);
    info.manufacturer = narrow(d->manufacturer_string);
    info.product = narrow(d->product_string);
    info.interface_number = d->interface_number;
    out.push_back(std::move(info));
  }
  hid_free_enumeration(list);
  std::sort(out.begin(), out.end(),
            [](const HidDeviceInfo& a, const HidDeviceInfo& b) { return a.path < b.path; });
  return out;
}

HidSelector parse_hid_selector(const std::string& text) {
  if (text.empty() || text == "auto") return {HidSelector::Kind::kAuto, {}};
  if (text.front() == '/') return {HidSelector::Kind::kPath, text};
  constexpr std::string_view kSerial = "serial=";
  if (text.rfind(kSerial, 0) == 0) return {HidSelector::Kind::kSerial, text.substr(kSerial.size())};
  return {HidSelector::Kind::kSerial, text};
}

const HidDeviceInfo* select_hid(const std::vector<HidDeviceInfo>& devices,
                                const HidSelector& selector) {
  for (const HidDeviceInfo& d : devices) {
    switch (selector.kind) {
      case HidSelector::Kind::kAuto:
        return &d;
      case HidSelector::Kind::kPath:
        if (d.path == selector.value) return &d;
        break;
      case HidSelector::Kind::kSerial:
        if (d.serial_number == selector.value) return &d;
        break;
    }
  }
  return nullptr;
}

std::string resolve_device_path(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path p(path);
  for (int hops = 0; hops < 8 && fs::is_symlink(p, ec); ++hops) {
    const fs::path target = fs::read_symlink(p, ec);
    if (ec) break;
    p = target.is_absolute() ? target : (p.parent_path() / target).lexically_normal();
  }
  return p.string();
}

HidOpenResult open_hid(uint16_t vendor_id, std::span<const uint16_t> product_ids,
                       const HidSelector& requested) {
  HidOpenResult r;
  HidSelector selector = requested;
  if (selector.kind == HidSelector::Kind::kPath) {
    selector.value = resolve_device_path(selector.value);
  }
  std::string error;
  const auto devices = hid_enumerate(vendor_id, product_ids, &error);
  if (!error.empty()) {
    r.error = error;
    return r;
  }
  const HidDeviceInfo* pick = select_hid(devices, selector);
  if (pick == nullptr) {
    const std::string what = selector.kind == HidSelector::Kind::kAuto ? "any device"
                             : selector.kind == HidSelector::Kind::kPath
                                 ? selector.value
                                 : "serial " + selector.value;
    char ids[32];
    (void)std::snprintf(ids, sizeof(ids), "%04x", vendor_id);
    r.error = "hid: no device matching " + what + " with vendor id 0x" + ids + " (" +
              std::to_string(devices.size()) + " found; check the USB cable and the udev rule)";
    return r;
  }
  hid_device* dev = hid_open_path(pick->path.c_str());
  if (dev == nullptr) {
    r.error = "hid: cannot open " + pick->path + ": " +
              std::error_code(errno, std::generic_category()).message() +
              " (permissions: the udev rule grants the companion group access)";
    return r;
  }
  if (hid_set_nonblocking(dev, 1) != 0) {
    r.error = "hid: cannot make " + pick->path + " non-blocking: " + hid_error_text(dev);
    hid_close(dev);
    return r;
  }
  r.info = *pick;
  r.device = std::make_unique<HidapiDevice>(dev);
  return r;
}

}  // namespace hal
