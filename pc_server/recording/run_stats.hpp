#pragma once
// Summary figures of a recorded run, accumulated from its telemetry (pure:
// no I/O, no clock; tested on messages).
#include <cstdint>
#include <string>
#include <vector>

#include "inspect_robot/v1/link.pb.h"

namespace inspect::server {

/// Odometry steps longer than this between two telemetry messages are a reset
/// or a reconnect, not motion (the robot's top speed is ~1 m/s, telemetry 50 Hz).
inline constexpr double kMaxOdometryStepM = 0.5;

struct GasFigures {
  int channel = 0;
  double max = 0;
  double mean = 0;
  uint64_t samples = 0;
};

struct RunFigures {
  double duration_s = 0;          // first to last telemetry (robot clock)
  double distance_m = 0;          // path length from the odometry pose
  double min_person_m = -1;       // nearest tracked person; < 0 = nobody seen
  double max_position_error_m = 0;  // tracking (Eq 10), over TRACKING telemetry
  double rms_position_error_m = 0;
  double max_angle_error_rad = 0;
  uint64_t telemetry = 0;         // messages
  uint64_t tracking_samples = 0;
  std::vector<GasFigures> gas;    // per channel
};

class RunStats {
 public:
  void add(const v1::Telemetry& t);
  RunFigures figures() const;

 private:
  RunFigures f_;
  bool have_pose_ = false;
  double last_x_ = 0, last_y_ = 0;
  uint64_t first_us_ = 0, last_us_ = 0;
  double sq_sum_ = 0;
  std::vector<double> gas_sum_;
};

}  // namespace inspect::server
