#include "hal/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <system_error>

namespace hal {
namespace {

RtResult failure(const char* what, int err) {
  RtResult r;
  r.error_number = err;
  r.message = std::string(what) + ": " + std::system_category().message(err);
  if (err == EPERM) {
    r.message +=
        " (needs CAP_SYS_NICE / CAP_IPC_LOCK or an rtprio/memlock limit; "
        "the systemd unit grants them)";
  }
  return r;
}

}  // namespace

RtResult lock_process_memory() {
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) return failure("mlockall", errno);
  return RtResult{true, 0, "memory locked"};
}

RtResult set_current_thread_fifo(int priority) {
  if (priority < 1 || priority > 49) {
    return RtResult{false, EINVAL, "SCHED_FIFO priority must be in 1..49"};
  }
  sched_param param{};
  param.sched_priority = priority;
  const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  if (rc != 0) return failure("pthread_setschedparam(SCHED_FIFO)", rc);
  return RtResult{true, 0, "SCHED_FIFO " + std::to_string(priority)};
}

void set_current_thread_name(const std::string& name) {
  pthread_setname_np(pthread_self(), name.substr(0, 15).c_str());
}

}  // namespace hal
