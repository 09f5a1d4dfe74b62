#pragma once
// slcan (Lawicel ASCII) protocol, pure: frame <-> text, and a byte-stream parser that
// resynchronises after garbage. No I/O.
//   t1118009600000000000\r   standard data frame (id 0x111, 8 bytes)
//   T12345678 2 AABB\r      extended (without the spaces), r/R remote
//   \r = OK, \a (0x07) = error; z/Z = transmit acknowledged (some firmware)
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <string_view>

#include "hal/can/can_frame.hpp"

namespace hal::slcan {

// Bit-rate command for kbit/s (10, 20, 50, 100, 125, 250, 500, 800, 1000) -> "S0".."S8".
std::optional<std::string> bitrate_command(int kbps);

// The command for one frame, including the terminating '\r'. Error frames cannot be sent.
std::optional<std::string> encode(const CanFrame& frame);

struct ParserStats {
  uint64_t frames = 0;
  uint64_t acks = 0;
  uint64_t nacks = 0;      // \a: the adapter refused a command
  uint64_t malformed = 0;  // lines that were not a valid frame or reply
  uint64_t overlong = 0;   // garbage lines longer than any slcan message (resynchronised)
};

class Parser {
 public:
  // Feeds bytes; complete frames are returned one by one by next_frame().
  void feed(std::string_view bytes);
  std::optional<CanFrame> next_frame();
  [[nodiscard]] const ParserStats& stats() const { return stats_; }

 private:
  void line(std::string_view l);

  std::string pending_;
  std::deque<CanFrame> frames_;
  bool discarding_ = false;
  ParserStats stats_;
};

}  // namespace hal::slcan
