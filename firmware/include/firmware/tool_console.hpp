#pragma once
// Console output of the small command-line tools (stdout for results, stderr for errors), with
// printf-checked formats, and Ctrl-C as a flag the tools' loops poll.
#include <atomic>
#include <csignal>
#include <cstdarg>
#include <cstdio>
#include <exception>

namespace firmware::tool {

__attribute__((format(printf, 1, 2))) inline void say(const char* format, ...) {
  va_list args;
  va_start(args, format);
  (void)std::vprintf(format, args);
  va_end(args);
}
__attribute__((format(printf, 1, 2))) inline void complain(const char* format, ...) {
  va_list args;
  va_start(args, format);
  (void)std::vfprintf(stderr, format, args);
  va_end(args);
}

inline std::atomic<bool>& interrupted() {
  static std::atomic<bool> flag{false};
  return flag;
}
inline void on_signal(int /*sig*/) {
  interrupted().store(true);
}
inline void catch_interrupts() {
  (void)std::signal(SIGINT, on_signal);
  (void)std::signal(SIGTERM, on_signal);
}

// A tool's main: runs `run`, and turns an escaping exception into a message and exit code 3.
inline int main_guarded(const char* tool, int (*run)(int, char**), int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    complain("%s: %s\n", tool, e.what());
    return 3;
  }
}

}  // namespace firmware::tool
