#include "tests/support/stack.hpp"
#include "tests/support/test_certs.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <regex>
#include <stdexcept>
#include <sstream>

namespace inspect::test {

namespace {
// The real-time priority of the stand-ins for hardware (the simulated MCU,
// the serial wire's relay): above robot_client's loop (10,
// config/client.yaml), as chips and cables of their own are never starved
// by the Pi's processes. Each applies it once started (--realtime-priority).
constexpr const char* kHardwarePriority = "20";
}  // namespace

std::string sharedHostClientConfig(const TempDir& dir) {
  std::string yaml = readFile(srcPath("config/client.yaml"));
  // Replace the value on the one `  sensor_timeout_s:` line, keeping its comment.
  const std::regex re("\\n  sensor_timeout_s: *([0-9.]+)");
  std::smatch m;
  if (!std::regex_search(yaml, m, re) ||
      std::distance(std::sregex_iterator(yaml.begin(), yaml.end(), re), std::sregex_iterator()) != 1)
    throw std::runtime_error("config/client.yaml: no single '  sensor_timeout_s:' line under safety to replace");
  yaml.replace(static_cast<std::size_t>(m.position(1)), static_cast<std::size_t>(m.length(1)), kSharedHostSensorTimeoutS);
  const std::string path = dir / "client-shared-host.yaml";
  writeFile(path, yaml);
  return path;
}

double expectedValue(const std::string& console_out, const std::string& field, int occurrence) {
  const std::regex re("expect ok \\(line \\d+\\): " + field + " = ([-0-9.e+]+)");
  int n = 0;
  for (auto it = std::sregex_iterator(console_out.begin(), console_out.end(), re); it != std::sregex_iterator(); ++it)
    if (n++ == occurrence) return std::stod((*it)[1]);
  return std::nan("");
}

Truth readTruth(const std::string& path) {
  Truth t;
  std::istringstream in(readFile(path));
  std::string line;
  while (std::getline(in, line)) {
    if (line.size() < 2 || line[0] == '#' || line[1] != ',') continue;
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) f.push_back(cell);
    try {
      if (line[0] == 'T' && f.size() >= 11) {
        TruthRow r;
        r.mono_ns = std::stoll(f[1]);
        r.t = std::stod(f[2]);
        r.x = std::stod(f[3]);
        r.y = std::stod(f[4]);
        r.theta = std::stod(f[5]);
        r.wheel_l = std::stod(f[6]);
        r.wheel_r = std::stod(f[7]);
        r.set_l = std::stod(f[8]);
        r.set_r = std::stod(f[9]);
        r.flags = static_cast<unsigned>(std::stoul(f[10]));
        t.rows.push_back(r);
      } else if (line[0] == 'C' && f.size() >= 7) {
        t.commands.push_back({std::stoll(f[1]), std::stod(f[2]), std::stoi(f[3]), std::stoi(f[4]), std::stoi(f[5]),
                              std::stoi(f[6])});
      } else if (line[0] == 'P' && f.size() >= 9) {
        t.people.push_back({std::stod(f[2]), f[3], std::stod(f[4]), std::stod(f[5]), std::stod(f[6]), std::stod(f[7]),
                            std::stod(f[8])});
      } else if (line[0] == 'G' && f.size() >= 7 && (f.size() - 5) % 2 == 0) {
        TruthGas g;
        g.mono_ns = std::stoll(f[1]);
        g.t = std::stod(f[2]);
        g.x = std::stod(f[3]);
        g.y = std::stod(f[4]);
        const std::size_t n = (f.size() - 5) / 2;
        for (std::size_t i = 0; i < n; ++i) {
          g.truth.push_back(std::stod(f[5 + i]));
          g.reading.push_back(std::stod(f[5 + n + i]));
        }
        t.gas.push_back(std::move(g));
      } else if (line[0] == 'E' && f.size() >= 4) {
        t.events.push_back({std::stoll(f[1]), std::stod(f[2]), f[3], f.size() > 4 ? f[4] : ""});
      }
    } catch (const std::exception&) {
      // A line being written while we read it: skip.
    }
  }
  return t;
}

