#include "hal/can/slcan_codec.hpp"

#include <array>
#include <cstdio>

#include "hal/can/hex.hpp"

namespace hal::slcan {
namespace {

constexpr size_t kMaxLine = 1 + 8 + 1 + 16 + 4;  // 'T' + id + dlc + data + optional timestamp
constexpr size_t kMaxFramesQueued = 1024;

std::optional<uint32_t> parse_hex(std::string_view s) {
  uint32_t v = 0;
  for (const char c : s) {
    const int h = hex::digit_value(c);
    if (h < 0) return std::nullopt;
    v = v * 16 + static_cast<uint32_t>(h);
  }
  return v;
}

std::optional<CanFrame> parse_frame(std::string_view l) {
  const char kind = l[0];
  const bool extended = kind == 'T' || kind == 'R';
  const bool remote = kind == 'r' || kind == 'R';
  const size_t id_len = extended ? 8 : 3;
  if (l.size() < 1 + id_len + 1) return std::nullopt;
  const auto id = parse_hex(l.substr(1, id_len));
  const int dlc = hex::digit_value(l[1 + id_len]);
  if (!id || dlc < 0 || dlc > 8) return std::nullopt;
  if (extended ? *id > 0x1FFFFFFF : *id > 0x7FF) return std::nullopt;
  const size_t data_len = remote ? 0 : static_cast<size_t>(dlc) * 2;
  const size_t base = 1 + id_len + 1 + data_len;
  // An optional 4-digit millisecond timestamp (Z1) may follow; nothing else may.
  if (l.size() != base && l.size() != base + 4) return std::nullopt;
  CanFrame f;
  f.id = *id;
  f.extended = extended;
  f.remote = remote;
  f.dlc = static_cast<uint8_t>(dlc);
  for (size_t i = 0; i < data_len / 2; ++i) {
    const auto byte = parse_hex(l.substr(1 + id_len + 1 + 2 * i, 2));
    if (!byte) return std::nullopt;
    f.data[i] = static_cast<uint8_t>(*byte);
  }
  if (l.size() == base + 4 && !parse_hex(l.substr(base, 4))) return std::nullopt;
  return f;
}

}  // namespace

std::optional<std::string> bitrate_command(int kbps) {
  static constexpr std::array<int, 9> kRates{10, 20, 50, 100, 125, 250, 500, 800, 1000};
  for (size_t i = 0; i < kRates.size(); ++i) {
    if (kRates[i] == kbps) return "S" + std::to_string(i);
  }
  return std::nullopt;
}

std::optional<std::string> encode(const CanFrame& f) {
  if (f.error || f.dlc > 8) return std::nullopt;
  if (f.extended ? f.id > 0x1FFFFFFF : f.id > 0x7FF) return std::nullopt;
  char buf[40];
  int n = 0;
  const char kind = f.remote ? (f.extended ? 'R' : 'r') : (f.extended ? 'T' : 't');
  if (f.extended) {
    n = std::snprintf(buf, sizeof(buf), "%c%08X%u", kind, f.id, f.dlc);
  } else {
    n = std::snprintf(buf, sizeof(buf), "%c%03X%u", kind, f.id, f.dlc);
  }
  std::string s(buf, static_cast<size_t>(n));
  if (!f.remote) hex::append_bytes(s, f.data.data(), f.dlc);
  s += '\r';
  return s;
}

void Parser::line(std::string_view l) {
  if (l.empty()) {
    ++stats_.acks;
    return;
  }
  switch (l[0]) {
    case 't':
    case 'T':
    case 'r':
    case 'R':
      if (auto f = parse_frame(l)) {
        if (frames_.size() >= kMaxFramesQueued) frames_.pop_front();
        frames_.push_back(*f);
        ++stats_.frames;
      } else {
        ++stats_.malformed;
      }
      return;
    case 'z':
    case 'Z':  // transmit acknowledged
    case 'F':  // status flags reply
    case 'V':  // version reply
    case 'N':  // serial number reply
      ++stats_.acks;
      return;
    default:
      ++stats_.malformed;
      return;
  }
}

void Parser::feed(std::string_view bytes) {
  for (const char c : bytes) {
    if (c == '\r' || c == '\n') {
      if (discarding_) {
        discarding_ = false;  // resynchronised at the end of the garbage
      } else if (c == '\r' || !pending_.empty()) {
        line(pending_);
      }
      pending_.clear();
    } else if (c == '\a') {
      ++stats_.nacks;
      pending_.clear();
    } else if (!discarding_) {
      pending_.push_back(c);
      if (pending_.size() > kMaxLine) {
        ++stats_.overlong;
        pending_.clear();
        discarding_ = true;
      }
    }
  }
}

std::optional<CanFrame> Parser::next_frame() {
  if (frames_.empty()) return std::nullopt;
  CanFrame f = frames_.front();
  frames_.pop_front();
  return f;
}

}  // namespace hal::slcan
