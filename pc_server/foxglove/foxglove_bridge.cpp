#include "pc_server/foxglove/foxglove_bridge.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include <nlohmann/json.hpp>

#include "pc_server/foxglove/bridge_services.hpp"
#include "pc_server/operator/route_file.hpp"
#include "pc_server/scene/topics.hpp"
#include "shared/config/config_node.hpp"
#include "shared/record/mcap_writer.hpp"
#include "shared/util/base64.hpp"
#include "shared/util/clock.hpp"
#include "shared/util/log.hpp"
#include "shared/util/number_text.hpp"

namespace inspect::server::foxglove {

namespace asio = boost::asio;
using SteadyClock = std::chrono::steady_clock;

namespace {
constexpr const char* kTag = "foxglove";
constexpr auto kDeadmanPeriod = std::chrono::milliseconds(50);
// A service call waiting for its robot's Ack looks again this often (an Ack takes 1-2 ms on a working link).
constexpr auto kCallPollPeriod = std::chrono::milliseconds(5);
constexpr auto kRefusalDebounce = std::chrono::seconds(1);
}  // namespace

std::vector<uint32_t> FoxgloveBridge::RobotChannels::all() const {
  std::vector<uint32_t> ids{telemetry, events, acks,  alarms,      camera,      camera_people,
                            tf,        scene,  log,   video_stats, camera_wide, camera_wide_people};
  for (const auto& [name, id] : grids) ids.push_back(id);
  std::erase(ids, 0u);
  return ids;
}

FoxgloveBridge::FoxgloveBridge(asio::io_context& ioc, Options options, RobotRegistry& registry, CommandSink& sink,
                               ControlArbiter& control, scene::SiteMaps& maps, scene::Geometry geometry,
                               Console::Options console_options, ClientOperator::Configure configure)
    : ioc_(ioc), options_(std::move(options)), registry_(registry), sink_(sink), control_(control), maps_(maps),
      geometry_(geometry), console_options_(console_options), configure_(std::move(configure)),
      server_(ioc, options_.server, *this), tick_timer_(ioc), deadman_timer_(ioc),
      service_(registry, sink, &control,
               OperatorService::Options{console_options.ack_timeout_s, options_.max_v_m_s, options_.max_w_rad_s}) {
  service_.setRunContext(options_.recorder, &maps_);
  for (const auto& d : serviceDefs()) service_ids_[d.name] = server_.addService(toService(d));
}

FoxgloveBridge::~FoxgloveBridge() { stop(); }

asio::ip::tcp::endpoint FoxgloveBridge::start() {
  const auto ep = server_.listen();
  tick();
  deadman();
  return ep;
}

void FoxgloveBridge::stop() {
  std::map<uint64_t, Client> clients;
  {
    std::lock_guard lk(mu_);
    if (stopped_) return;
    stopped_ = true;
    clients.swap(clients_);
    for (auto& weak : call_timers_)
      if (const auto t = weak.lock()) t->cancel();  // their handlers then return without answering
    call_timers_.clear();
  }
  // The timers see stopped_ at their next expiry and end their chains.
  server_.stop();
  for (auto& [id, c] : clients) {
    if (!c.teleop_robot.empty() && c.op) stopIfHeld(c.teleop_robot, c.op->session());
    if (c.op) c.op->end();
  }
  clients.clear();
  // Lines still running return at once (their sessions ended); then the sessions close.
  console_pool_.join();
}

uint32_t FoxgloveBridge::addChannel(const std::string& topic, const google::protobuf::Descriptor* d,
                                    WsServer::Kind kind) {
  auto it = schemas_.find(d->full_name());
  if (it == schemas_.end())
    it = schemas_.emplace(d->full_name(), util::base64(record::protobufFileDescriptorSet(d))).first;
  Channel c;
  c.topic = topic;
  c.encoding = "protobuf";
  c.schema_name = d->full_name();
  c.schema = it->second;
  c.schema_encoding = "protobuf";
  return server_.addChannel(std::move(c), kind);
}

void FoxgloveBridge::publishMessage(uint32_t channel, uint64_t ns, const google::protobuf::Message& m) {
  if (channel == 0 || !server_.subscribed(channel)) return;
  server_.publish(channel, ns, std::make_shared<const std::string>(m.SerializeAsString()));
}

uint32_t FoxgloveBridge::addTopic(const std::string& robot, scene::TopicKind kind) {
  // The topic table's live topics (pc_server/scene/topics: the names the recorder writes too).
  const auto& d = scene::topicDef(kind);
  return addChannel(scene::topicName(robot, kind), d.type(), d.video ? WsServer::Kind::kVideo : WsServer::Kind::kData);
}

void FoxgloveBridge::advertiseRobot(const std::string& robot, RobotState& r) {
  using scene::TopicKind;
  auto& c = r.ch;
  const auto add = [&](TopicKind kind) { return addTopic(robot, kind); };
  c.telemetry = add(TopicKind::kTelemetry);
  c.events = add(TopicKind::kEvents);
  c.acks = add(TopicKind::kAcks);
  c.alarms = add(TopicKind::kAlarms);
  c.camera = add(TopicKind::kCamera);
  c.camera_people = add(TopicKind::kCameraPeople);
  c.tf = add(TopicKind::kTf);
  c.scene = add(TopicKind::kScene);
  c.log = add(TopicKind::kLog);
  c.video_stats = add(TopicKind::kVideoStats);
  r.connected = true;
  log::info(kTag, robot, ": channels advertised");
}

void FoxgloveBridge::advertiseWideHead(const std::string& robot, RobotState& r) {
  r.ch.camera_wide = addTopic(robot, scene::TopicKind::kCameraWide);
  r.ch.camera_wide_people = addTopic(robot, scene::TopicKind::kCameraWidePeople);
  log::info(kTag, robot, ": the wide head's channels advertised");
}

void FoxgloveBridge::unadvertiseRobot(RobotState& r) {
  for (const uint32_t id : r.ch.all()) server_.removeChannel(id);
  r.ch = {};
  r.connected = false;
}

void FoxgloveBridge::onEnvelope(const std::string& robot, const v1::Envelope& env, bool inbound, uint64_t time_us) {
  const uint64_t ns = monoUsToWallNs(time_us);
  std::lock_guard lk(mu_);
  if (stopped_) return;
  auto [it, fresh] = robots_.try_emplace(robot);
  RobotState& r = it->second;
  if (!r.feed) r.feed = std::make_unique<scene::SceneFeed>(robot, geometry_);
  if (!r.connected) {
    // A (re)connected robot: its Hello (gas channels, inlet) as the registry has it.
    if (const auto snap = registry_.snapshot(robot, monoNowNs())) r.feed->onHello(snap->hello);
    advertiseRobot(robot, r);
  }
  r.feed->onEnvelope(env, inbound);
  if (!inbound) return;
  switch (env.body_case()) {
    case v1::Envelope::kTelemetry: {
      const auto& t = env.telemetry();
      publishMessage(r.ch.telemetry, ns, t);
      const int64_t link_offset_us = static_cast<int64_t>(time_us) - static_cast<int64_t>(env.send_time_us());
      if (const auto people = r.feed->cameraPeople(t, link_offset_us); people && server_.subscribed(r.ch.camera_people))
        publishMessage(r.ch.camera_people, people->first, people->second);
      if (t.has_wide_video()) {
        if (!r.ch.camera_wide) advertiseWideHead(robot, r);
        if (const auto people = r.feed->cameraPeople(t, link_offset_us, v1::WIDE_HEAD);
            people && server_.subscribed(r.ch.camera_wide_people))
          publishMessage(r.ch.camera_wide_people, people->first, people->second);
      }
      if (server_.subscribed(r.ch.tf)) publishMessage(r.ch.tf, ns, r.feed->scene().transforms(ns));
      break;
    }
    case v1::Envelope::kEvent: {
      const auto& e = env.event();
      publishMessage(r.ch.events, ns, e);
      if (server_.subscribed(r.ch.log)) publishMessage(r.ch.log, ns, scene::RobotScene::log(robot, e, ns));
      if (e.has_gas_alarm()) publishMessage(r.ch.alarms, ns, e.gas_alarm());
      break;
    }
    case v1::Envelope::kAck: publishMessage(r.ch.acks, ns, env.ack()); break;
    default: break;
  }
}

void FoxgloveBridge::onAccessUnit(const std::string& robot, v1::CameraHead head, const video::Frame& frame,
                                  uint64_t capture_us) {
  uint32_t channel = 0;
  const uint64_t ns = capture_us ? monoUsToWallNs(capture_us) : wallNowNs();
  {
    std::lock_guard lk(mu_);
    const auto it = robots_.find(robot);
    if (it == robots_.end() || !it->second.connected) return;
    if (it->second.feed) it->second.feed->onAccessUnit(frame, capture_us, ns, head);
    channel = head == v1::WIDE_HEAD ? it->second.ch.camera_wide : it->second.ch.camera;
  }
  if (channel == 0 || !server_.subscribed(channel)) return;
  const auto v = scene::RobotScene::cameraFrame(robot, frame, ns, head);
  server_.publish(channel, ns, std::make_shared<const std::string>(v.SerializeAsString()), frame.keyframe);
}

void FoxgloveBridge::tick() {
  {
    std::lock_guard lk(mu_);
    if (stopped_) return;
    const uint64_t ns = wallNowNs();
    const auto now = SteadyClock::now();
    // Robots that went away lose their channels (they come back with the next connection).
    for (const auto& snap : registry_.snapshots(monoNowNs())) {
      const auto it = robots_.find(snap.id);
      if (it != robots_.end() && it->second.connected && !snap.connected) {
        unadvertiseRobot(it->second);
        log::info(kTag, snap.id, ": disconnected, channels unadvertised");
      }
    }
    for (auto& [robot, r] : robots_) {
      if (!r.connected || !r.feed) continue;
      r.feed->followMap(maps_, robot);
      if (server_.subscribed(r.ch.scene)) publishMessage(r.ch.scene, ns, r.feed->scene().scene(ns));
      if (server_.subscribed(r.ch.video_stats) && now - r.last_video_stats >= std::chrono::seconds(1)) {
        r.last_video_stats = now;
        publishMessage(r.ch.video_stats, ns, videoStats(robot));
      }
      if (now - r.last_grid >= steadyDuration(1.0 / options_.grid_hz)) {
        r.last_grid = now;
        for (const auto& name : r.feed->scene().gridChannels()) {
          auto& id = r.ch.grids[name];
          if (id == 0)
            id = addChannel(scene::topicName(robot, scene::TopicKind::kGasGrid, name), ::foxglove::Grid::descriptor(),
                            WsServer::Kind::kData);
          if (server_.subscribed(id))
            if (const auto g = r.feed->scene().grid(name, ns)) publishMessage(id, ns, *g);
        }
      }
    }
  }
  tick_timer_.expires_after(steadyDuration(1.0 / options_.scene_hz));
  tick_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) tick();
  });
}