Stack::~Stack() {
  // Client first, so the simulator's watchdog is not what a test sees at teardown.
  server_.terminate();
  for (auto& r : robots_) {
    r->client.terminate();
    r->sim.terminate();
  }
  for (auto& [id, p] : relays_) p.terminate();
}

bool Stack::startServer(const std::string& script, const std::vector<std::string>& extra) {
  writeFile(dir_ / "script.txt", script);
  std::vector<std::string> argv = {binPath("pc_server"), "--config", srcPath("config/server.yaml"),
                                   "--bind",            "127.0.0.1", "--port",
                                   "0",                 "--port-file", dir_ / "port",
                                   "--script",          dir_ / "script.txt"};
  // Runs are recorded (track/goto start them) into the test's directory.
  if (std::find(extra.begin(), extra.end(), "--runs-dir") == extra.end()) {
    argv.push_back("--runs-dir");
    argv.push_back(dir_ / "runs");
  }
  if (video_) {
    for (const std::string a : {"--video-port", "0", "--video-port-file"}) argv.push_back(a);
    argv.push_back(dir_ / "video_port");
    argv.push_back("--video-dir");
    argv.push_back(videoDir());
  } else {
    argv.push_back("--no-video");
  }
  if (foxglove_) {
    for (const std::string a : {"--foxglove-port", "0", "--foxglove-port-file"}) argv.push_back(a);
    argv.push_back(dir_ / "foxglove_port");
    argv.push_back("--foxglove-token-file");
    argv.push_back(dir_ / "foxglove.token");
  } else {
    argv.push_back("--no-foxglove");
  }
  // Mutual TLS with the tests' certificates, as in the field (unless the test asks for --plaintext).
  if (std::find(extra.begin(), extra.end(), "--plaintext") == extra.end()) {
    argv.push_back("--certs");
    argv.push_back(testCertsDir());
  }
  argv.insert(argv.end(), extra.begin(), extra.end());
  server_ = Process::spawn(argv, dir_ / "server.out", dir_ / "server.err");
  if (!waitUntil([&] { return exists(dir_ / "port"); }, 10.0)) return false;
  port_ = std::atoi(readFile(dir_ / "port").c_str());
  if (video_) {
    if (!waitUntil([&] { return exists(dir_ / "video_port"); }, 10.0)) return false;
    video_port_ = std::atoi(readFile(dir_ / "video_port").c_str());
  }
  if (foxglove_) {
    if (!waitUntil([&] { return exists(dir_ / "foxglove_port"); }, 10.0)) return false;
    foxglove_port_ = std::atoi(readFile(dir_ / "foxglove_port").c_str());
  }
  return port_ > 0 && (!video_ || video_port_ > 0) && (!foxglove_ || foxglove_port_ > 0);
}

std::string Stack::foxgloveToken() const {
  std::string t = readFile(dir_ / "foxglove.token");
  while (!t.empty() && (t.back() == '\n' || t.back() == '\r')) t.pop_back();
  return t;
}

