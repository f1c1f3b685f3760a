#include "shared/config/control_config.hpp"

#include <sys/stat.h>

#include "shared/fuzzy/fis_error.hpp"
#include "shared/fuzzy/fis_reader.hpp"

namespace inspect::config {
namespace {
bool exists(const std::string& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0;
}
std::string dirOf(const std::string& p) {
  const auto slash = p.rfind('/');
  return slash == std::string::npos ? "." : p.substr(0, slash);
}
}  // namespace

ControlConfig loadControlConfig(const ConfigNode& root, const std::string& base_dir) {
  ControlConfig c;
  auto& t = c.tracker;
  const auto a = root.optChild("auxiliary");
  t.aux.a1 = a.number("a1", t.aux.a1, -20, 0);
  t.aux.a2 = a.number("a2", t.aux.a2, -20, 0);
  t.aux.a3 = a.number("a3", t.aux.a3, -20, 0);
  const auto w = root.optChild("wheel");
  const std::string kind = w.oneOf("controller", "fuzzy_pid", {"fuzzy_pid", "pid", "direct"});
  t.wheel_control = kind == "pid" ? control::WheelControl::kPid
                    : kind == "direct" ? control::WheelControl::kDirect
                                       : control::WheelControl::kFuzzyPid;
  t.feedforward = w.boolean("feedforward", t.feedforward);
  t.fuzzy.base.kp = w.number("kp", t.fuzzy.base.kp, 0, 100);
  t.fuzzy.base.ki = w.number("ki", t.fuzzy.base.ki, 0, 100);
  t.fuzzy.base.kd = w.number("kd", t.fuzzy.base.kd, 0, 100);
  t.pid.derivative_filter_s = w.number("derivative_filter_s", 0.2, 0.001, 5);
  t.pid.integral_limit = w.number("integral_limit_rad_s", 2.0, 0, 50);
  const auto f = root.optChild("fuzzy_pid");
  c.fis_path = f.string("fis", c.fis_path);
  if (!c.fis_path.empty() && c.fis_path[0] != '/' && !exists(c.fis_path)) {
    // Relative to the project root when the config sits in <root>/config/.
    const std::string alt = base_dir + "/../" + c.fis_path;
    if (exists(alt)) c.fis_path = alt;
  }
  c.use_lookup = f.boolean("lookup", c.use_lookup);
  t.fuzzy.ke = f.number("ke", t.fuzzy.ke, 0, 100);
  t.fuzzy.kec = f.number("kec", t.fuzzy.kec, 0, 100);
  t.fuzzy.k1 = f.number("k1", t.fuzzy.k1, 0, 100);
  t.fuzzy.k2 = f.number("k2", t.fuzzy.k2, 0, 100);
  t.fuzzy.k3 = f.number("k3", t.fuzzy.k3, 0, 100);
  return c;
}

ControlConfig loadControlConfigFile(const std::string& path) {
  const auto root = ConfigNode::loadFile(path);
  ControlConfig c = loadControlConfig(root, dirOf(path));
  root.checkKnown();
  return c;
}

void applyRobot(ControlConfig& c, const RobotConfig& robot) {
  c.tracker.wheel_radius_m = robot.geometry.wheel_radius_m;
  c.tracker.track_m = robot.geometry.track_m;
  c.tracker.max_wheel_speed_rad_s = robot.limits.max_wheel_speed_rad_s;
}

TrackingSetup loadTrackingSetup(const std::string& robot_path, const std::string& control_path) {
  TrackingSetup s;
  s.robot = loadRobotConfigFile(robot_path);
  s.control = loadControlConfigFile(control_path);
  applyRobot(s.control, s.robot);
  s.fis = fuzzy::readFisFile(s.control.fis_path);
  return s;
}

std::shared_ptr<control::FuzzyGainScheduler> loadScheduler(const ControlConfig& c) {
  try {
    return std::make_shared<control::FuzzyGainScheduler>(fuzzy::readFisFile(c.fis_path), c.use_lookup);
  } catch (const fuzzy::FisError& e) {
    throw ConfigError(std::string("fuzzy_pid.fis: ") + e.what());
  }
}

}  // namespace inspect::config