v1::VideoStats FoxgloveBridge::videoStats(const std::string& robot) const {
  v1::VideoStats m;
  if (const auto snap = registry_.snapshot(robot, monoNowNs()); snap && snap->has_telemetry && snap->telemetry.has_video())
    *m.mutable_sender() = snap->telemetry.video();
  if (options_.video_stats)
    if (auto r = options_.video_stats(robot)) *m.mutable_receiver() = std::move(*r);
  return m;
}

void FoxgloveBridge::deadman() {
  std::vector<std::pair<uint64_t, std::string>> lapsed;
  {
    std::lock_guard lk(mu_);
    if (stopped_) return;
    const auto now = SteadyClock::now();
    for (auto& [id, c] : clients_) {
      if (c.teleop_robot.empty() || now - c.last_teleop < steadyDuration(options_.teleop_timeout_s)) continue;
      lapsed.emplace_back(id, c.teleop_robot);
      c.teleop_robot.clear();
    }
  }
  for (const auto& [client, robot] : lapsed) {
    const auto op = operatorOf(client);
    if (!op || !stopIfHeld(robot, op->session())) continue;
    server_.status(client, StatusLevel::kInfo,
                   "teleop: no set-point for " + util::fmtShort(options_.teleop_timeout_s) + " s; " + robot + " stopped");
  }
  deadman_timer_.expires_after(kDeadmanPeriod);
  deadman_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) deadman();
  });
}

