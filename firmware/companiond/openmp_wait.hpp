#pragma once
// The OpenMP wait policy of the MPPI rollouts' worker threads. libgomp's default spins between
// parallel regions; the workers inherit the control group's SCHED_FIFO priority, so with one
// region per 10 ms step a worker spins at real-time priority most of the period, the kernel's
// real-time throttling (sched_rt_runtime_us, 950 of every 1000 ms) then freezes every SCHED_FIFO
// thread for up to 50 ms, and the supervisor holds (docs/PERFORMANCE.md, 2026-12-06). Passive
// puts a worker to sleep at once; one futex wake per step is the cost.
#include <string>

namespace companiond {

struct OpenmpWaitPolicy {
  std::string value;   // OMP_WAIT_POLICY as libgomp read it; empty: libgomp's default (spin)
  std::string source;  // why: companiond's default, the environment's, or the exec failure
};

// libgomp reads OMP_WAIT_POLICY once, when it is loaded, before main(): to choose passive the
// process has to start again with the variable set. When the environment does not set it, this
// sets it and re-executes /proc/self/exe with the same arguments (same PID, so systemd and a
// parent's waitpid() are unaffected); it returns only when the environment chose already or the
// exec failed. Call it first thing in main(), before any thread exists.
OpenmpWaitPolicy choose_openmp_wait_policy(char** argv);

}  // namespace companiond
