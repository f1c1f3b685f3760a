#include "shared/util/realtime.hpp"

#include <sched.h>

#include <cerrno>
#include <cstring>

namespace inspect::util {

std::string enterRealtime(int priority) {
  if (priority <= 0) return "";
  if (priority > 99) return "real-time priority " + std::to_string(priority) + " is above 99";
  sched_param sp{};
  sp.sched_priority = priority;
  // pid 0 is the calling thread only (Linux schedules threads, not processes).
  if (::sched_setscheduler(0, SCHED_FIFO | SCHED_RESET_ON_FORK, &sp) != 0) {
    const int e = errno;
    return "SCHED_FIFO priority " + std::to_string(priority) + ": " + std::strerror(e) +
           (e == EPERM ? " (needs root, CAP_SYS_NICE or LimitRTPRIO>=" + std::to_string(priority) + ")" : "");
  }
  return "";
}

}  // namespace inspect::util