void FoxgloveBridge::stopRobot(const std::string& robot, uint64_t session) {
  // Through the service like every other way of moving a robot (a stop needs
  // no control); its Ack is not waited for. A robot that is not connected
  // keeps no set-point to re-send.
  const Issued issued = service_.stop(session, robot, monoNowNs());
  if (const auto* r = std::get_if<CallResult>(&issued); r && !r->ok()) service_.clearTeleop(robot);
}

bool FoxgloveBridge::stopIfHeld(const std::string& robot, uint64_t session) {
  // A robot another session has taken over since is that session's to stop, not ours.
  const auto h = control_.holder(robot);
  if (!h || h->session != session) return false;
  stopRobot(robot, session);
  return true;
}

void FoxgloveBridge::onClientOpen(uint64_t client, const std::string& peer) {
  auto op = std::make_shared<ClientOperator>("foxglove " + peer, registry_, sink_, control_, console_options_, configure_,
                                             console_pool_);
  log::info(kTag, "client ", client, " (", peer, ") is operator session ", op->name());
  std::lock_guard lk(mu_);
  if (stopped_) return;
  clients_[client] = Client{std::move(op), peer, "", {}, {}};
}

void FoxgloveBridge::onClientClose(uint64_t client) {
  Client c;
  {
    std::lock_guard lk(mu_);
    const auto it = clients_.find(client);
    if (it == clients_.end()) return;
    c = std::move(it->second);
    clients_.erase(it);
  }
  // A client that drove a robot and went away leaves it stopped.
  if (!c.teleop_robot.empty() && c.op) stopIfHeld(c.teleop_robot, c.op->session());
  // A console line of it still running is interrupted; the session closes
  // when that line lets go of it (on the pool), or here.
  if (c.op) c.op->end();
}

