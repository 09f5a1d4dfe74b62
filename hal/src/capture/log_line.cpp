#include "hal/capture/log_line.hpp"

#include <cstdio>

namespace hal {
namespace {

bool parse_dec(std::string_view s, int64_t& out) {
  if (s.empty() || s.size() > 18) return false;
  out = 0;
  for (const char c : s) {
    if (c < '0' || c > '9') return false;
    out = out * 10 + (c - '0');
  }
  return true;
}

LogLineParse fail(std::string& error, const char* why) {
  error = why;
  return LogLineParse::kMalformed;
}

}  // namespace

LogLineParse split_log_line(std::string_view line, LogLine& out, std::string& error) {
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r'))
    line.remove_suffix(1);
  if (line.empty() || line.front() != '(') return LogLineParse::kIgnored;

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
  out.iface = rest.substr(0, sp);
  std::string_view payload = rest.substr(sp + 1);
  if (const size_t end = payload.find(' '); end != std::string_view::npos) {
    payload = payload.substr(0, end);
  }
  out.payload = payload;
  return LogLineParse::kRecord;
}

std::string log_line_prefix(int64_t sec, int64_t nsec, std::string_view iface, bool nine_digits) {
  char stamp[48];
  if (nine_digits) {
    (void)std::snprintf(stamp, sizeof(stamp), "(%lld.%09lld) ", static_cast<long long>(sec),
                        static_cast<long long>(nsec));
  } else {
    (void)std::snprintf(stamp, sizeof(stamp), "(%lld.%06lld) ", static_cast<long long>(sec),
                        static_cast<long long>(nsec / 1000));
  }
  std::string out(stamp);
  out.append(iface);
  out += ' ';
  return out;
}

}  // namespace hal
