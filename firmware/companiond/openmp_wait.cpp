#include "openmp_wait.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

namespace companiond {

namespace {
constexpr const char* kVariable = "OMP_WAIT_POLICY";
constexpr const char* kMarker = "COMPANIOND_OMP_WAIT_SET";  // set by the re-exec, then removed
}  // namespace

// The environment functions are not thread-safe: this runs before any thread exists (header).
// NOLINTBEGIN(concurrency-mt-unsafe)
OpenmpWaitPolicy choose_openmp_wait_policy(char** argv) {
  const char* chosen = std::getenv(kVariable);
  if (chosen != nullptr) {
    const bool ours = std::getenv(kMarker) != nullptr;
    unsetenv(kMarker);  // children (none today) see a plain environment
    return {chosen,
            ours ? "companiond's default; OMP_WAIT_POLICY overrides" : "from OMP_WAIT_POLICY"};
  }
  if (setenv(kVariable, "passive", 1) == 0 && setenv(kMarker, "1", 1) == 0) {
    execv("/proc/self/exe", argv);
  }
  const int error = errno;
  unsetenv(kVariable);  // libgomp of this process keeps its default: say so, do not pretend
  unsetenv(kMarker);
  return {"", std::string("re-exec to set it failed: ") + std::strerror(error)};
}
// NOLINTEND(concurrency-mt-unsafe)

}  // namespace companiond
