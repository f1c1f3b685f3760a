#pragma once
// Commands for the decision core's tests, as pc_server would send them.
#include <cstdint>

#include "inspect_robot/v1/link.pb.h"

namespace inspect::test {

inline v1::Command teleop(uint64_t id, double v, double w) {
  v1::Command c;
  c.set_id(id);
  c.mutable_teleop()->set_v_m_s(v);
  c.mutable_teleop()->set_w_rad_s(w);
  return c;
}

}  // namespace inspect::test
