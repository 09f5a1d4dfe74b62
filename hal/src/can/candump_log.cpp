#include "hal/can/candump_log.hpp"

#include <cctype>
#include <cstdio>

#include "hal/can/hex.hpp"

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

bool parse_dec(std::string_view s, int64_t& out) {
  if (s.empty() || s.size() > 18) return false;
  out = 0;
  for (const char c : s) {
    if (c < '0' || c > '9') return false;
    out = out * 10 + (c - '0');
  }
  return true;
}

CandumpParse fail(std::string& error, const char* why) {
  error = why;
  return CandumpParse::kMalformed;
}

}  // namespace

CandumpParse parse_candump_line(std::string_view line, CandumpRecord& out, std::string& error) {
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r'))
    line.remove_suffix(1);
  if (line.empty() || line.front() != '(') return CandumpParse::kIgnored;

  const size_t close = line.find(')');
  if (close == std::string_view::npos) return fail(error, "no ')' after the timestamp");
  const std::string_view stamp = line.substr(1, close - 1);
  const size_t dot = stamp.find('.');
  if (dot == std::string_view::npos) return fail(error, "timestamp without fraction");
  const std::string_view frac = stamp.substr(dot + 1);
  if (frac.size() != 6 && frac.size() != 9) return fail(error, "timestamp needs 6 or 9 digits");
  int64_t sec = 0;
  int64_t f = 0;
  if (!parse_dec(stamp.substr(0, dot), sec) || !parse_dec(frac, f)) {
    return fail(error, "bad timestamp digits");
  }
  out.sec = sec;
  out.nsec = frac.size() == 6 ? f * 1000 : f;

  std::string_view rest = line.substr(close + 1);
  if (rest.empty() || rest.front() != ' ') return fail(error, "no space after the timestamp");
  rest.remove_prefix(1);
  const size_t sp = rest.find(' ');
  if (sp == std::string_view::npos || sp == 0) return fail(error, "no interface name");
  out.iface = std::string(rest.substr(0, sp));
  std::string_view frame = rest.substr(sp + 1);
  // Trailing annotations (e.g. " T" / " R" direction flags of newer candump) are ignored.
  if (const size_t end = frame.find(' '); end != std::string_view::npos)
    frame = frame.substr(0, end);

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
  char stamp[48];
  if (nine_digits) {
    (void)std::snprintf(stamp, sizeof(stamp), "(%lld.%09lld) ", static_cast<long long>(rec.sec),
                        static_cast<long long>(rec.nsec));
  } else {
    (void)std::snprintf(stamp, sizeof(stamp), "(%lld.%06lld) ", static_cast<long long>(rec.sec),
                        static_cast<long long>(rec.nsec / 1000));
  }
  return std::string(stamp) + rec.iface + " " + to_cansend(rec.frame);
}

CandumpReader::CandumpReader(const std::string& path) : in_(path) {}

std::optional<CandumpRecord> CandumpReader::next() {
  std::string line;
  while (std::getline(in_, line)) {
    ++line_;
    CandumpRecord rec;
    std::string error;
    switch (parse_candump_line(line, rec, error)) {
      case CandumpParse::kRecord:
        return rec;
      case CandumpParse::kIgnored:
        break;
      case CandumpParse::kMalformed:
        ++malformed_;
        last_error_ = "line " + std::to_string(line_) + ": " + error;
        break;
    }
  }
  return std::nullopt;
}

CandumpWriter::CandumpWriter(const std::string& path) : out_(path) {}

void CandumpWriter::write(const CandumpRecord& rec) {
  out_ << format_candump_line(rec) << '\n';
}

}  // namespace hal