void FoxgloveBridge::onSubscribe(uint64_t client, uint32_t channel) {
  // A new video subscriber needs a keyframe to start from: ask the robot (at most once a second per head).
  std::string robot;
  VideoRequest keyframe;
  keyframe.what = VideoRequest::What::kKeyframe;
  {
    std::lock_guard lk(mu_);
    for (auto& [id, r] : robots_) {
      if (!r.connected || channel == 0 || (r.ch.camera != channel && r.ch.camera_wide != channel)) continue;
      const bool wide = r.ch.camera_wide == channel;
      auto& asked = wide ? r.wide_keyframe_asked : r.keyframe_asked;
      const auto now = SteadyClock::now();
      if (now - asked < std::chrono::seconds(1)) return;
      asked = now;
      robot = id;
      keyframe.head = wide ? v1::WIDE_HEAD : v1::PTZ_HEAD;
    }
  }
  if (robot.empty()) return;
  // The camera's settings need no control; the Ack is not waited for.
  const auto op = operatorOf(client);
  (void)service_.video(op ? op->session() : 0, robot, keyframe, monoNowNs());
}

std::shared_ptr<ClientOperator> FoxgloveBridge::operatorOf(uint64_t client) const {
  std::lock_guard lk(mu_);
  const auto it = clients_.find(client);
  return it == clients_.end() ? nullptr : it->second.op;
}

