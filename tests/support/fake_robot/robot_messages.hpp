#pragma once
// What the fake robot says (tests/support/fake_robot): the one home of the
// test robots' Hello and Ack, for the scripted robot (one test drives it step
// by step) and the fleet robot (many at once, the load generator).
#include <string>

#include "inspect_robot/v1/link.pb.h"
#include "shared/net/link_version.hpp"

namespace inspect::test {

/// The Hello robot_client sends: every capability, the four gas channels and
/// the gains of config/robot.yaml and config/control.yaml, the inlet position.
v1::Hello fullHello(const std::string& robot_id, const std::string& software_version);

/// The least a robot written from proto/ alone sends: id, version, teleop.
v1::Hello minimalHello(const std::string& robot_id, uint32_t version = net::kProtocolVersion);

/// ACCEPTED for `command`.
v1::Ack acceptedAck(const v1::Command& command);

}  // namespace inspect::test