RobotProcs& Stack::startRobot(const std::string& id, const std::string& world,
                              const std::vector<std::string>& relay_args, const std::vector<std::string>& sim_args,
                              const std::vector<std::string>& client_args) {
  auto r = std::make_unique<RobotProcs>();
  r->id = id;
  r->truth = dir_ / (id + "-truth.csv");
  r->cmd_log = dir_ / (id + "-cmds.csv");
  const std::string sim_pty = dir_ / (id + "-mcu");
  const std::string world_path = world.starts_with("/") ? world : srcPath("config/worlds/" + world);
  std::vector<std::string> sim_argv = {binPath("mcu_sim"), "--world", world_path, "--robot",
                                       srcPath("config/robot.yaml"), "--pty-link", sim_pty, "--truth", r->truth};
  if (!firmware_elf_.empty()) {
    // The firmware in QEMU on the line, mcu_sim --hil behind it (the options after --world are mcu_sim's).
    // QEMU is the MCU: it and its mcu_sim at the hardware's priority, above robot_client's loop. (QEMU
    // ran at normal priority until the circle through the firmware was measured: 160-530 control
    // ticks over 5 ms late in a run, and the Pi's wheel loop oscillating on them.)
    sim_argv = {"/bin/bash", srcPath("scripts/mcu_qemu.sh"), "--serial-link", sim_pty, "--elf", firmware_elf_,
                "--realtime-priority", kHardwarePriority, "--mcu-sim", binPath("mcu_sim"), "--world", world_path,
                "--robot", srcPath("config/robot.yaml"), "--truth", r->truth};
  }
  sim_argv.insert(sim_argv.end(), sim_args.begin(), sim_args.end());
  if (firmware_elf_.empty()) sim_argv.insert(sim_argv.end(), {"--realtime-priority", kHardwarePriority});
  // Not with the firmware: its clock runs on through a stall of mcu_sim's, and
  // a world that waited would be wheels that stopped turning under it.
  if (!measure_failsafes_ && !catch_up_ && firmware_elf_.empty()) sim_argv.push_back("--freeze-on-stall");
  r->sim = Process::spawn(sim_argv, dir_ / (id + "-sim.out"), dir_ / (id + "-sim.err"));
  waitUntil([&] { return exists(sim_pty); }, firmware_elf_.empty() ? 10.0 : 20.0);
  r->pty = sim_pty;
  if (!relay_args.empty()) {
    r->pty = dir_ / (id + "-relay");
    std::vector<std::string> argv = {binPath("serial_relay"), "--mcu", sim_pty, "--pty-link", r->pty,
                                     "--realtime-priority", kHardwarePriority};
    argv.insert(argv.end(), relay_args.begin(), relay_args.end());
    relays_.emplace(id, Process::spawn(argv, dir_ / (id + "-relay.out"), dir_ / (id + "-relay.err")));
    waitUntil([&] { return exists(r->pty); }, 10.0);
  }
  const std::string client_config =
      measure_failsafes_ ? srcPath("config/client.yaml") : sharedHostClientConfig(dir_);
  std::vector<std::string> client_argv = {binPath("robot_client"), "--config", client_config,
                                          "--robot-config", srcPath("config/robot.yaml"), "--control-config",
                                          srcPath("config/control.yaml"), "--behavior-config",
                                          srcPath("config/behavior.yaml"), "--serial", r->pty, "--server",
                                          "127.0.0.1:" + std::to_string(port_), "--id", id, "--cmd-log", r->cmd_log};
  if (video_) {
    client_argv.push_back("--video-port");
    client_argv.push_back(std::to_string(video_port_));
  } else {
    client_argv.push_back("--no-video");
  }
  if (std::find(client_args.begin(), client_args.end(), "--plaintext") == client_args.end()) {
    client_argv.push_back("--certs");
    client_argv.push_back(testCertsDir({id}));
  }
  client_argv.insert(client_argv.end(), client_args.begin(), client_args.end());
  client_argv.insert(client_argv.begin(), client_prefix_.begin(), client_prefix_.end());
  r->client = Process::spawn(client_argv, dir_ / (id + "-client.out"), dir_ / (id + "-client.err"));
  r->client_argv = std::move(client_argv);
  robots_.push_back(std::move(r));
  return *robots_.back();
}

void Stack::restartClient(const std::string& id) {
  for (auto& r : robots_)
    if (r->id == id) r->client = Process::spawn(r->client_argv, dir_ / (id + "-client.out"), dir_ / (id + "-client.err"));
}

std::string Stack::logs() const {
  std::string out;
  auto add = [&](const std::string& name) {
    const std::string text = readFile(dir_ / name);
    if (text.empty()) return;
    out += "---- " + name + " ----\n" + (text.size() > 6000 ? "...\n" + text.substr(text.size() - 6000) : text);
  };
  add("server.out");
  add("server.err");
  for (const auto& r : robots_) {
    add(r->id + "-sim.out");
    add(r->id + "-sim.err");
    add(r->id + "-client.err");
    add(r->id + "-relay.out");
    add(r->id + "-relay.err");
  }
  return out;
}

int mcapTopicCount(const std::string& reader_json, const std::string& topic) {
  const std::regex re("\"" + topic + "\":([0-9]+)");
  std::smatch m;
  return std::regex_search(reader_json, m, re) ? std::stoi(m[1]) : -1;
}

}  // namespace inspect::test
