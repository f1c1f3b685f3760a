#include "tests/support/sparkplug_host.hpp"

#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include "tests/support/paths.hpp"

namespace inspect::test {

std::string sparkplugHostJson(const std::string& dir) { return dir + "/sparkplug_host.json"; }

Process startSparkplugHost(const MosquittoBroker& broker, const std::string& dir, const std::string& host_id,
                           const std::vector<std::string>& extra) {
  const std::string ready = dir + "/sparkplug_host.ready";
  const char* pb = std::getenv("INSPECT_PYTHON_PROTO");
  // Debian's Python, which has python3-paho-mqtt and python3-protobuf (scripts/setup.sh).
  std::vector<std::string> argv = {"/usr/bin/python3", srcPath("tests/tools/sparkplug_host.py"), "--port",
                                   std::to_string(broker.port()), "--credentials", broker.credentialsFile(),
                                   "--pb-dir", pb ? pb : binDir() + "/../python_proto", "--host-id", host_id,
                                   "--json", sparkplugHostJson(dir), "--ready-file", ready};
  argv.insert(argv.end(), extra.begin(), extra.end());
  auto host = Process::spawn(argv, dir + "/sparkplug_host.out", dir + "/sparkplug_host.out");
  if (!waitUntil([&] { return std::filesystem::exists(ready); }, 15.0))
    throw std::runtime_error("the Sparkplug host did not subscribe within 15 s: " + readFile(dir + "/sparkplug_host.out"));
  return host;
}

std::string sparkplugServerConfig(const std::string& source, const MosquittoBroker& broker,
                                  const std::string& primary_host_id,
                                  const std::vector<std::pair<std::string, std::string>>& set) {
  std::string yaml = readFile(source);
  const auto at = yaml.find("\nsparkplug:");
  // The value of `key` in the block: from after "key:" to its comment or the line's end.
  const auto put = [&](const std::string& key, const std::string& value) {
    const auto k = at == std::string::npos ? std::string::npos : yaml.find("\n  " + key + ":", at);
    if (k == std::string::npos) throw std::runtime_error(source + ": no sparkplug." + key + " to set");
    const auto from = k + 4 + key.size();
    const auto end = yaml.find_first_of("#\n", from);
    yaml.replace(from, end - from, " " + value + " ");
  };
  put("enabled", "true");
  put("port", std::to_string(broker.port()));
  put("credentials_file", broker.credentialsFile());
  put("primary_host_id", primary_host_id);
  for (const auto& [k, v] : set) put(k, v);
  return yaml;
}

}  // namespace inspect::test