std::string FoxgloveBridge::robotOfTopic(const std::string& topic) const {
  // "/<robot>/cmd_vel" names the robot; "/cmd_vel" means the session's selected one.
  if (topic.size() > 1 && topic[0] == '/') {
    const auto slash = topic.find('/', 1);
    if (slash != std::string::npos) return topic.substr(1, slash - 1);
  }
  return "";
}

void FoxgloveBridge::refuse(uint64_t client, const std::string& why) {
  {
    std::lock_guard lk(mu_);
    const auto it = clients_.find(client);
    if (it == clients_.end()) return;
    if (SteadyClock::now() - it->second.last_refusal < kRefusalDebounce) return;
    it->second.last_refusal = SteadyClock::now();
  }
  server_.status(client, StatusLevel::kError, why);
}

void FoxgloveBridge::onClientMessage(uint64_t client, const ClientChannel& channel, std::string_view payload) {
  const std::string& t = channel.topic;
  if (t == "/cmd_vel" || t.ends_with("/cmd_vel")) {
    teleop(client, robotOfTopic(t), payload);
    return;
  }
  refuse(client, "topic '" + t + "' is not one this server takes (publish geometry_msgs/Twist JSON on /cmd_vel or /<robot>/cmd_vel)");
}

void FoxgloveBridge::teleop(uint64_t client, const std::string& topic_robot, std::string_view payload) {
  using Json = nlohmann::json;
  const Json j = Json::parse(payload, nullptr, false);
  const auto num = [&](const char* a, const char* b) -> std::optional<double> {
    if (!j.is_object()) return std::nullopt;
    const auto o = j.find(a);
    if (o == j.end() || !o->is_object()) return 0.0;  // a Twist with a part left out: zero
    const auto v = o->find(b);
    if (v == o->end()) return 0.0;
    if (!v->is_number()) return std::nullopt;
    return v->get<double>();
  };
  const auto v = num("linear", "x"), w = num("angular", "z");
  if (j.is_discarded() || !v || !w || !std::isfinite(*v) || !std::isfinite(*w)) {
    refuse(client, "teleop: not a geometry_msgs/Twist JSON ({\"linear\": {\"x\": v}, \"angular\": {\"z\": w}})");
    return;
  }
  const auto op = operatorOf(client);
  if (!op) return;
  std::string robot = topic_robot;
  if (robot.empty()) robot = op->selected();
  if (robot.empty()) robot = registry_.firstConnected();
  if (robot.empty()) {
    refuse(client, "teleop: no robot connected");
    return;
  }
  // The set-point lapses to zero in the robot's session teleop_timeout_s after
  // this message unless the next one renews it (the deadman below only tells the client).
  const Issued issued = service_.teleop(op->session(), robot, *v, *w, options_.teleop_timeout_s, monoNowNs());
  if (const auto* r = std::get_if<CallResult>(&issued)) {
    if (r->outcome == CallOutcome::kRefused) {
      // Another session holds the robot: this client drives nothing, its deadman has nothing to stop.
      std::lock_guard lk(mu_);
      if (const auto it = clients_.find(client); it != clients_.end() && it->second.teleop_robot == robot)
        it->second.teleop_robot.clear();
    }
    refuse(client, r->outcome == CallOutcome::kRefused ? "teleop refused: " + r->reason
                                                       : "teleop: " + r->reason + "; set-point ignored");
    return;
  }
  const bool taken_now = !std::get<PendingCall>(issued).control_note.empty();  // the Ack is not waited for
  std::string previous;
  {
    std::lock_guard lk(mu_);
    const auto it = clients_.find(client);
    if (it == clients_.end()) return;
    previous = it->second.teleop_robot;
    it->second.teleop_robot = robot;
    it->second.last_teleop = SteadyClock::now();
  }
  if (!previous.empty() && previous != robot) stopRobot(previous, op->session());
  if (taken_now) server_.status(client, StatusLevel::kInfo, robot + ": controlled by " + op->name());
}

