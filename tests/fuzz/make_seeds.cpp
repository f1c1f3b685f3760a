// Writes the seed corpora of the fuzz harnesses (tests/fuzz/corpus/<name>/)
// and the dictionaries (tests/fuzz/*.dict) from the project's real code and
// files: serial frames from the FrameEncoder, Hello/telemetry/events/acks
// from RobotCore as robot_client sends them, commands as pc_server sends
// them (the real route files), RTP packets of the real H.264 encoder, the
// .fis files of config/fuzzy and tests/shared/fuzzy/data, the YAML of config/.
// Run once from the source root after a change of a wire format:
//   build-asan/bin/fuzz_make_seeds tests/fuzz
// Not a test; the seeds are committed.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "inspect_robot/v1/link.pb.h"
#include "pc_server/operator/route_file.hpp"
#include "robot_client/client_config.hpp"
#include "shared/robot/robot_core.hpp"
#include "shared/config/control_config.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/net/delimited_codec.hpp"
#include "shared/net/gains_proto.hpp"
#include "shared/net/link_version.hpp"
#include "shared/serial/cobs.hpp"
#include "shared/serial/frame_codec.hpp"
#include "shared/util/log.hpp"
#include "shared/video/frame_source.hpp"
#include "shared/video/h264_codec.hpp"
#include "shared/video/rtcp.hpp"
#include "shared/video/rtp_h264.hpp"
#include "tests/fuzz/fuzz_records.hpp"
#include "tests/support/paths.hpp"

namespace fs = std::filesystem;
using namespace inspect;
using Bytes = std::vector<uint8_t>;

namespace {

const std::string kSrc = inspect::test::sourceDir();
fs::path g_out;

void write(const std::string& corpus, const std::string& name, const Bytes& b) {
  const fs::path dir = g_out / "corpus" / corpus;
  fs::create_directories(dir);
  std::ofstream(dir / name, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), b.size());
}
Bytes readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), {});
}
Bytes bytesOf(const std::string& s) { return Bytes(s.begin(), s.end()); }
Bytes frameBytes(const serial::EncodedFrame& f) { return Bytes(f.bytes.begin(), f.bytes.begin() + f.size); }
void append(Bytes& a, const Bytes& b) { a.insert(a.end(), b.begin(), b.end()); }

std::string delimited(const v1::Envelope& env) {
  std::string s;
  net::appendDelimited(env, s);
  return s;
}

serial::SensorFrame sensorFrame(uint32_t ms, int32_t disp, uint16_t gas0 = 40) {
  serial::SensorFrame f;
  f.mcu_time_ms = ms;
  f.wheel_speed_mrad_s = {500, 500};
  f.wheel_disp_0p1mm = {disp, disp};
  f.ultrasonic_mm = {1800, serial::kNoEcho, 600, serial::kNoEcho};
  f.grayscale = 0x18;
  f.gas_raw = {gas0, 10, 20, 2090};
  f.battery_mv = 12400;
  return f;
}

// --- serial -----------------------------------------------------------------

void serialSeeds() {
  serial::FrameEncoder enc;
  Bytes stream{7};  // byte 0: the chunking seed
  for (int i = 0; i < 5; ++i) append(stream, frameBytes(enc.encode(sensorFrame(1000 + 10 * i, 50 * i))));
  write("serial", "sensor_stream", stream);

  Bytes cmds{42};
  append(cmds, frameBytes(enc.encode(serial::WheelCommand{1200, -800, serial::WheelCommand::kEnable})));
  append(cmds, frameBytes(enc.encode(serial::Heartbeat{123456})));
  append(cmds, frameBytes(enc.encode(serial::PtzCommand{1500, -300, 0})));
  append(cmds, frameBytes(enc.encode(serial::PtzCommand{0, 0, 1})));
  write("serial", "commands", cmds);

  Bytes noisy{200, 0x13, 0x37, 0x00};
  Bytes good = frameBytes(enc.encode(sensorFrame(2000, 100)));
  Bytes flipped = good;
  flipped[10] ^= 0x04;
  append(noisy, flipped);
  append(noisy, Bytes(good.begin(), good.begin() + 20));  // truncated, then a good one
  noisy.push_back(0);
  append(noisy, good);
  append(noisy, Bytes(300, 0x55));  // longer than any frame
  noisy.push_back(0);
  append(noisy, frameBytes(enc.encode(serial::WheelCommand{0, 0, 0})));
  write("serial", "noisy", noisy);
}

