// HID selection logic (pure) and hidapi enumeration/open on this machine (which has no
// Amfitrack plugged in: the error must say what was looked for).
#include <gtest/gtest.h>

#include <filesystem>

#include "hal/hid/hid_device.hpp"

namespace {

std::vector<hal::HidDeviceInfo> two_devices() {
  hal::HidDeviceInfo a;
  a.path = "/dev/hidraw1";
  a.serial_number = "0042";
  a.product_id = 0x0D01;
  hal::HidDeviceInfo b;
  b.path = "/dev/hidraw4";
  b.serial_number = "0077";
  b.product_id = 0x0D12;
  return {a, b};
}

TEST(HidSelector, ParsesAutoPathAndSerial) {
  EXPECT_EQ(hal::parse_hid_selector("auto").kind, hal::HidSelector::Kind::kAuto);
  EXPECT_EQ(hal::parse_hid_selector("").kind, hal::HidSelector::Kind::kAuto);
  const auto p = hal::parse_hid_selector("/dev/hidraw4");
  EXPECT_EQ(p.kind, hal::HidSelector::Kind::kPath);
  EXPECT_EQ(p.value, "/dev/hidraw4");
  const auto s = hal::parse_hid_selector("serial=0077");
  EXPECT_EQ(s.kind, hal::HidSelector::Kind::kSerial);
  EXPECT_EQ(s.value, "0077");
  EXPECT_EQ(hal::parse_hid_selector("0077").value, "0077");
}

TEST(HidSelector, PicksTheRequestedDeviceOnly) {
  const auto devs = two_devices();
  EXPECT_EQ(hal::select_hid(devs, hal::parse_hid_selector("auto")), &devs[0]);
  EXPECT_EQ(hal::select_hid(devs, hal::parse_hid_selector("/dev/hidraw4")), &devs[1]);
  EXPECT_EQ(hal::select_hid(devs, hal::parse_hid_selector("serial=0042")), &devs[0]);
  // A hidraw node that is not an Amfitrack device is never opened.
  EXPECT_EQ(hal::select_hid(devs, hal::parse_hid_selector("/dev/hidraw0")), nullptr);
  EXPECT_EQ(hal::select_hid(devs, hal::parse_hid_selector("serial=9999")), nullptr);
  EXPECT_EQ(hal::select_hid({}, hal::parse_hid_selector("auto")), nullptr);
}

TEST(HidEnumerate, ListsOnlyTheRequestedProducts) {
  const std::array<uint16_t, 2> pids = {0x0D01, 0x0D12};
  std::string error;
  for (const auto& d : hal::hid_enumerate(0x0C17, pids, &error)) {
    EXPECT_EQ(d.vendor_id, 0x0C17);
    EXPECT_TRUE(d.product_id == 0x0D01 || d.product_id == 0x0D12);
  }
}

TEST(HidOpen, MissingDeviceIsAClearError) {
  const std::array<uint16_t, 1> pids = {0x0D12};
  const auto r = hal::open_hid(0xFFFE, pids, hal::parse_hid_selector("serial=NOPE"));
  ASSERT_EQ(r.device, nullptr);
  EXPECT_NE(r.error.find("serial NOPE"), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("0xfffe"), std::string::npos) << r.error;
}

}  // namespace

namespace {
TEST(HidSelector, UdevSymlinksResolveToTheHidrawNode) {
  const std::string dir = ::testing::TempDir() + "hid_links";
  std::filesystem::create_directories(dir);
  const std::string link = dir + "/amfitrack-sensor";
  std::filesystem::remove(link);
  std::filesystem::create_symlink("/dev/hidraw4", link);
  EXPECT_EQ(hal::resolve_device_path(link), "/dev/hidraw4");
  const std::string relative = dir + "/rel";
  std::filesystem::remove(relative);
  std::filesystem::create_symlink("amfitrack-sensor", relative);  // a link to the link
  EXPECT_EQ(hal::resolve_device_path(relative), "/dev/hidraw4");
  EXPECT_EQ(hal::resolve_device_path("/dev/hidraw7"), "/dev/hidraw7");
}
}  // namespace