void FoxgloveBridge::onServiceCall(uint64_t client, const Service& service, uint32_t call_id, std::string_view payload) {
  const ServiceRequest req = parseServiceRequest(service.name, payload);
  if (!req.ok()) {
    server_.failCall(client, service.id, call_id, req.error);
    return;
  }
  const auto op = operatorOf(client);
  if (!op) return;
  if (!req.robot.empty()) {
    // A robot named stays the session's choice for its next calls, typed or console lines alike.
    {
      std::lock_guard lk(mu_);
      if (const auto it = clients_.find(client); it != clients_.end()) it->second.selected = req.robot;
    }
    if (req.call != ServiceRequest::Call::kConsoleLine) (void)op->post(req.robot, "", {});  // the console's select
  }
  if (req.call != ServiceRequest::Call::kConsoleLine) {
    callService(client, *op, service.id, call_id, req);
    return;
  }
  const uint32_t sid = service.id;
  const bool queued = op->post(req.robot, req.line, [this, client, sid, call_id](bool ok, const std::string& text) {
    server_.respond(client, sid, call_id, serviceResponse(ok, text));
  });
  if (!queued)
    server_.failCall(client, service.id, call_id,
                     "busy: " + std::to_string(ClientOperator::kMaxQueued) + " calls of this client are waiting");
}

Issued FoxgloveBridge::issue(const ServiceRequest& req, uint64_t session, const std::string& robot,
                             std::string& preface) {
  using Call = ServiceRequest::Call;
  const int64_t now = monoNowNs();
  switch (req.call) {
    case Call::kStop: return service_.stop(session, robot, now);
    case Call::kEstop: return service_.estop(session, robot, now);
    case Call::kResume: return service_.resume(session, robot, now);
    case Call::kGoto: return service_.goTo(session, robot, req.x_m, req.y_m, req.speed_m_s, now);
    case Call::kRoute:
    case Call::kInspect: {
      const bool inspection = req.call == Call::kInspect;
      Route r;
      try {
        r = openRoute(req.route);
      } catch (const config::ConfigError& e) {
        CallResult bad;
        bad.action = inspection ? "inspect" : "route";
        bad.robot = robot;
        bad.reason = e.what();
        return bad;
      }
      std::string summary;
      Issued issued = inspection ? service_.inspect(session, robot, r, req.speed_m_s, now, &summary)
                                 : service_.route(session, robot, r, now, &summary);
      if (!summary.empty()) preface = summary + "\n";
      return issued;
    }
    case Call::kRecordStart: return service_.recordStart(session, robot, req.name);
    case Call::kRecordStop: return service_.recordStop(session, robot);
    case Call::kAlarmAck: {
      const auto acks = service_.acknowledgeAlarms(session, req.alarm, now);
      CallResult r;
      r.action = "ack";
      r.reason = acks.error;
      if (acks.error.empty()) {
        r.outcome = CallOutcome::kCompleted;
        r.robot = acks.acked.front().first.robot_id;
        r.reason = acks.acked.front().second;
        for (std::size_t i = 1; i < acks.acked.size(); ++i)
          r.reason += "\n" + acks.acked[i].first.robot_id + ": " + acks.acked[i].second;
      }
      return r;
    }
    case Call::kControlTake: return service_.takeControl(session, robot, req.force, now);
    case Call::kControlRelease: return service_.releaseControl(session, robot);
    case Call::kConsoleLine: break;
  }
  CallResult bad;
  bad.action = "console";
  bad.reason = "not a typed call";
  return bad;
}

