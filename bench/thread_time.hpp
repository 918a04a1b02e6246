// The calling thread's CPU time, for the benchmarks' one-thread timings on shared machines.
#pragma once

#include <ctime>

namespace limber {

/// The calling thread's CPU time, s (CLOCK_THREAD_CPUTIME_ID): a stretch in which the machine
/// preempts the thread does not count, so timings on a busy 2-core machine stay comparable.
inline double thread_seconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

}  // namespace limber
