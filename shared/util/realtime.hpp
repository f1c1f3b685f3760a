#pragma once
// Real-time scheduling of one thread: a control loop (robot_client) or a
// stand-in for separate hardware (mcu_sim) is made SCHED_FIFO once it has
// finished starting up, so that its start-up work (loading libraries,
// building lookup tables) never holds a core at real-time priority.
#include <string>

namespace inspect::util {

/// Makes the calling thread SCHED_FIFO at `priority` (1-99) with
/// SCHED_RESET_ON_FORK, so that threads and processes it starts afterwards
/// are ordinary ones. Returns "" on success, else why not (e.g. not
/// permitted: needs root, CAP_SYS_NICE or an RLIMIT_RTPRIO of at least
/// `priority`, which systemd's LimitRTPRIO= gives). priority 0: nothing.
std::string enterRealtime(int priority);

}  // namespace inspect::util