// --- a robot as robot_client runs it ------------------------------------------

struct RealRobot {
  client::ClientConfig client = client::loadClientConfigFile(kSrc + "/config/client.yaml");
  config::RobotConfig robot = config::loadRobotConfigFile(kSrc + "/config/robot.yaml");
  config::ControlConfig control = [this] {
    auto c = config::loadControlConfigFile(kSrc + "/config/control.yaml");
    config::applyRobot(c, robot);
    return c;
  }();
  robot::RobotCore core{robot, client.safety, control, config::loadScheduler(control)};
  double t = 0.0;
  uint32_t ms = 1000;
  int32_t disp = 0;

  RealRobot() {
    core.onSerialState(true, t);
    core.onLinkUp(t);
  }
  v1::Envelope hello(const std::string& id) {
    v1::Envelope env;
    env.set_seq(1);
    auto* h = env.mutable_hello();
    h->set_robot_id(id);
    h->set_protocol_version(net::kProtocolVersion);
    for (const char* c : {"teleop", "video", "ptz", "gas"}) h->add_capabilities(c);
    h->set_software_version("0.1.0");
    for (const auto& g : core.gasChannels()) *h->add_gas_channels() = g;
    net::toProto(core.gains(), *h->mutable_gains());
    h->set_gains_version(core.gainsVersion());
    h->set_fis_name("fuzzy_pid");
    return env;
  }
  void frames(int n, uint16_t gas0 = 40) {
    for (int i = 0; i < n; ++i) {
      t += 0.01;
      ms += 10;
      disp += 20;
      core.onLinkActivity(t);
      core.onSensorFrame(sensorFrame(ms, disp, gas0), t);
    }
  }
  v1::Envelope telemetry() {
    v1::Envelope env;
    core.fillTelemetry(*env.mutable_telemetry(), t);
    return env;
  }
  std::vector<v1::Envelope> events() {
    std::vector<v1::Envelope> out;
    for (auto& a : core.takeAcks()) {
      v1::Envelope env;
      *env.mutable_ack() = a;
      out.push_back(env);
    }
    for (auto& e : core.takeEvents()) {
      v1::Envelope env;
      auto* ev = env.mutable_event();
      ev->set_kind(e.kind);
      ev->set_text(e.text);
      if (e.gas_alarm) *ev->mutable_gas_alarm() = *e.gas_alarm;
      if (e.gains) {
        *ev->mutable_gains() = *e.gains;
        ev->set_gains_version(e.gains_version);
      }
      ev->set_robot_time_us(static_cast<uint64_t>(t * 1e6));
      out.push_back(env);
    }
    return out;
  }
};

// --- link_server: what robots send ---------------------------------------------

// tag: bit 0 = connection, (tag >> 1) % 4: 0 bytes, 2 reconnect, 3 look.
void putLink(Bytes& out, int conn, const std::string& bytes) { fuzz::putRecord(out, static_cast<uint8_t>(conn), bytes); }
void putLook(Bytes& out, uint8_t what, uint8_t n = 1) {
  fuzz::putRecord(out, 0x06, Bytes{what, n});
}

