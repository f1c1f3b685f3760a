#include "robot_client/robot_app.hpp"

#include "shared/net/gains_proto.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <cmath>

#include "shared/config/config_node.hpp"
#include "shared/util/clock.hpp"
#include "shared/util/log.hpp"

namespace inspect::client {

namespace asio = boost::asio;
using std::chrono::steady_clock;

namespace {
video::SenderSettings senderSettings(const ClientConfig& cfg) {
  const VideoParams& v = cfg.video;
  video::SenderSettings s;
  s.enabled = v.enabled;
  s.source.uri = v.source;
  s.source.width = v.width;
  s.source.height = v.height;
  s.source.fps = v.fps;
  s.source.pixel_format = v.pixel_format;
  s.encoder.codec = v.encoder;
  s.encoder.preset = v.preset;
  s.encoder.bitrate_kbps = v.bitrate_kbps;
  s.encoder.gop = v.gop;
  s.encoder.intra_refresh = v.intra_refresh;
  s.host = v.host.empty() ? cfg.server_host : v.host;
  s.port = static_cast<uint16_t>(v.port);
  s.mtu = static_cast<std::size_t>(v.mtu);
  s.retransmission = v.retransmission;
  s.history_packets = static_cast<std::size_t>(v.history_packets);
  s.history_s = v.history_s;
  s.adapt.enabled = v.adapt;
  s.adapt.min_kbps = v.adapt_min_kbps;
  s.adapt.max_kbps = v.adapt_max_kbps;
  return s;
}

WatcherSettings watcherSettings(const DetectionParams& p, const config::CameraMount& mount) {
  WatcherSettings w;
  if (!perception::parseDetectorMethod(p.detector, w.detector.method))
    throw std::invalid_argument("perception.detector: '" + p.detector + "' is not known");
  w.detector.hit_threshold = p.hit_threshold;
  w.detector.group_threshold = p.group_threshold;
  w.detector.floor_band = p.floor_band;
  w.width = p.width;
  w.height = p.height;
  w.rate_hz = p.rate_hz;
  w.max_core_share = p.max_core_share;
  w.mount = mount;
  return w;
}

v1::Ack ack(uint64_t id, v1::Ack::Status status, const std::string& reason = {}) {
  v1::Ack a;
  a.set_command_id(id);
  a.set_status(status);
  a.set_reason(reason);
  return a;
}

// What a look aside at track `id` found, as its track now says.
const char* lookOutcome(const std::vector<behavior::HumanTrack>& tracks, int id) {
  const auto it = std::find_if(tracks.begin(), tracks.end(), [&](const auto& t) { return t.id == id; });
  if (it == tracks.end()) return "the track is gone";
  if (it->camera_hits > 0) return "a person found there";
  if (it->camera_denied || it->camera_doubted) return "nobody seen there: not a person";
  return "the dwell is over or someone is ahead";
}

}  // namespace

RobotApp::RobotApp(asio::io_context& io, const ClientConfig& cfg, const config::RobotConfig& robot,
                   const config::ControlConfig& control, std::shared_ptr<control::FuzzyGainScheduler> scheduler,
                   const std::string& cmd_log_path)
    : io_(io), cfg_(cfg), core_(robot, cfg.safety, control, std::move(scheduler)),
      serial_(io, cfg.serial_device, cfg.baud, cfg.serial_reopen_period_s), link_(io, cfg),
      outbox_(cfg.events.journal, static_cast<std::size_t>(cfg.events.max_pending), cfg.events.sync_period_s),
      tick_timer_(io), telemetry_timer_(io), mcu_hb_timer_(io), t0_ns_(monoNowNs()) {
  core_.setFisName(std::filesystem::path(control.fis_path).stem().string());
  for (const auto& s : outbox_.skippedRecords()) log::warn("events", "journal ", cfg.events.journal, ": ", s);
  if (cfg.events.journal.empty())
    log::info("events", "no journal (events.journal \"\"): events of an outage are kept in memory only");
  else if (!outbox_.hasJournal())
    log::error("events", "journal: ", outbox_.journalError(), ": events of an outage are kept in memory only");
  else
    log::info("events", "journal ", cfg.events.journal, ": stream ", outbox_.stream(), ", ",
              outbox_.counters().loaded, " entries pending from before");
  if (!cmd_log_path.empty()) {
    cmd_log_ = std::fopen(cmd_log_path.c_str(), "w");
    if (!cmd_log_) throw config::ConfigError("--cmd-log: cannot write " + cmd_log_path);
    std::setvbuf(cmd_log_, nullptr, _IOLBF, 0);  // readers see every command at once
    std::fprintf(cmd_log_, "# seq,left_mrad_s,right_mrad_s,flags\n");
  }
  try {
    video_ = std::make_unique<video::VideoSender>(senderSettings(cfg));
  } catch (const video::VideoError& e) {
    log::error("video", e.what(), ": no video stream");
  }
  camera_mount_ = robot.camera;
  if (video_ && cfg.perception.enabled && showsPeople(cfg.video.source)) {
    try {
      watcher_ = std::make_unique<PeopleWatcher>(watcherSettings(cfg.perception, robot.camera));
      video_->setPictureTap([w = watcher_.get()](const cv::Mat& bgr, uint64_t us) { w->offer(bgr, us); });
      log::info("perception", "people detector ", watcher_->stats().detector, " at ", cfg.perception.width, "x",
                cfg.perception.height, ", at most ", cfg.perception.rate_hz, " Hz and ",
                cfg.perception.max_core_share * 100, " % of a core");
    } catch (const std::exception& e) {
      log::error("perception", e.what(), ": people are seen by the sonars only");
      watcher_.reset();
    }
  } else if (cfg.perception.enabled && video_) {
    log::info("perception", "video source ", cfg.video.source, " shows no people: no detection (sonars only)");
  }
  openWideHead(robot);
}

void RobotApp::openWideHead(const config::RobotConfig& robot) {
  const WideHeadParams& w = cfg_.wide_head;
  if (w.source.empty()) return;
  if (!cfg_.perception.enabled) {
    log::info("perception", "wide head: perception.enabled is false: not used");
    return;
  }
  if (!robot.wide_camera) {
    log::error("perception", "wide_head.source is ", w.source,
               " but the robot config has no wide_camera (its mount and field of view): no wide head");
    return;
  }
  wide_mount_ = *robot.wide_camera;
  // Streamed: video:'s encoder and destination, its own source, bitrate and SSRC (docs/video.md).
  video::SenderSettings s = senderSettings(cfg_);
  s.enabled = true;
  s.stream = w.stream;
  s.encoder.bitrate_kbps = w.bitrate_kbps;
  s.adapt.max_kbps = 0;
  s.thread_prefix = "wide";
  s.source.uri = w.source;
  s.source.width = w.width;
  s.source.height = w.height;
  s.source.fps = w.fps;
  s.source.pixel_format = w.pixel_format;
  try {
    wide_video_ = std::make_unique<video::VideoSender>(s);
    WatcherSettings ws = watcherSettings(w, wide_mount_);
    ws.thread_name = "wide-detect";
    wide_watcher_ = std::make_unique<PeopleWatcher>(ws);
    wide_video_->setPictureTap([p = wide_watcher_.get()](const cv::Mat& bgr, uint64_t us) { p->offer(bgr, us); });
    log::info("perception", "wide head ", w.source, " (", wide_mount_.hfov_deg, " deg): people detector ",
              wide_watcher_->stats().detector, " at ", w.width, "x", w.height, ", at most ", w.rate_hz, " Hz and ",
              w.max_core_share * 100, " % of a core",
              w.stream ? "; streamed at " + std::to_string(w.bitrate_kbps) + " kbit/s" : std::string("; not streamed"));
  } catch (const std::exception& e) {
    log::error("perception", "wide head: ", e.what(), ": not used");
    wide_watcher_.reset();
    wide_video_.reset();
  }
}

RobotApp::~RobotApp() {
  if (cmd_log_) std::fclose(cmd_log_);
}

double RobotApp::now() const { return static_cast<double>(monoNowNs() - t0_ns_) * 1e-9; }

void RobotApp::start() {
  link_.setGasChannels(core_.gasChannels(), core_.gasMonitor().config().inlet_x_m,
                       core_.gasMonitor().config().inlet_y_m);
  // Each Hello (also after a reconnect) announces the gains in force then.
  link_.setHelloFiller([this](v1::Hello& h) {
    h.set_wall_time_us(static_cast<uint64_t>(wallNowNs() / 1000));
    h.set_event_stream(outbox_.stream());
    net::toProto(core_.gains(), *h.mutable_gains());
    h.set_gains_version(core_.gainsVersion());
    h.set_fis_name(core_.fisName());
  });
  serial_.start([this](const serial::Message& m, uint8_t) { onSerialMessage(m); },
                [this](bool open, const std::string&) {
                  core_.onSerialState(open, now());
                  flushEvents();
                });
  link_.start({[this] {
                 // What the server has not filed yet goes first, in order (replayed), then what happens now.
                 outbox_.linkUp();
                 core_.onLinkUp(now());
                 flushEvents();
               },
               [this](const std::string& why) {
                 outbox_.linkDown();
                 core_.onLinkDown(now(), why);
                 // Stop at once rather than waiting for the next sensor frame.
                 sendWheels(core_.commandNow());
                 flushEvents();
               },
               [this](const v1::Envelope& env) { onServerMessage(env); }});
  tick10ms();
  sendTelemetry();
  mcuHeartbeat();
  if (watcher_) watcher_->start();
  if (video_) video_->start();
  if (wide_watcher_) wide_watcher_->start();
  if (wide_video_) wide_video_->start();
}

void RobotApp::stop() {
  tick_timer_.cancel();
  telemetry_timer_.cancel();
  mcu_hb_timer_.cancel();
  if (video_) video_->stop();
  if (watcher_) watcher_->stop();
  if (wide_video_) wide_video_->stop();
  if (wide_watcher_) wide_watcher_->stop();
  // Leave the motors commanded to zero before going.
  if (serial_.isOpen()) sendWheels(serial::WheelCommand{});
  link_.stop();
  logLoopFigures();
}

void RobotApp::logLoopFigures() {
  log::info("loop", "sensor frame in -> wheel command out: ", frame_to_command_.summary("frames"));
  frame_to_command_ = util::LatencyHistogram{};
}

void RobotApp::sendWheels(const serial::WheelCommand& c) {
  if (!serial_.isOpen()) return;
  const uint8_t seq = serial_.send(c);
  if (cmd_log_) std::fprintf(cmd_log_, "%u,%d,%d,%u\n", seq, c.left_mrad_s, c.right_mrad_s, c.flags);
}

void RobotApp::onSerialMessage(const serial::Message& m) {
  if (const auto* f = std::get_if<serial::SensorFrame>(&m)) {
    sendWheels(core_.onSensorFrame(*f, now()));
    frame_to_command_.record(monoNowNs() - serial_.lastReadNs());
    feedCamera();
    flushEvents();
  }
  // Messages meant for the MCU (echoes on a loop-back) are ignored.
}

void RobotApp::onServerMessage(const v1::Envelope& env) {
  switch (env.body_case()) {
    case v1::Envelope::kHeartbeat: core_.onLinkActivity(now()); break;
    case v1::Envelope::kDelivered: outbox_.delivered(env.delivered().event_stream(), env.delivered().up_to_seq()); break;
    case v1::Envelope::kCommand: {
      v1::Envelope reply;
      if (env.command().has_video() || env.command().has_ptz()) {
        // Camera commands do not touch the motion state.
        *reply.mutable_ack() = env.command().has_video() ? onVideoCommand(env.command()) : onPtzCommand(env.command());
        link_.send(reply);
        break;
      }
      *reply.mutable_ack() = core_.onCommand(env.command(), now());
      link_.send(reply);
      // A stop takes effect now, not at the next sensor frame.
      if (core_.mode() != v1::TELEOP && serial_.isOpen()) sendWheels(core_.commandNow());
      break;
    }
    default: log::debug("link", "ignoring message type ", static_cast<int>(env.body_case()));
  }
  flushEvents();
}

v1::Ack RobotApp::onVideoCommand(const v1::Command& cmd) {
  const auto& v = cmd.video();
  const bool wide = v.head() == v1::WIDE_HEAD;
  video::VideoSender* const sender = wide ? wide_video_.get() : video_.get();
  if (wide && (!sender || !cfg_.wide_head.stream))
    return ack(cmd.id(), v1::Ack::REJECTED, "video: this robot does not stream a wide head (wide_head.stream)");
  if (!sender) return ack(cmd.id(), v1::Ack::REJECTED, "video: this robot has no video stream (see its log)");
  video::SenderChange c;
  if (v.has_enabled()) c.enabled = v.enabled();
  if (v.width() || v.height()) {
    c.width = static_cast<int>(v.width());
    c.height = static_cast<int>(v.height());
  }
  if (v.fps() != 0) c.fps = v.fps();
  if (v.bitrate_kbps()) c.bitrate_kbps = static_cast<int>(v.bitrate_kbps());
  if (const auto why = sender->apply(c); !why.empty()) return ack(cmd.id(), v1::Ack::REJECTED, why);
  if (v.keyframe()) sender->requestKeyframe();
  return ack(cmd.id(), v1::Ack::ACCEPTED);
}

v1::Ack RobotApp::onPtzCommand(const v1::Command& cmd) {
  abandonLookAside("the operator moved the camera");
  if (const std::string why = sendPtz(cmd.ptz()); !why.empty()) return ack(cmd.id(), v1::Ack::REJECTED, why);
  // The operator points the camera: the look-ahead yields until nobody is near.
  if (looking_ahead_) {
    looking_ahead_ = false;
    look_ahead_yielded_ = true;
    log::info("perception", "the operator moved the camera: looking ahead for people yields");
  }
  return ack(cmd.id(), v1::Ack::ACCEPTED);
}

std::string RobotApp::applyPtz(const v1::Ptz& p) {
  // A route's camera preset while the camera looks ahead for people: given back afterwards.
  if (looking_ahead_) {
    ptz_before_look_ = p;
    return "";
  }
  abandonLookAside("a route's camera preset");
  return sendPtz(p);
}

std::string RobotApp::sendPtz(const v1::Ptz& p) {
  if (!std::isfinite(p.pan_rad()) || !std::isfinite(p.tilt_rad()) || std::abs(p.pan_rad()) > M_PI ||
      std::abs(p.tilt_rad()) > M_PI / 2)
    return "ptz: pan must be within [-pi, pi] and tilt within [-pi/2, pi/2] rad";
  if (!serial_.isOpen()) return "ptz: the MCU's serial line is down";
  serial::PtzCommand c;
  if (p.home()) {
    c.flags = 0x01;
    ptz_pan_rad_ = ptz_tilt_rad_ = 0;
  } else {
    c.pan_0p1mrad = static_cast<int16_t>(std::lround(p.pan_rad() * 1e4));
    c.tilt_0p1mrad = static_cast<int16_t>(std::lround(p.tilt_rad() * 1e4));
    ptz_pan_rad_ = p.pan_rad();
    ptz_tilt_rad_ = p.tilt_rad();
  }
  serial_.send(c);
  if (watcher_) watcher_->setPtz(ptz_pan_rad_, ptz_tilt_rad_);
  return "";
}

void RobotApp::lookAhead(double now_s) {
  if (!watcher_ || !cfg_.perception.look_ahead) return;
  const auto near = core_.nearestPersonM();
  const auto tw = core_.commandedTwist();
  const bool moving = std::abs(tw.v_m_s) > 0.02 || std::abs(tw.w_rad_s) > 0.1;
  const bool want = near && *near <= cfg_.perception.look_ahead_within_m && moving;
  if (want) look_last_s_ = now_s;
  const bool held = now_s - look_last_s_ <= cfg_.perception.look_ahead_hold_s;
  if (!held) look_ahead_yielded_ = false;
  const bool ahead = std::abs(ptz_pan_rad_) <= cfg_.perception.ahead_deg * M_PI / 180 && std::abs(ptz_tilt_rad_) < 0.1;
  if (want && !looking_ahead_ && !look_ahead_yielded_ && !ahead) {
    ptz_before_look_.Clear();  // a look aside is not given back: level ahead is
    if (!looking_aside_) {
      ptz_before_look_.set_pan_rad(ptz_pan_rad_);
      ptz_before_look_.set_tilt_rad(ptz_tilt_rad_);
    }
    abandonLookAside("a person near while moving");
    v1::Ptz level;  // straight ahead, level
    if (sendPtz(level).empty()) {
      looking_ahead_ = true;
      log::info("perception", "a person ", *near, " m away while moving: the camera looks ahead");
    }
  } else if (looking_ahead_ && !held) {
    looking_ahead_ = false;
    if (const auto why = sendPtz(ptz_before_look_); !why.empty())
      log::warn("perception", "giving the camera back: ", why);
    else
      log::info("perception", "nobody near: the camera goes back to pan ", ptz_before_look_.pan_rad(), " tilt ",
                ptz_before_look_.tilt_rad(), " rad");
  }
}

void RobotApp::lookAside(double now_s) {
  const behavior::HumanAwareness* aw = core_.awareness();
  if (!watcher_ || !aw || !aw->config().active_look.enabled || looking_ahead_) return;
  const bool level = std::abs(ptz_pan_rad_) < 1e-3 && std::abs(ptz_tilt_rad_) < 1e-3;
  if (!looking_aside_ && !level) return;  // someone else's set-point
  const int before = aside_.target_id;
  const double settled_before = aside_.settled_s;
  const double pan = behavior::activeLookPan(aside_, aw->config().active_look, aw->tracker().tracks(), core_.pose(),
                                             camera_mount_.x_m, camera_mount_.y_m, camera_mount_.hfov_deg * M_PI / 360.0,
                                             aw->config().tracker.camera.recall, now_s);
  if (aside_.settled_s != settled_before)  // a turn began: its pictures are blurred
    aside_settled_us_ = monoNowUs() + static_cast<uint64_t>(std::max(0.0, aside_.settled_s - now_s) * 1e6);
  if (std::abs(pan - ptz_pan_rad_) > 1e-3) {
    v1::Ptz p;
    p.set_pan_rad(pan);
    if (const auto why = sendPtz(p); !why.empty()) {
      log::warn("perception", "active looking: ", why);
      return;
    }
  }
  looking_aside_ = aside_.target_id >= 0 || std::abs(ptz_pan_rad_) > 1e-3;
  if (aside_.target_id >= 0 && aside_.target_id != before)
    log::info("perception", "nobody ahead: the camera looks aside at sonar track ", aside_.target_id, ", pan ", pan,
              " rad");
  else if (aside_.target_id < 0 && before >= 0)
    log::info("perception", "the look aside at track ", before, " is over (", lookOutcome(aw->tracker().tracks(), before),
              "): the camera goes back ahead");
}

void RobotApp::abandonLookAside(const char* why) {
  if (!looking_aside_) return;
  log::info("perception", why, ": the look aside at track ", aside_.target_id, " ends");
  aside_.target_id = -1;
  aside_.pan_rad = 0.0;
  looking_aside_ = false;
}

void RobotApp::feedCamera() {
  if (watcher_) feedHead(*watcher_, camera_mount_, false, camera_fed_seq_);
  if (wide_watcher_) feedHead(*wide_watcher_, wide_mount_, true, wide_fed_seq_);
}

void RobotApp::feedHead(const PeopleWatcher& w, const config::CameraMount& mount, bool wide, uint64_t& fed) {
  if (w.latestSeq() == fed) return;
  const auto view = w.latest();
  if (!view) return;
  fed = view->seq;
  // Old pictures, and pictures of the floor or the ceiling, say nothing of
  // the people around now.
  if (monoNowUs() > view->capture_us + static_cast<uint64_t>(cfg_.perception.stale_s * 1e6)) return;
  if (std::abs(view->tilt_rad) > M_PI / 6) return;
  if (!wide && view->capture_us < aside_settled_us_) return;  // taken while the head turned
  behavior::CameraLook look;
  look.lens_x_m = mount.x_m;
  look.lens_y_m = mount.y_m;
  look.axis_rad = view->pan_rad;
  look.half_fov_rad = mount.hfov_deg * M_PI / 360.0;
  look.wide = wide;
  for (const auto& s : view->people) look.add({s.at.bearing_rad, s.at.range_m.value_or(-1.0)});
  core_.onCameraLook(look);
}

void RobotApp::fillPerception(v1::Telemetry& t) const {
  if (!watcher_) {
    t.clear_perception();
  } else {
    auto* p = t.mutable_perception();
    fillHead(*watcher_, *p);
    p->set_looking_ahead(looking_ahead_);
    p->set_looking_aside(looking_aside_);
    p->set_aside_looks(static_cast<uint32_t>(aside_.looks));
    p->set_aside_off_path_s(aside_.off_path_s);
    const bool ahead =
        std::abs(ptz_pan_rad_) <= cfg_.perception.ahead_deg * M_PI / 180 && std::abs(ptz_tilt_rad_) <= M_PI / 6;
    if (p->mode() == v1::CAMERA_AND_SONAR && !ahead) p->set_mode(v1::CAMERA_ELSEWHERE);
  }
  if (!wide_watcher_)
    t.clear_wide_perception();
  else
    fillHead(*wide_watcher_, *t.mutable_wide_perception());
}

void RobotApp::fillHead(const PeopleWatcher& w, v1::Perception& p) const {
  const WatcherStats st = w.stats();
  p.set_detector(st.detector);
  p.set_rate_hz(st.rate_hz);
  p.set_detect_ms(st.detect_ms);
  p.set_detections(st.detections);
  p.set_error(st.error);
  p.clear_people();
  const auto view = w.latest();
  const uint64_t now_us = monoNowUs();
  const bool fresh = view && now_us < view->capture_us + static_cast<uint64_t>(cfg_.perception.stale_s * 1e6);
  p.set_mode(fresh ? v1::CAMERA_AND_SONAR : v1::SONAR_ONLY);
  if (!view) return;
  p.set_capture_us(view->capture_us);
  p.set_width(static_cast<uint32_t>(view->width));
  p.set_height(static_cast<uint32_t>(view->height));
  p.set_pan_rad(view->pan_rad);
  p.set_tilt_rad(view->tilt_rad);
  if (!fresh) return;
  for (const auto& s : view->people) {
    auto* q = p.add_people();
    q->set_bearing_rad(s.at.bearing_rad);
    if (s.at.range_m) {
      q->set_range_m(*s.at.range_m);
      q->set_x_m(s.at.x_m);
      q->set_y_m(s.at.y_m);
    }
    q->set_score(s.box.score);
    q->set_box_x(static_cast<uint32_t>(s.box.box.x));
    q->set_box_y(static_cast<uint32_t>(s.box.box.y));
    q->set_box_w(static_cast<uint32_t>(s.box.box.width));
    q->set_box_h(static_cast<uint32_t>(s.box.box.height));
  }
}

void RobotApp::fillVideoStatus(v1::Telemetry& t) const {
  t.set_ptz_pan_rad(ptz_pan_rad_);
  t.set_ptz_tilt_rad(ptz_tilt_rad_);
  if (video_)
    fillStream(video_->stats(), *t.mutable_video());
  else
    t.clear_video();
  if (wide_video_ && cfg_.wide_head.stream)
    fillStream(wide_video_->stats(), *t.mutable_wide_video());
  else
    t.clear_wide_video();
}

void RobotApp::fillStream(const video::SenderStats& s, v1::VideoStatus& status) {
  auto* v = &status;
  v->set_enabled(s.enabled);
  v->set_ssrc(s.ssrc);
  v->set_width(static_cast<uint32_t>(s.width));
  v->set_height(static_cast<uint32_t>(s.height));
  v->set_fps(s.fps);
  v->set_bitrate_kbps(static_cast<uint32_t>(s.bitrate_kbps));
  v->set_encoder(s.encoder);
  v->set_source(s.source);
  v->set_frames_captured(s.captured);
  v->set_frames_encoded(s.encoded);
  v->set_frames_dropped(s.dropped);
  v->set_keyframes(s.keyframes);
  v->set_packets_sent(s.packets);
  v->set_bytes_sent(s.bytes);
  v->set_encode_ms(s.encode_ms);
  v->set_port(s.port);
  v->set_error(s.error);
  v->set_keyframe_requests(s.keyframe_requests);
  v->set_adapt(s.adapt);
  v->set_min_kbps(static_cast<uint32_t>(s.min_kbps));
  v->set_max_kbps(static_cast<uint32_t>(s.max_kbps));
  v->set_rate_kbps(static_cast<uint32_t>(s.rate_kbps));
  v->set_send_width(static_cast<uint32_t>(s.send_width));
  v->set_send_height(static_cast<uint32_t>(s.send_height));
  v->set_send_fps(s.send_fps);
  v->set_rate_level(static_cast<uint32_t>(s.rate_level));
  v->set_rate_reason(s.rate_reason);
  const uint64_t now_us = monoNowUs();
  v->set_rate_age_s(now_us > s.rate_changed_us ? static_cast<double>(now_us - s.rate_changed_us) / 1e6 : 0.0);
  v->set_rate_changes(s.rate_changes);
  v->set_peer_loss_pct(s.peer_loss_pct);
  v->set_rtt_ms(s.rtt_ms);
  v->set_nacked_packets(s.nacked_packets);
  v->set_retransmitted(s.retransmitted);
  v->set_repeat_nacks(s.repeat_nacks);
  v->set_not_in_history(s.not_in_history);
}

void RobotApp::pumpOutbox() {
  // In order, behind what a reconnect has to replay; at most half the link's
  // send queue at a time (telemetry and heartbeats keep their room), and at
  // most 800 a second (64 at once): well inside the server's per-robot
  // limits (2000 messages/s, docs/load.md), which would drop the excess.
  const std::size_t room = link_.queued() < 128 ? 128 - link_.queued() : 0;
  const double now_s = now();
  const auto budget = std::min(room, static_cast<std::size_t>(outbox_budget_.tokens(now_s)));
  const std::size_t sent = outbox_.sendNext([this](v1::Envelope& e) { link_.send(e); }, budget);
  if (sent) outbox_budget_.take(static_cast<double>(sent), now_s);
}

void RobotApp::fillOutboxStatus(v1::Telemetry& t) const {
  auto* o = t.mutable_outbox();
  const auto& c = outbox_.counters();
  o->set_pending(static_cast<uint32_t>(outbox_.pending()));
  o->set_max_pending(static_cast<uint32_t>(outbox_.maxPending()));
  o->set_stored(c.stored);
  o->set_delivered(c.delivered);
  o->set_dropped(c.dropped);
  o->set_replayed(c.replayed);
  o->set_loaded(c.loaded);
  o->set_skipped(c.skipped);
  o->set_journal_errors(c.journal_errors);
  o->set_journal(outbox_.hasJournal());
  o->set_journal_error(outbox_.journalError());
}

void RobotApp::flushEvents() {
  // Late acks (COMPLETED, FAILED of a run) are stored and forwarded like events.
  for (auto& a : core_.takeAcks()) {
    v1::Envelope env;
    *env.mutable_ack() = a;
    outbox_.store(env, wallNowNs() / 1000);
  }
  for (const auto& p : core_.takePtz()) {
    if (const std::string why = applyPtz(p); !why.empty()) log::warn("core", "inspection point camera preset: ", why);
  }
  core_.takeEvents(events_);
  for (auto& e : events_) {
    log::info("core", v1::Event::Kind_Name(e.kind), ": ", e.text);
    v1::Envelope env;
    auto* ev = env.mutable_event();
    ev->set_kind(e.kind);
    ev->set_text(e.text);
    if (e.gas_alarm) *ev->mutable_gas_alarm() = *e.gas_alarm;
    if (e.gains) {
      *ev->mutable_gains() = *e.gains;
      ev->set_gains_version(e.gains_version);
    }
    ev->set_robot_time_us(static_cast<uint64_t>(now() * 1e6));
    outbox_.store(env, wallNowNs() / 1000);
  }
  pumpOutbox();  // what was stored, in order behind anything a reconnect replays
}

void RobotApp::tick10ms() {
  if (auto c = core_.onTimer(now())) sendWheels(*c);
  flushEvents();  // and the outbox's next batch
  tick_timer_.expires_after(std::chrono::milliseconds(10));
  tick_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) tick10ms();
  });
}

void RobotApp::sendTelemetry() {
  lookAside(now());
  lookAhead(now());
  core_.setSerialCounters(serial_.rxCounters(), serial_.bytesTx(), serial_.framesTx());
  if (link_.isUp()) {
    core_.fillTelemetry(*telemetry_env_.mutable_telemetry(), now());
    fillVideoStatus(*telemetry_env_.mutable_telemetry());
    fillPerception(*telemetry_env_.mutable_telemetry());
    fillOutboxStatus(*telemetry_env_.mutable_telemetry());
    link_.send(telemetry_env_);
  }
  telemetry_timer_.expires_after(steadyDuration(1.0 / cfg_.telemetry_hz));
  telemetry_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) sendTelemetry();
  });
}

void RobotApp::mcuHeartbeat() {
  if (serial_.isOpen()) serial_.send(serial::Heartbeat{static_cast<uint32_t>(now() * 1000.0)});
  mcu_hb_timer_.expires_after(steadyDuration(cfg_.mcu_heartbeat_period_s));
  mcu_hb_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) mcuHeartbeat();
  });
}

}  // namespace inspect::client
