#pragma once
// The calling thread's CPU time (CLOCK_THREAD_CPUTIME_ID), in milliseconds:
// what a benchmark or a worker thread reports as its CPU per picture.
#include <time.h>

namespace inspect::util {

inline double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) / 1e6;
}

}  // namespace inspect::util
