// Fuzzes the YAML configuration loaders: shared/config (ConfigNode, the
// robot with its gas channels, control), robot_client's client config and
// behaviour (awareness) config, pc_server's server config and route files,
// and world files (sim/world, and the robot's map made from one). Each gets
// the same text, as if it had been given that file.
//
// Input: the YAML text.
// Invariant: a bad file is refused with config::ConfigError (the programs'
// main() prints it as a clear startup error); any other exception escaping a
// loader, or a crash, is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "pc_server/operator/route_file.hpp"
#include "pc_server/app/server_config.hpp"
#include "robot_client/client_config.hpp"
#include "shared/world/robot_map.hpp"
#include "shared/behavior/human_awareness.hpp"
#include "shared/config/config_node.hpp"
#include "shared/config/control_config.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/world/world.hpp"
#include "tests/fuzz/fuzz_records.hpp"
#include "tests/support/paths.hpp"

using namespace inspect;

namespace {

const std::string kConfigDir = inspect::test::srcPath("config");

template <class F>
void tryLoad(const std::string& text, F&& load) {
  try {
    const auto root = config::ConfigNode::loadString(text, "fuzz.yaml");
    load(root);
    root.checkKnown();
  } catch (const config::ConfigError& e) {
    FUZZ_CHECK(std::string(e.what()).starts_with("fuzz.yaml"));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size > 64 * 1024) return 0;
  const std::string text(reinterpret_cast<const char*>(data), size);
  tryLoad(text, [](const config::ConfigNode& root) {
    const auto robot = config::loadRobotConfig(root);
    auto control = config::loadControlConfig(config::ConfigNode::loadString("{}", "fuzz.yaml"), kConfigDir);
    config::applyRobot(control, robot);
  });
  tryLoad(text, [](const config::ConfigNode& root) { (void)config::loadControlConfig(root, kConfigDir); });
  tryLoad(text, [](const config::ConfigNode& root) { (void)client::loadClientConfig(root); });
  tryLoad(text, [](const config::ConfigNode& root) { (void)behavior::loadAwarenessConfig(root, kConfigDir); });
  tryLoad(text, [](const config::ConfigNode& root) { (void)server::loadServerConfig(root); });
  tryLoad(text, [](const config::ConfigNode& root) {
    const world::World w = world::loadWorld(root);
    root.checkKnown();
    (void)world::mapFromWorld(w);
    (void)world::solidBounds(w);
    world::checkStartPose(w, 0.2);
  });
  try {
    const server::Route r = server::loadRouteText(text, "fuzz.yaml");
    (void)r.waypointsM();
    if (r.isWheelTest()) (void)server::wheelTestOf(r);
    else (void)server::goToOf(r, true);
  } catch (const config::ConfigError& e) {
    FUZZ_CHECK(std::string(e.what()).starts_with("fuzz.yaml"));
  }
  return 0;
}