void linkServerSeeds() {
  RealRobot r;
  const auto hello = r.hello("robot1");
  r.frames(50);
  const auto tlm_quiet = r.telemetry();
  v1::Command teleop;
  teleop.set_id(7);
  teleop.mutable_teleop()->set_v_m_s(0.3);
  v1::Envelope ack;
  *ack.mutable_ack() = r.core.onCommand(teleop, r.t);
  r.frames(300, 4000);  // CH4 far over its thresholds: alarms raised
  const auto tlm_alarm = r.telemetry();
  const auto events = r.events();
  v1::Envelope hb;
  hb.mutable_heartbeat();

  Bytes s;
  putLink(s, 0, delimited(hello));
  putLink(s, 0, delimited(tlm_quiet) + delimited(hb) + delimited(ack));
  for (const auto& e : events) putLink(s, 0, delimited(e));
  putLink(s, 0, delimited(tlm_alarm));
  for (uint8_t w = 0; w < 6; ++w) putLook(s, w, 1);
  write("link_server", "session", s);

  // The same stream in small pieces, and the split inside frames.
  std::string all = delimited(hello) + delimited(tlm_quiet) + delimited(events.empty() ? hb : events.front());
  Bytes split;
  for (std::size_t i = 0; i < all.size(); i += 7) putLink(split, 0, all.substr(i, 7));
  putLook(split, 0);
  write("link_server", "split", split);

  // Two robots, one of them reconnecting (and replacing its older session).
  RealRobot r2;
  Bytes two;
  putLink(two, 0, delimited(hello));
  putLink(two, 1, delimited(r2.hello("robot2")));
  putLink(two, 0, delimited(tlm_alarm));
  r2.frames(20);
  putLink(two, 1, delimited(r2.telemetry()));
  fuzz::putRecord(two, 0x04, Bytes{});  // connection 0 closes, a new one opens
  putLink(two, 0, delimited(hello) + delimited(tlm_quiet));
  putLook(two, 0);
  putLook(two, 3);
  putLook(two, 0x81);
  write("link_server", "two_robots", two);

  // Refused: wrong version, bad id, telemetry first, an oversized length.
  Bytes bad;
  auto wrong = hello;
  wrong.mutable_hello()->set_protocol_version(99);
  putLink(bad, 0, delimited(wrong));
  fuzz::putRecord(bad, 0x04, Bytes{});
  auto badid = hello;
  badid.mutable_hello()->set_robot_id("robot 1\x01");
  putLink(bad, 0, delimited(badid));
  putLink(bad, 1, delimited(tlm_quiet));
  fuzz::putRecord(bad, 0x05, Bytes{});
  putLink(bad, 1, std::string("\xff\xff\xff\xff\x0f", 5));
  write("link_server", "refused", bad);
}

// --- robot_core: what the server and the MCU send a robot ------------------------

Bytes payloadOf(const serial::SensorFrame& f) {
  serial::FrameEncoder enc;
  const auto e = enc.encode(f);
  std::array<uint8_t, serial::kMaxRawFrame> raw{};
  const auto n = serial::cobsDecode({e.bytes.data(), e.size - 1}, raw);
  return Bytes(raw.begin() + 2, raw.begin() + static_cast<long>(*n) - 2);
}
// tag % 5 == 2 with (tag >> 5) + 1 == repeat.
uint8_t payloadTag(int repeat) {
  for (int tag = 32 * (repeat - 1); tag < 32 * repeat; ++tag)
    if (tag % 5 == 2) return static_cast<uint8_t>(tag);
  return 2;
}

struct CoreSeed {
  Bytes b;
  uint32_t ms = 1000;
  int32_t disp = 0;
  uint64_t id = 0;
  void frames(int n, uint16_t gas0 = 40) {
    while (n > 0) {
      const int k = std::min(n, 8);
      fuzz::putRecord(b, payloadTag(k), payloadOf(sensorFrame(ms, disp, gas0)));
      ms += 10 * k;
      disp += 20;
      n -= k;
    }
  }
  void link(const v1::Envelope& env) { fuzz::putRecord(b, 0, delimited(env)); }
  void command(v1::Command c) {
    c.set_id(++id);
    v1::Envelope env;
    *env.mutable_command() = c;
    link(env);
  }
  void heartbeat() {
    v1::Envelope env;
    env.mutable_heartbeat();
    link(env);
  }
};

v1::Command teleopCmd(double v, double w) {
  v1::Command c;
  c.mutable_teleop()->set_v_m_s(v);
  c.mutable_teleop()->set_w_rad_s(w);
  return c;
}

