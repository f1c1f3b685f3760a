#include "tests/support/fake_robot/robot_messages.hpp"

namespace inspect::test {
namespace {

void addGas(v1::Hello& h, const char* name, const char* gas, const char* unit, const char* sensor, double lo, double hi,
            bool falling, double t90, double max, double background) {
  auto* c = h.add_gas_channels();
  c->set_name(name);
  c->set_gas(gas);
  c->set_unit(unit);
  c->set_sensor(sensor);
  c->set_alarm_low(lo);
  c->set_alarm_high(hi);
  c->set_falling(falling);
  c->set_t90_s(t90);
  c->set_range_min(0);
  c->set_range_max(max);
  c->set_background(background);
}

}  // namespace

v1::Hello fullHello(const std::string& robot_id, const std::string& software_version) {
  v1::Hello h;
  h.set_robot_id(robot_id);
  h.set_protocol_version(net::kProtocolVersion);
  for (const char* c : {"teleop", "track", "navigate", "video", "gas", "ptz", "gains"}) h.add_capabilities(c);
  h.set_software_version(software_version);
  addGas(h, "CH4", "methane", "%LEL", "catalytic", 10, 20, false, 6, 100, 0);
  addGas(h, "H2S", "hydrogen sulfide", "ppm", "electrochemical", 5, 10, false, 8, 100, 0);
  addGas(h, "CO", "carbon monoxide", "ppm", "electrochemical", 35, 100, false, 10, 1000, 0);
  addGas(h, "O2", "oxygen", "%vol", "electrochemical", 19.5, 18.0, true, 8, 30, 20.9);
  h.set_gas_inlet_x_m(0.25);
  h.set_gas_inlet_y_m(0.0);
  auto* g = h.mutable_gains();
  g->set_kp(9.0);
  g->set_ki(2.0);
  g->set_kd(3.0);
  g->set_ke(1.0);
  g->set_kec(0.1);
  g->set_k1(3.0);
  g->set_k2(1.0);
  g->set_k3(1.0);
  g->set_a1(-2.0);
  g->set_a2(-4.0);
  g->set_a3(-2.0);
  h.set_fis_name("fuzzy_pid");
  return h;
}

v1::Hello minimalHello(const std::string& robot_id, uint32_t version) {
  v1::Hello h;
  h.set_robot_id(robot_id);
  h.set_protocol_version(version);
  h.add_capabilities("teleop");
  h.set_software_version("test");
  return h;
}

v1::Ack acceptedAck(const v1::Command& command) {
  v1::Ack a;
  a.set_command_id(command.id());
  a.set_status(v1::Ack::ACCEPTED);
  return a;
}

}  // namespace inspect::test
