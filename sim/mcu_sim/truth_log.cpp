#include "sim/mcu_sim/truth_log.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "shared/serial/cobs.hpp"
#include "shared/util/clock.hpp"

namespace inspect::sim {

TruthLog::TruthLog(const std::string& path) : file_(std::make_unique<BackgroundFile>(path, "--truth")) {
  comment("mcu_sim ground truth; format: docs/simulator.md");
  comment("T,mono_ns,sim_t_s,x_m,y_m,theta_rad,wheel_l_rad_s,wheel_r_rad_s,setpoint_l_rad_s,setpoint_r_rad_s,fault_flags");
  comment("C,mono_ns,sim_t_s,seq,left_mrad_s,right_mrad_s,flags");
  comment("E,mono_ns,sim_t_s,event,detail");
  comment("P,mono_ns,sim_t_s,id,x_m,y_m,vx_m_s,vy_m_s,robot_dist_m");
  comment("G,mono_ns,sim_t_s,inlet_x_m,inlet_y_m,true0,...,trueN-1,read0,...,readN-1 (N gas channels in slot order, "
          "see the gas_channels event; read NaN = no data)");
}

TruthLog::~TruthLog() = default;

void TruthLog::openFrameLog(const std::string& path) {
  frames_.reset();
  frames_ = std::make_unique<BackgroundFile>(path, "--frame-log");
  frames_->append(
      "# mcu_sim sensor frames sent; format: docs/failsafes.md\n"
      "# F,mono_ns,sim_t_s,msg_id,seq,crc16,mcu_time_ms\n");
}

std::string TruthLog::writerSummary() const {
  char buf[160];
  std::snprintf(buf, sizeof buf, "truth log: longest write-out %.0f ms, dropped %llu bytes",
                std::max(file_->maxWriteMs(), frames_ ? frames_->maxWriteMs() : 0.0),
                static_cast<unsigned long long>(file_->droppedBytes() + (frames_ ? frames_->droppedBytes() : 0)));
  return buf;
}

void TruthLog::onFrameSent(double sim_t_s, std::span<const uint8_t> wire, uint32_t mcu_time_ms) {
  if (!frames_ || wire.size() < 2) return;
  // The wire CRC as sent: undo COBS (without the delimiter); the frame ends with the CRC, little-endian.
  std::array<uint8_t, serial::kMaxRawFrame> raw{};
  const auto n = serial::cobsDecode(wire.first(wire.size() - 1), raw);
  if (!n || *n < 4) return;
  const unsigned crc = raw[*n - 2] | (static_cast<unsigned>(raw[*n - 1]) << 8);
  char buf[128];
  const int len = std::snprintf(buf, sizeof buf, "F,%lld,%.3f,%u,%u,%u,%u\n", static_cast<long long>(monoNowNs()),
                                sim_t_s, static_cast<unsigned>(raw[0]), static_cast<unsigned>(raw[1]), crc,
                                static_cast<unsigned>(mcu_time_ms));
  if (len > 0) frames_->append({buf, std::min<std::size_t>(static_cast<std::size_t>(len), sizeof buf - 1)});
}

void TruthLog::line(const char* text, int n) {
  if (n <= 0) return;
  // snprintf returns the untruncated length; the callers' buffers end with '\n' only when it fit.
  n = std::min(n, static_cast<int>(std::strlen(text)));
  file_->append({text, static_cast<std::size_t>(n)});
}

void TruthLog::onSample(const TruthSample& s) {
  char buf[256];
  const int n = std::snprintf(buf, sizeof buf, "T,%lld,%.3f,%.6f,%.6f,%.6f,%.5f,%.5f,%.5f,%.5f,%u\n",
                              static_cast<long long>(monoNowNs()), s.sim_t_s, s.pose.x_m, s.pose.y_m, s.pose.theta_rad,
                              s.wheel.left_rad_s, s.wheel.right_rad_s, s.setpoint.left_rad_s, s.setpoint.right_rad_s,
                              static_cast<unsigned>(s.faults));
  line(buf, n);
}

void TruthLog::onCommand(double sim_t_s, uint8_t seq, const serial::WheelCommand& cmd) {
  char buf[128];
  const int n = std::snprintf(buf, sizeof buf, "C,%lld,%.3f,%u,%d,%d,%u\n", static_cast<long long>(monoNowNs()),
                              sim_t_s, static_cast<unsigned>(seq), static_cast<int>(cmd.left_mrad_s),
                              static_cast<int>(cmd.right_mrad_s), static_cast<unsigned>(cmd.flags));
  line(buf, n);
}

void TruthLog::onEvent(double sim_t_s, std::string_view event, std::string_view detail) {
  std::string s = "E," + std::to_string(monoNowNs()) + ",";
  char t[32];
  std::snprintf(t, sizeof t, "%.3f", sim_t_s);
  s += t;
  s += ',';
  s += event;
  s += ',';
  for (char c : detail) s += (c == ',' || c == '\n') ? ';' : c;  // keep one CSV record per line
  s += '\n';
  line(s.data(), static_cast<int>(s.size()));
}

void TruthLog::onPedestrian(const PedestrianSample& s) {
  // ids are checked at load to hold no comma; the length cap only guards the buffer.
  char buf[256];
  const int id_len = static_cast<int>(std::min<std::size_t>(s.id.size(), 64));
  const int n = std::snprintf(buf, sizeof buf, "P,%lld,%.3f,%.*s,%.4f,%.4f,%.4f,%.4f,%.4f\n",
                              static_cast<long long>(monoNowNs()), s.sim_t_s, id_len, s.id.data(), s.x_m, s.y_m,
                              s.vx_m_s, s.vy_m_s, s.robot_distance_m);
  line(buf, n);
}

void TruthLog::onGas(const GasSample& s) {
  char buf[64];
  std::string row = "G," + std::to_string(monoNowNs());
  std::snprintf(buf, sizeof buf, ",%.3f,%.4f,%.4f", s.sim_t_s, s.inlet_x_m, s.inlet_y_m);
  row += buf;
  for (const auto values : {s.true_value, s.reading}) {
    for (double v : values) {
      if (std::isnan(v)) {
        row += ",NaN";
      } else {
        std::snprintf(buf, sizeof buf, ",%.4f", v);
        row += buf;
      }
    }
  }
  row += '\n';
  line(row.data(), static_cast<int>(row.size()));
}

void TruthLog::comment(std::string_view text) {
  std::string s = "# ";
  s += text;
  s += '\n';
  line(s.data(), static_cast<int>(s.size()));
}

}  // namespace inspect::sim
