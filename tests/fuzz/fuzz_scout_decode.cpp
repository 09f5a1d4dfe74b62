// libFuzzer: CAN frames as they could arrive from a faulty base or another node on the bus.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "scout_mini/scout_codec.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 3) return 0;
  hal::CanFrame f;
  f.id = (static_cast<uint32_t>(data[0]) << 8 | data[1]) & 0x7FF;
  f.extended = (data[2] & 0x80) != 0;
  f.remote = (data[2] & 0x40) != 0;
  f.error = (data[2] & 0x20) != 0;
  f.dlc = static_cast<uint8_t>(data[2] & 0x0F);  // 0..15: over-long DLCs must be refused
  std::memcpy(f.data.data(), data + 3, std::min<size_t>(size - 3, 8));
  const auto d = scout_mini::decode(f);
  if (d.message) {
    if (f.dlc != 8 || f.extended || f.remote || f.error) __builtin_trap();
    if (const auto* m = std::get_if<scout_mini::MotionState>(&*d.message)) {
      if (!std::isfinite(m->vx_mps) || std::abs(m->vx_mps) > 32.768) __builtin_trap();
    }
    if (const auto* hs = std::get_if<scout_mini::MotorHighSpeed>(&*d.message)) {
      if (hs->motor < 1 || hs->motor > 4) __builtin_trap();
    }
  }
  const auto cmd = scout_mini::decode_motion_command(f);
  if (cmd && f.dlc != 8) __builtin_trap();
  return 0;
}
