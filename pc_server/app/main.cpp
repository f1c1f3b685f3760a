// pc_server: the operator PC process (robot link + operator console).
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "pc_server/app/cli_options.hpp"
#include "pc_server/terminal/operator_socket.hpp"
#include "pc_server/app/server_app.hpp"
#include "shared/util/startup_error.hpp"

int main(int argc, char** argv) {
  using namespace inspect::server;
  try {
    const CliOptions options = parseCli(std::vector<std::string>(argv + 1, argv + argc));
    if (options.help) {
      std::cout << usageText();
      return 0;
    }
    if (options.attach) return attachToOperatorSocket(*options.attach);
    return runServer(options);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "pc_server: %s\n", e.what());
    return 2;
  } catch (const inspect::config::ConfigError& e) {
    std::fprintf(stderr, "pc_server: %s\n", e.what());
    return 2;
  } catch (const inspect::util::StartupError& e) {
    std::fprintf(stderr, "pc_server: %s\n", e.what());
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pc_server: fatal: %s\n", e.what());
    return 4;
  }
}
