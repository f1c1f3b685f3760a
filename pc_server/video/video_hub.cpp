#include "pc_server/video/video_hub.hpp"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include <opencv2/highgui.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "shared/util/startup_error.hpp"
#include "shared/util/clock.hpp"
#include "shared/util/file_util.hpp"
#include "shared/util/log.hpp"
#include "shared/video/sdp.hpp"
#include "pc_server/video/video_streams.hpp"

namespace inspect::server {

namespace asio = boost::asio;

namespace {
constexpr std::size_t kOffsetSamples = 250;  // 5 s of telemetry at 50 Hz

std::string hostOf(const std::string& address) {
  const auto colon = address.rfind(':');
  std::string host = colon == std::string::npos ? address : address.substr(0, colon);
  if (host.size() > 2 && host.front() == '[') host = host.substr(1, host.size() - 2);
  return host;
}

/// PNG via a temporary name and rename, so readers never see half a file.
bool writePng(const std::string& path, const cv::Mat& bgr) {
  const std::string tmp = path + ".tmp.png";
  if (!cv::imwrite(tmp, bgr, {cv::IMWRITE_PNG_COMPRESSION, 1})) return false;
  return std::rename(tmp.c_str(), path.c_str()) == 0;
}
}  // namespace

VideoHub::VideoHub(const VideoServerConfig& config, const std::string& link_bind, CommandSink& sink)
    : config_(config), sink_(sink), fwd_socket_(fwd_io_), next_forward_port_(config.forward_base_port) {
  video::ReceiverSettings rs;
  rs.bind = config.bind.empty() ? link_bind : config.bind;
  rs.port = config.port;
  rs.reorder_window = config.reorder_window;
  rs.keyframe_min_interval_s = config.keyframe_min_interval_s;
  try {
    receiver_ = std::make_unique<video::VideoReceiver>(rs);
  } catch (const video::VideoError& e) {
    throw util::StartupError(e.what());
  }
  std::error_code fec;
  std::filesystem::create_directories(config.dir, fec);
  if (fec) throw util::StartupError("video.dir: cannot create '" + config.dir + "': " + fec.message());
  if (config.forward_base_port) {
    boost::system::error_code ec;
    fwd_socket_.open(asio::ip::udp::v4(), ec);
    if (ec) throw util::StartupError("video: cannot open the forwarding socket: " + ec.message());
  }
  receiver_->setKeyframeRequest([this](const std::string& stream) {
    const StreamRef ref = parseStreamName(stream);
    v1::Command c;
    c.mutable_video()->set_keyframe(true);
    c.mutable_video()->set_head(ref.head);
    sink_.sendCommand(ref.robot, c);
  });
  receiver_->setFrameHook([this](const std::string& robot, const cv::Mat& bgr, uint64_t capture_us) {
    onFrame(robot, bgr, capture_us);
  });
  if (config.forward_base_port)
    receiver_->setPacketHook([this](const std::string& robot, const std::vector<uint8_t>& d) { forward(robot, d); });
}

VideoHub::~VideoHub() { stop(); }

uint16_t VideoHub::port() const { return receiver_->port(); }

void VideoHub::start() {
  receiver_->start();
  const bool display = std::getenv("DISPLAY") != nullptr;
  if (config_.window == "on" || (config_.window == "auto" && display)) {
    window_running_ = true;
    window_thread_ = std::thread([this] { windowLoop(); });
  }
}

void VideoHub::stop() {
  stopping_ = true;
  if (window_thread_.joinable()) window_thread_.join();
  receiver_->stop();
}

void VideoHub::onTelemetry(const std::string& robot_id, const std::string& address, const v1::Envelope& env,
                           uint64_t recv_us) {
  const auto& t = env.telemetry();
  const bool ptz = t.has_video() && t.video().ssrc() != 0, wide = t.has_wide_video() && t.wide_video().ssrc() != 0;
  if (!ptz && !wide) return;
  std::lock_guard lk(mu_);
  // Clock offset: the smallest (receive - send) of recent messages is the
  // offset plus the shortest one-way delay (tens of µs on loopback).
  auto& offsets = offsets_[robot_id];
  offsets.push_back(static_cast<int64_t>(recv_us) - static_cast<int64_t>(env.send_time_us()));
  if (offsets.size() > kOffsetSamples) offsets.pop_front();
  int64_t offset = offsets.front();
  for (auto o : offsets) offset = std::min(offset, o);
  const std::string ip = hostOf(address);
  if (ptz) followStream(streamName(robot_id, v1::PTZ_HEAD), t.video().ssrc(), ip, offset);
  if (wide) followStream(streamName(robot_id, v1::WIDE_HEAD), t.wide_video().ssrc(), ip, offset);
}

void VideoHub::followStream(const std::string& name, uint32_t ssrc, const std::string& ip, int64_t offset) {
  Stream& r = streams_[name];
  const bool changed = r.ssrc != ssrc || r.source_ip != ip;
  if (changed) {
    r.ssrc = ssrc;
    r.source_ip = ip;
    r.offset_us = offset;
    boost::system::error_code ec;
    const auto addr = asio::ip::make_address(ip, ec);
    receiver_->setStream(name, r.ssrc, ec ? asio::ip::address() : addr, offset);
    if (r.sdp_path.empty()) {
      if (config_.forward_base_port) r.forward_port = next_forward_port_++;
      r.sdp_path = config_.dir + "/" + streamFileStem(name) + ".sdp";
      writeSdp(name, r, false);
    }
    log::info(log::tag::kVideo, name, ": stream SSRC ", r.ssrc, " from ", ip,
              r.forward_port ? ", forwarded to 127.0.0.1:" + std::to_string(r.forward_port) : std::string(),
              "; play with: ", ffplayCommand(r.sdp_path));
  } else if (std::abs(offset - r.offset_us) > 200) {
    r.offset_us = offset;
    receiver_->setClockOffset(name, offset);
  }
}

void VideoHub::writeSdp(const std::string& name, Stream& r, bool with_params) {
  const StreamRef ref = parseStreamName(name);
  video::SdpParams p;
  p.session_name = ref.robot + (ref.head == v1::WIDE_HEAD ? " wide camera" : " camera");
  p.address = "127.0.0.1";
  p.port = r.forward_port;
  if (with_params && receiver_->parameterSets(name, p.sps, p.pps)) r.sdp_has_params = true;
  if (const auto why = writeFileAtomically(r.sdp_path, video::makeSdp(p)); !why.empty())
    log::warn(log::tag::kVideo, name, ": SDP: ", why);
}

void VideoHub::forward(const std::string& stream, const std::vector<uint8_t>& datagram) {
  uint16_t port = 0;
  {
    std::lock_guard lk(mu_);
    auto it = streams_.find(stream);
    if (it != streams_.end()) port = it->second.forward_port;
  }
  if (!port) return;
  boost::system::error_code ec;  // nobody listening is fine
  fwd_socket_.send_to(asio::buffer(datagram), asio::ip::udp::endpoint(asio::ip::address_v4::loopback(), port), 0, ec);
}

void VideoHub::onFrame(const std::string& stream, const cv::Mat& bgr, uint64_t) {
  std::string latest;
  {
    std::lock_guard lk(mu_);
    auto it = streams_.find(stream);
    if (it == streams_.end()) return;
    Stream& r = it->second;
    if (!r.sdp_has_params) writeSdp(stream, r, true);
    const auto now = static_cast<int64_t>(monoNowUs());
    if (!window_running_ && config_.snapshot_period_s > 0 &&
        now - r.last_snapshot_us >= static_cast<int64_t>(config_.snapshot_period_s * 1e6)) {
      r.last_snapshot_us = now;
      latest = config_.dir + "/" + streamFileStem(stream) + "_latest.png";
    }
  }
  if (!latest.empty() && !writePng(latest, bgr)) log::warn(log::tag::kVideo, stream, ": cannot write ", latest);
}

std::optional<video::StreamStats> VideoHub::stats(const std::string& stream) const {
  return receiver_->stats(stream);
}

video::ReceiverCounters VideoHub::counters() const { return receiver_->counters(); }

std::string VideoHub::snapshot(const std::string& stream, const std::string& path) {
  cv::Mat bgr;
  if (!receiver_->latestFrame(stream, bgr)) throw std::runtime_error("no picture decoded from " + stream + " yet");
  std::string out = path;
  if (out.empty()) {
    std::lock_guard lk(mu_);
    out = config_.dir + "/" + streamFileStem(stream) + "_" + std::to_string(++streams_[stream].snapshot_count) + ".png";
  }
  if (out.size() < 4 || out.substr(out.size() - 4) != ".png") out += ".png";
  if (!writePng(out, bgr)) throw std::runtime_error("cannot write '" + out + "'");
  return out;
}

std::string VideoHub::sdpPath(const std::string& stream) const {
  std::lock_guard lk(mu_);
  auto it = streams_.find(stream);
  return it == streams_.end() ? std::string() : it->second.sdp_path;
}

uint16_t VideoHub::forwardPort(const std::string& stream) const {
  std::lock_guard lk(mu_);
  auto it = streams_.find(stream);
  return it == streams_.end() ? 0 : it->second.forward_port;
}

void VideoHub::windowLoop() {
  std::map<std::string, uint64_t> shown;  // stream -> capture time of the picture on screen
  try {
    while (!stopping_) {
      std::vector<std::string> ids;
      {
        std::lock_guard lk(mu_);
        for (const auto& [id, r] : streams_) ids.push_back(id);
      }
      for (const auto& id : ids) {
        cv::Mat bgr;
        uint64_t capture_us = 0;
        if (!receiver_->latestFrame(id, bgr, &capture_us) || shown[id] == capture_us) continue;
        shown[id] = capture_us;
        cv::Mat view = bgr.clone();
        if (auto st = receiver_->stats(id)) {
          char text[160];
          std::snprintf(text, sizeof text, "%s  %.0f fps  %.0f kbit/s  loss %.1f%%  latency %.0f ms", id.c_str(),
                        st->fps_decoded, st->kbps, st->loss_pct, st->latency_ms);
          cv::putText(view, text, {8, view.rows - 10}, cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 255, 255}, 1, cv::LINE_AA);
        }
        cv::imshow(id + " camera", view);
      }
      cv::waitKey(15);
    }
    cv::destroyAllWindows();
  } catch (const cv::Exception& e) {
    log::warn(log::tag::kVideo, "no video window (", e.what(), "): PNG snapshots instead");
  }
  window_running_ = false;
}

}  // namespace inspect::server
