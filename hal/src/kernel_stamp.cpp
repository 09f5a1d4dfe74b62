#include "hal/kernel_stamp.hpp"

#include <ctime>

namespace hal {

Nanos monotonic_from_kernel_stamp(Nanos kernel_realtime, Nanos received_now) {
  timespec rt{};
  clock_gettime(CLOCK_REALTIME, &rt);
  const Nanos real_now(static_cast<int64_t>(rt.tv_sec) * 1'000'000'000 + rt.tv_nsec);
  const Nanos age = real_now - kernel_realtime;
  if (age >= Nanos(0) && age < std::chrono::seconds(1)) return received_now - age;
  return received_now;
}

}  // namespace hal
