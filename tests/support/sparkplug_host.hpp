#pragma once
// The tests' Sparkplug B host application (tests/tools/sparkplug_host.py,
// written from the specification on python3-paho-mqtt and protoc's module
// of proto/sparkplug_b) on a test's broker, and pc_server's config pointed
// at that broker (docs/sparkplug.md).
#include <string>
#include <utility>
#include <vector>

#include "tests/support/mosquitto_broker.hpp"
#include "tests/support/process.hpp"

namespace inspect::test {

/// Where the host writes: <dir>/sparkplug_host.json (what it saw), <dir>/sparkplug_host.out.
std::string sparkplugHostJson(const std::string& dir);

/// Starts the host as primary host `host_id` (it publishes STATE online)
/// with `extra` arguments (--seconds, --until-ndeath, --dcmd, --tls ...);
/// returns once it has subscribed. Throws std::runtime_error when it did not within 15 s.
Process startSparkplugHost(const MosquittoBroker& broker, const std::string& dir, const std::string& host_id,
                           const std::vector<std::string>& extra);

/// The server config at `source` with its `sparkplug:` block turned on for
/// `broker` and `primary_host_id`, and each of `set`'s keys of the block
/// given its value (e.g. {"commands", "true"}). Throws std::runtime_error
/// when the block lacks a key.
std::string sparkplugServerConfig(const std::string& source, const MosquittoBroker& broker,
                                  const std::string& primary_host_id,
                                  const std::vector<std::pair<std::string, std::string>>& set = {});

}  // namespace inspect::test
