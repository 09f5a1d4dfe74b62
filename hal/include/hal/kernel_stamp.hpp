#pragma once
// Kernel receive timestamps (SO_TIMESTAMP / SO_TIMESTAMPNS) are CLOCK_REALTIME; the daemon's
// time is CLOCK_MONOTONIC. Shifts a kernel stamp by its age, measured on the realtime clock now.
#include "hal/clock.hpp"

namespace hal {

// `received_now` is the monotonic time the read stands for (the caller's `now`); the result is
// earlier by the datagram's age at that time, and never later than it. Ages outside [0, 1 s)
// (the wall clock jumped) are ignored.
Nanos monotonic_from_kernel_stamp(Nanos kernel_realtime, Nanos received_now);

}  // namespace hal