void FoxgloveBridge::callService(uint64_t client, const ClientOperator& op, uint32_t service_id, uint32_t call_id,
                                 const ServiceRequest& req) {
  // The robot: the one named, else for a stop the one this client drives,
  // else the last one it named, else its console session's selected one,
  // else the first connected.
  std::string robot = req.robot;
  {
    std::lock_guard lk(mu_);
    const auto it = clients_.find(client);
    if (it == clients_.end()) return;
    if (robot.empty() && req.urgent()) robot = it->second.teleop_robot;
    if (robot.empty()) robot = it->second.selected;
  }
  if (robot.empty()) robot = op.selected();
  if (robot.empty()) robot = registry_.firstConnected();
  std::string preface;
  const Issued issued = issue(req, op.session(), robot, preface);
  if (const auto* p = std::get_if<PendingCall>(&issued)) {
    awaitCall(client, service_id, call_id, *p, std::move(preface));
    return;
  }
  const CallResult& done = std::get<CallResult>(issued);
  // Calls done at once (control, record) answer with the console's line ("robot1: recording run ...").
  server_.respond(client, service_id, call_id,
                  serviceResponse(done.ok(), preface + (done.ok() ? done.robot + ": " + done.reason : done.text())));
}

void FoxgloveBridge::awaitCall(uint64_t client, uint32_t service_id, uint32_t call_id, PendingCall pending,
                               std::string preface) {
  if (const auto r = service_.settle(pending, monoNowNs())) {
    const std::string note = r->control_note.empty() ? "" : r->control_note + "\n";
    server_.respond(client, service_id, call_id, serviceResponse(r->ok(), preface + note + r->text()));
    return;
  }
  auto timer = std::make_shared<asio::steady_timer>(ioc_, kCallPollPeriod);
  {
    std::lock_guard lk(mu_);
    if (stopped_) return;
    std::erase_if(call_timers_, [](const auto& w) { return w.expired(); });
    call_timers_.push_back(timer);
  }
  timer->async_wait([this, timer, client, service_id, call_id, pending = std::move(pending),
                     preface = std::move(preface)](const boost::system::error_code& ec) mutable {
    if (ec) return;  // stop(): the bridge is going
    awaitCall(client, service_id, call_id, std::move(pending), std::move(preface));
  });
}

std::string FoxgloveBridge::report() const {
  const auto clients = server_.clients();
  std::ostringstream o;
  const auto& so = server_.options();
  o << "foxglove: " << (so.tls ? "wss" : "ws") << "://" << so.bind << ":" << so.port << "/"
    << (so.token.empty() ? " (no token)" : " (token required)") << ", " << clients.size() << " client"
    << (clients.size() == 1 ? "" : "s") << ", " << server_.refusedConnections() << " connection(s) refused\n";
  std::map<uint64_t, std::string> names;
  {
    std::lock_guard lk(mu_);
    for (const auto& [id, c] : clients_) names[id] = c.op ? c.op->name() : "";
  }
  for (const auto& c : clients) {
    o << "  client " << c.id << " " << c.peer << " (" << names[c.id] << "), " << util::fmtShort(c.connected_s, 0)
      << " s: " << c.subscriptions.size() << " subscriptions, queue " << c.queued_messages << " msgs / "
      << c.queued_bytes / 1024 << " KiB, sent " << c.counters.sent << ", dropped " << c.counters.dropped_data
      << " data + " << c.counters.dropped_video << " video (+" << c.counters.skipped_video
      << " skipped to a keyframe), refused " << c.refused << "\n";
    if (!c.subscriptions.empty()) {
      o << "    subscribed:";
      for (const auto& t : c.subscriptions) o << " " << t;
      o << "\n";
    }
    if (!c.publishing.empty()) {
      o << "    publishing:";
      for (const auto& t : c.publishing) o << " " << t;
      o << "\n";
    }
  }
  return o.str();
}

}  // namespace inspect::server::foxglove