void robotCoreSeeds() {
  {
    CoreSeed s;
    s.frames(3);
    s.heartbeat();
    s.command(teleopCmd(0.4, 0.2));
    s.frames(16);
    s.command(teleopCmd(-0.2, -1.0));
    s.frames(16);
    v1::Command stop;
    stop.mutable_stop();
    s.command(stop);
    s.frames(8);
    write("robot_core", "teleop", s.b);
  }
  {
    CoreSeed s;
    s.frames(2);
    s.command(teleopCmd(0.3, 0));
    v1::Command e;
    e.mutable_estop();
    s.command(e);
    s.frames(4);
    s.command(teleopCmd(0.3, 0));  // refused while latched
    v1::Command r;
    r.mutable_resume();
    s.command(r);
    s.frames(4);
    fuzz::putRecord(s.b, 3, Bytes{250});  // 250 ms without frames: stale, failsafe
    fuzz::putRecord(s.b, 4, Bytes{0x02});  // link down
    fuzz::putRecord(s.b, 4, Bytes{0x01});  // link up, serial closed
    fuzz::putRecord(s.b, 4, Bytes{0x03});
    s.command(r);
    write("robot_core", "latches", s.b);
  }
  {
    const auto route = server::loadRouteFile(kSrc + "/config/routes/gas_lab_inspection.yaml");
    CoreSeed s;
    s.frames(2);
    v1::Command c;
    *c.mutable_go_to() = server::goToOf(route, true);
    s.command(c);
    s.frames(40);
    s.frames(40, 4000);  // a gas alarm on the way
    v1::Command r;
    r.mutable_resume();
    s.command(r);
    s.frames(16);
    write("robot_core", "inspection_route", s.b);
  }
  {
    const auto route = server::loadRouteFile(kSrc + "/config/routes/identification.yaml");
    CoreSeed s;
    s.frames(2);
    v1::Command c;
    *c.mutable_wheel_test() = server::wheelTestOf(route);
    s.command(c);
    s.frames(40);
    write("robot_core", "wheel_test", s.b);
  }
  {
    CoreSeed s;
    s.frames(2);
    v1::Command c;
    auto* circle = c.mutable_track()->mutable_circle();
    circle->set_radius_m(1.0);
    circle->set_speed_m_s(0.3);
    circle->set_laps(1);
    c.mutable_track()->set_controller("fuzzy_pid");
    s.command(c);
    s.frames(40);
    v1::Command stop;
    stop.mutable_stop();
    s.command(stop);
    v1::Command w;
    auto* wp = w.mutable_track()->mutable_waypoints();
    for (int i = 0; i < 4; ++i) {
      auto* p = wp->add_points();
      p->set_t_s(1.0 + i);
      p->set_x_m(0.3 * (i + 1));
      p->set_y_m(i % 2 ? 0.2 : 0.0);
    }
    w.mutable_track()->set_controller("pid");
    s.command(w);
    s.frames(24);
    write("robot_core", "track_paths", s.b);
  }
  {
    RealRobot real;
    CoreSeed s;
    s.frames(2);
    v1::Command g;
    net::toProto(real.core.gains(), *g.mutable_gains()->mutable_gains());
    g.mutable_gains()->mutable_gains()->set_kp(real.core.gains().fuzzy.base.kp * 1.1);
    const Bytes fis = readFile(kSrc + "/config/fuzzy/fuzzy_pid.fis");
    g.mutable_gains()->set_fis(std::string(fis.begin(), fis.end()));
    g.mutable_gains()->set_source("fuzz seed");
    s.command(g);
    s.frames(4);
    write("robot_core", "gains_push", s.b);
  }
  {
    serial::FrameEncoder enc;
    CoreSeed s;
    Bytes raw{0x11, 0x22};
    for (int i = 0; i < 4; ++i) append(raw, frameBytes(enc.encode(sensorFrame(5000 + 10 * i, 10 * i))));
    raw[raw.size() / 2] ^= 0x40;
    fuzz::putRecord(s.b, 1, raw);
    s.heartbeat();
    s.command(teleopCmd(0.1, 0));
    fuzz::putRecord(s.b, 1, frameBytes(enc.encode(sensorFrame(5100, 100))));
    write("robot_core", "raw_serial", s.b);
  }
  {
    // People from the camera between sensor frames (tag 4, bit 2): one at
    // +0.05 rad 5 m, one at -0.1 rad with the feet out of view.
    CoreSeed s;
    s.frames(3);
    s.heartbeat();
    s.command(teleopCmd(0.3, 0));
    const Bytes look{7, 2, 0xf4, 0x01, 0x88, 0x13, 0x18, 0xfc, 0x18, 0xfc};
    for (int i = 0; i < 6; ++i) {
      s.frames(8);
      fuzz::putRecord(s.b, 4, look);
    }
    write("robot_core", "camera_people", s.b);
  }
}

// --- rtp_h264: the robot's camera stream -----------------------------------------

