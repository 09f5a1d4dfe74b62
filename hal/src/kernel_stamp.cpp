#include "hal/kernel_stamp.hpp"

#include <ctime>

namespace hal {
namespace {
Nanos read(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return Nanos(static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec);
}
}  // namespace

Nanos monotonic_from_kernel_stamp(Nanos kernel_realtime, Nanos received_now) {
  // The age is measured now, which can be well after `received_now` (the caller's time, taken
  // before it drained a queue or was preempted): the monotonic clock read beside the realtime
  // one says how much later, and that much is not age. (Without it a loaded machine stamped
  // datagrams milliseconds before they were sent.)
  const Nanos mono_now = read(CLOCK_MONOTONIC);
  const Nanos real_now = read(CLOCK_REALTIME);
  Nanos age = real_now - kernel_realtime;
  if (age < Nanos(0) || age >= std::chrono::seconds(1)) return received_now;  // wall clock jumped
  const Nanos since_received = mono_now - received_now;
  // On a simulated clock `received_now` is not monotonic time: no correction (kDrain is the
  // stamp for that).
  if (since_received >= Nanos(0) && since_received < std::chrono::seconds(1)) {
    age -= since_received;
  }
  // Arrived after `received_now`: it is stamped then (the time this read stands for).
  return age > Nanos(0) ? received_now - age : received_now;
}

}  // namespace hal
