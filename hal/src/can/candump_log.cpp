#include "hal/can/candump_log.hpp"

#include <cctype>
#include <cstdio>

#include "hal/can/hex.hpp"
#include "hal/capture/log_line.hpp"

namespace hal {
namespace {

bool parse_hex(std::string_view s, uint64_t& out) {
  if (s.empty() || s.size() > 16) return false;
  out = 0;
  for (const char c : s) {
    const int v = hex::digit_value(c);
    if (v < 0) return false;
    out = out * 16 + static_cast<uint64_t>(v);
  }
  return true;
}

CandumpParse fail(std::string& error, const char* why) {
  error = why;
  return CandumpParse::kMalformed;
}

}  // namespace

CandumpParse parse_candump_line(std::string_view line, CandumpRecord& out, std::string& error) {
  LogLine ll;
  switch (split_log_line(line, ll, error)) {
    case LogLineParse::kIgnored:
      return CandumpParse::kIgnored;
    case LogLineParse::kMalformed:
      return CandumpParse::kMalformed;
    case LogLineParse::kRecord:
      break;
  }
  out.sec = ll.sec;
  out.nsec = ll.nsec;
  out.iface = std::string(ll.iface);
  const std::string_view frame = ll.payload;

  const size_t hash = frame.find('#');
  if (hash == std::string_view::npos) return fail(error, "no '#' in the frame");
  if (frame.substr(hash).rfind("##", 0) == 0) return fail(error, "CAN FD frames are not supported");
  const std::string_view id_text = frame.substr(0, hash);
  std::string_view data = frame.substr(hash + 1);
  uint64_t id = 0;
  if (!parse_hex(id_text, id)) return fail(error, "bad identifier");
  CanFrame cf;
  if (id_text.size() == 3) {
    if (id > 0x7FF) return fail(error, "standard identifier above 0x7FF");
    cf.id = static_cast<uint32_t>(id);
  } else if (id_text.size() == 8) {
    if (id & 0x20000000U) {
      cf.error = true;
      cf.id = static_cast<uint32_t>(id & 0x1FFFFFFFU);
    } else {
      if (id > 0x1FFFFFFF) return fail(error, "extended identifier above 29 bits");
      cf.extended = true;
      cf.id = static_cast<uint32_t>(id);
    }
  } else {
    return fail(error, "identifier must have 3 or 8 hex digits");
  }

  if (!data.empty() && (data.front() == 'R' || data.front() == 'r')) {
    cf.remote = true;
    if (data.size() == 2 && data[1] >= '0' && data[1] <= '8') {
      cf.dlc = static_cast<uint8_t>(data[1] - '0');
    } else if (data.size() != 1) {
      return fail(error, "bad remote frame length");
    }
  } else {
    std::string compact;  // cansend allows '.' separators
    for (const char c : data) {
      if (c != '.') compact.push_back(c);
    }
    if (compact.size() % 2 != 0) return fail(error, "odd number of data hex digits");
    if (compact.size() > 16) return fail(error, "more than 8 data bytes");
    cf.dlc = static_cast<uint8_t>(compact.size() / 2);
    for (size_t i = 0; i < cf.dlc; ++i) {
      const int hi = hex::digit_value(compact[2 * i]);
      const int lo = hex::digit_value(compact[2 * i + 1]);
      if (hi < 0 || lo < 0) return fail(error, "bad data hex digit");
      cf.data[i] = static_cast<uint8_t>(hi * 16 + lo);
    }
  }
  out.frame = cf;
  return CandumpParse::kRecord;
}

std::string format_candump_line(const CandumpRecord& rec, bool nine_digits) {
  return log_line_prefix(rec.sec, rec.nsec, rec.iface, nine_digits) + to_cansend(rec.frame);
}

}  // namespace hal