void rtpSeeds() {
  video::EncoderSettings es;
  es.width = 96;
  es.height = 64;
  es.gop = 4;
  es.bitrate_kbps = 200;
  video::H264Encoder encoder(es);
  video::SyntheticSource source(es.width, es.height);
  video::H264Packetizer pk(0xC0FFEE, 240, 100);
  std::vector<std::vector<uint8_t>> packets;
  cv::Mat bgr;
  for (uint32_t i = 0; i < 6; ++i) {
    source.read(bgr, 1'000'000 + i * 33'333, i);
    video::EncodedFrame f;
    if (encoder.encode(bgr, 1'000'000 + i * 33'333, i, false, f))
      pk.packetize(f.annexb, i * 3000, f.capture_us, packets);
  }
  Bytes inorder, luma, shuffled;
  for (const auto& p : packets) {
    fuzz::putRecord(inorder, 0, p);
    fuzz::putRecord(luma, 8, p);
  }
  write("rtp_h264", "stream", inorder);
  write("rtp_h264", "stream_luma", luma);
  // Reordered, a duplicate, a loss, then a pause (flush).
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < packets.size(); ++i) order.push_back(i);
  if (order.size() > 6) {
    std::swap(order[1], order[2]);
    order.insert(order.begin() + 4, order[3]);
    order.erase(order.begin() + static_cast<long>(order.size()) - 3);
  }
  for (std::size_t i : order) fuzz::putRecord(shuffled, 0, packets[i]);
  fuzz::putRecord(shuffled, 7, Bytes{});
  write("rtp_h264", "reordered_lossy", shuffled);
  // RTCP both ways among the packets: the robot's SR + CNAME, the server's
  // RR + NACK for two lost packets + PLI (record tag 6).
  Bytes with_rtcp;
  const video::rtcp::ReportBlock block{0xC0FFEE, 26, 2, 105, 90, 0x12345678, 6554};
  Bytes sr, rr;
  video::rtcp::appendSenderReport(sr, 0xC0FFEE, {video::rtcp::ntpFromUnixMicros(1767225600000000ULL), 3000, 4, 900});
  video::rtcp::appendCname(sr, 0xC0FFEE, "robot1");
  video::rtcp::appendReceiverReport(rr, 0x5E55, std::span(&block, 1));
  const std::vector<uint16_t> lost{102, 104};
  video::rtcp::appendNack(rr, 0x5E55, 0xC0FFEE, lost);
  video::rtcp::appendPli(rr, 0x5E55, 0xC0FFEE);
  for (std::size_t i = 0; i < packets.size(); ++i) {
    if (i == 2) fuzz::putRecord(with_rtcp, 6, sr);
    if (i == 4) fuzz::putRecord(with_rtcp, 6, rr);
    if (i != 2 && i != 4) fuzz::putRecord(with_rtcp, 0, packets[i]);
  }
  write("rtp_h264", "with_rtcp", with_rtcp);
}

// --- files ------------------------------------------------------------------

void copyFiles(const std::string& corpus, const std::vector<fs::path>& dirs, const std::string& ext) {
  for (const auto& d : dirs)
    for (const auto& e : fs::directory_iterator(d))
      if (e.path().extension() == ext) write(corpus, e.path().filename().string(), readFile(e.path()));
}

void collectKeys(const YAML::Node& n, std::set<std::string>& keys) {
  if (n.IsMap()) {
    for (const auto& kv : n) {
      if (kv.first.IsScalar()) keys.insert(kv.first.Scalar());
      collectKeys(kv.second, keys);
    }
  } else if (n.IsSequence()) {
    for (const auto& e : n) collectKeys(e, keys);
  }
}

void dictionaries() {
  std::set<std::string> keys;
  for (const char* d : {"/config", "/config/worlds", "/config/routes", "/config/scenarios"})
    for (const auto& e : fs::directory_iterator(kSrc + d))
      if (e.path().extension() == ".yaml") collectKeys(YAML::LoadFile(e.path().string()), keys);
  std::ofstream yaml(g_out / "config.dict");
  yaml << "# YAML keys of config/ (written by make_seeds)\n";
  for (const auto& k : keys) yaml << "\"" << k << ":\"\n";
  for (const char* t : {": ", "- ", "{", "}", "[", "]", ", ", "\\x0a  ", "true", "false", ".nan", "-.inf", "1e309", "~",
                        "&a ", "*a", "!!str ", "---", "|", ">"})
    yaml << "\"" << t << "\"\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: fuzz_make_seeds OUT_DIR   (OUT_DIR = tests/fuzz: writes corpus/<name>/ and *.dict)\n";
    return 2;
  }
  log::setLevel(log::Level::kError);
  g_out = argv[1];
  serialSeeds();
  linkServerSeeds();
  robotCoreSeeds();
  rtpSeeds();
  copyFiles("fis", {kSrc + "/config/fuzzy", kSrc + "/tests/shared/fuzzy/data"}, ".fis");
  copyFiles("config", {kSrc + "/config", kSrc + "/config/worlds", kSrc + "/config/routes"}, ".yaml");
  dictionaries();
  std::cout << "seeds written under " << g_out << "\n";
  return 0;
}
