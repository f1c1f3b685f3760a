#include "pc_server/recording/recorder.hpp"
#include "pc_server/recording/recorder_run.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "foxglove/CompressedVideo.pb.h"
#include "pc_server/scene/scene_feed.hpp"
#include "pc_server/scene/topics.hpp"
#include "shared/record/mcap_writer.hpp"
#include "shared/util/clock.hpp"
#include "shared/util/log.hpp"
#include "shared/util/number_text.hpp"
#include "shared/video/frame_source.hpp"
#include "shared/video/mp4_writer.hpp"

namespace inspect::server {

using util::fmtShort;

namespace fs = std::filesystem;

namespace {

int64_t fileBytes(const std::string& path) {
  std::error_code ec;
  const auto n = fs::file_size(path, ec);
  return ec ? 0 : static_cast<int64_t>(n);
}
}  // namespace

std::string gainsJson(const v1::Telemetry& t) {
  if (t.track_controller().empty() || !t.has_kp()) return "{}";  // not tracking, or gains unknown
  char json[256];
  std::snprintf(json, sizeof json, R"({"controller":"%s","kp":%.6g,"ki":%.6g,"kd":%.6g})",
                t.track_controller().c_str(), t.kp(), t.ki(), t.kd());
  return json;
}

std::string runGainsJson(const v1::Gains& g, uint32_t version) {
  nlohmann::json j;
  j["version"] = version;
  j["kp"] = g.kp();
  j["ki"] = g.ki();
  j["kd"] = g.kd();
  j["ke"] = g.ke();
  j["kec"] = g.kec();
  j["k1"] = g.k1();
  j["k2"] = g.k2();
  j["k3"] = g.k3();
  j["a1"] = g.a1();
  j["a2"] = g.a2();
  j["a3"] = g.a3();
  return j.dump();
}

Recorder::Recorder(const RecordingConfig& config, std::string software_version)
    : config_(config), software_version_(std::move(software_version)) {
  std::error_code ec;
  fs::create_directories(config_.dir, ec);
  if (ec) throw std::runtime_error("recording.dir: cannot create '" + config_.dir + "': " + ec.message());
  const std::string target = config_.catalog.empty() ? config_.dir + "/catalog.sqlite" : config_.catalog;
  catalog_ = std::make_unique<catalog::Catalog>(catalog::Catalog::open(target));
  catalog_->setServerId(config_.server_id);
  spool_ = std::make_unique<catalog::CatalogSpool>(*catalog_, config_.dir + "/catalog-spool.sqlite");
  // What a server stopped during an outage kept goes in first (its runs' ends included).
  if (!spool_->flush(std::chrono::seconds(10)))
    log::warn(log::tag::kRecord, spool_->status().pending, " writes kept in ", spool_->path(),
              " are not in the catalog yet: ", spool_->status().error);
  const auto incomplete = catalog_->markIncompleteRuns();  // this server's only
  for (const auto& id : incomplete) {
    const auto detail = catalog_->run(id);
    std::string what = id + ": marked incomplete";
    if (detail) {
      const std::string dir = config_.dir + "/" + id;
      const std::string mcap = dir + "/run.mcap";
      try {
        if (fs::exists(mcap)) {
          const auto r = record::repairMcap(mcap);
          what += r.was_complete ? ", MCAP complete"
                                 : ", MCAP repaired (" + std::to_string(r.messages_kept) + " messages kept, " +
                                       std::to_string(r.bytes_dropped) + " bytes of an unfinished chunk dropped)";
          spool_->addFile(id, "mcap", mcap, fileBytes(mcap));
        }
      } catch (const std::exception& e) {
        what += std::string(", MCAP not repaired: ") + e.what();
      }
      const std::string mp4 = dir + "/video.mp4";
      if (fs::exists(mp4)) spool_->addFile(id, "video", mp4, fileBytes(mp4));
    }
    log::warn(log::tag::kRecord, what);
    startup_report_ += (startup_report_.empty() ? "" : "; ") + what;
  }
  if (!config_.shared_runs.empty()) {
    copier_ = std::make_unique<RunCopier>(
        [this](const std::string& id, const std::string& dst, int64_t bytes, const std::string& error) {
          if (!error.empty()) {
            log::error(log::tag::kRecord, "run ", id, " not copied to the shared runs root: ", error);
            return;
          }
          log::info(log::tag::kRecord, "run ", id, " copied to ", dst, " (", bytes, " bytes)");
          spool_->addFile(id, "shared", dst, bytes);
        });
    queueUncopiedRuns();
  }
}

std::string Recorder::sharedDir(const std::string& server, const std::string& run_id) const {
  return config_.shared_runs + "/" + (server.empty() ? "local" : server) + "/" + run_id;
}

void Recorder::queueUncopiedRuns() {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(config_.dir, ec)) {
    const std::string id = e.path().filename().string();
    if (!e.is_directory() || !fs::exists(e.path() / "run.mcap")) continue;
    if (!fs::exists(sharedDir(config_.server_id, id))) copier_->copy(id, e.path().string(), sharedDir(config_.server_id, id));
  }
}

std::string Recorder::runsRoot() const {
  std::error_code ec;
  const std::string root =
      config_.shared_runs.empty() ? config_.dir : config_.shared_runs + "/" + (config_.server_id.empty() ? "local" : config_.server_id);
  const auto abs = fs::absolute(root, ec);
  return ec ? root : abs.lexically_normal().string();
}

std::string Recorder::runDir(const catalog::RunInfo& run, std::string* why) const {
  if (run.server.empty() || run.server == config_.server_id) return config_.dir + "/" + run.id;
  if (!config_.shared_runs.empty()) {
    const std::string shared = sharedDir(run.server, run.id);
    if (fs::exists(shared + "/run.mcap")) return shared;
    if (why)
      *why = "run " + run.id + " was recorded by server " + run.server + " and is not in the shared runs root yet (" +
             shared + ")";
    return "";
  }
  if (why)
    *why = "run " + run.id + " was recorded by server " + run.server +
           ", whose files this server cannot reach: give both servers a shared runs root (recording.shared_runs, "
           "--shared-runs), or ask on " + run.server;
  return "";
}

Recorder::~Recorder() {
  std::lock_guard lk(mu_);
  std::vector<std::string> robots;
  for (const auto& [robot, r] : runs_) robots.push_back(robot);
  for (const auto& robot : robots) {
    try {
      stopLocked(robot, "stopped");
    } catch (const std::exception& e) {
      log::error(log::tag::kRecord, robot, ": ending the run at shutdown: ", e.what());
    }
  }
}

void Recorder::setGainsSource(std::function<std::string(const std::string&)> f) {
  std::lock_guard lk(mu_);
  gains_source_ = std::move(f);
}

void Recorder::setHelloSource(std::function<std::optional<v1::Hello>(const std::string&)> f) {
  std::lock_guard lk(mu_);
  hello_source_ = std::move(f);
}

void Recorder::setRunMap(const std::string& robot, const std::string& map_path) {
  std::lock_guard lk(mu_);
  if (map_path.empty()) {  // the command that would have started the run was refused
    pending_map_.erase(robot);
    return;
  }
  if (auto it = runs_.find(robot); it != runs_.end()) {
    try {
      spool_->addFile(it->second->info.id, "map", map_path, fileBytes(map_path));
    } catch (const std::exception& e) {
      log::error(log::tag::kRecord, robot, ": run map not in the catalog: ", e.what());
    }
    return;
  }
  pending_map_[robot] = map_path;
}


void Recorder::noteAlarmAck(const std::string& robot, const v1::GasAlarm& a, const std::string& text) {
  std::lock_guard lk(mu_);
  auto it = runs_.find(robot);
  const std::string run_id = it == runs_.end() ? "" : it->second->info.id;
  try {
    if (it != runs_.end()) noteLocked(*it->second, robot, text);
    spool_->addAlarm(run_id, robot, std::chrono::system_clock::now(), a.channel_name(), v1::GasAlarm::Level_Name(a.level()),
                       "acked", a.value(), a.pose().x_m(), a.pose().y_m());
  } catch (const std::exception& e) {
    log::error(log::tag::kRecord, robot, ": alarm acknowledgement not recorded: ", e.what());
  }
}

void Recorder::setVideoFigures(std::function<std::optional<VideoFigures>(const std::string&)> f) {
  std::lock_guard lk(mu_);
  video_figures_ = std::move(f);
}

std::optional<std::string> Recorder::activeRun(const std::string& robot) const {
  std::lock_guard lk(mu_);
  auto it = runs_.find(robot);
  if (it == runs_.end()) return std::nullopt;
  return it->second->info.id;
}

std::string Recorder::start(const std::string& robot, const std::string& name, const std::string& route) {
  std::lock_guard lk(mu_);
  return startLocked(robot, name, route, 0);
}

std::string Recorder::startLocked(const std::string& robot, const std::string& name, const std::string& route,
                                  uint64_t command_id) {
  if (auto it = runs_.find(robot); it != runs_.end())
    throw std::runtime_error(robot + " is already recording run " + it->second->info.id);
  catalog::RunStart rs;
  rs.robot = robot;
  rs.name = name;
  rs.route = route;
  rs.software_version = software_version_;
  if (gains_source_) rs.gains_json = gains_source_(robot);
  const bool gains_known = rs.gains_json != "{}";
  rs.dir = config_.dir;  // the runs directory: the run's files are in <dir>/<run id>/
  record::McapWriterOptions mo;
  mo.compression = config_.compression == "none" ? "" : config_.compression;
  // Chunks closed by 0.8 s of log time (ticks every 0.2 s): a kill loses at most 1 s.
  mo.chunk_max_age_ns = 800'000'000;
  auto run = std::make_unique<Run>(mo);
  rs.start = std::chrono::system_clock::now();
  rs.id = newRunId(robot, *rs.start);
  spool_->startRun(rs);
  run->info = catalog::RunInfo{0, rs.id, robot, name, route, rs.gains_json, software_version_,
                               config_.dir + "/" + rs.id, *rs.start, {}, {}, catalog_->serverId()};
  try {
    fs::create_directories(run->info.dir);
    run->mcap.open(run->info.dir + "/run.mcap");
    // The topic table's recorded topics: the live view's names (pc_server/scene/topics).
    using scene::TopicKind;
    const auto add = [&](TopicKind kind) {
      return run->mcap.addProtobufChannel(scene::topicDef(kind).type(), scene::topicName(robot, kind));
    };
    run->ch_telemetry = add(TopicKind::kTelemetry);
    run->ch_command = add(TopicKind::kCommands);
    run->ch_ack = add(TopicKind::kAcks);
    run->ch_event = add(TopicKind::kEvents);
    run->ch_server = add(TopicKind::kServerEvents);
    run->ch_camera = add(TopicKind::kCamera);
    run->ch_camera_people = add(TopicKind::kCameraPeople);
    run->ch_info = add(TopicKind::kRobotInfo);
    run->ch_tf = add(TopicKind::kTf);
    run->ch_scene = add(TopicKind::kScene);
    run->ch_log = add(TopicKind::kLog);
    run->feed = std::make_unique<scene::SceneFeed>(robot, geometry_);
    video::Mp4Settings ms;
    ms.max_fragment_s = config_.max_fragment_s;
    run->mp4 = std::make_unique<video::Mp4Writer>(run->info.dir + "/video.mp4", ms);
  } catch (const std::exception& e) {
    spool_->endRun(run->info.id, "failed", std::chrono::system_clock::now());
    throw std::runtime_error("run " + run->info.id + ": " + e.what());
  }
  run->command_id = command_id;
  run->gains_known = gains_known && rs.gains_json.find("\"controller\"") != std::string::npos;
  run->gains = nlohmann::json::parse(rs.gains_json, nullptr, false);
  if (!run->gains.is_object()) run->gains = nlohmann::json::object();
  const std::string id = run->info.id;
  noteLocked(*run, robot, "run " + id + " started" + (name.empty() ? "" : " (" + name + ")"));
  spool_->addFile(id, "mcap", run->info.dir + "/run.mcap", 0);
  if (auto pm = pending_map_.find(robot); pm != pending_map_.end()) {
    spool_->addFile(id, "map", pm->second, fileBytes(pm->second));
    pending_map_.erase(pm);
  }
  // The robot as it announced itself (gas channels and units), for reports and tools.
  if (hello_source_) {
    if (const auto h = hello_source_(robot)) {
      const uint64_t now = wallNowNs();
      run->mcap.write(run->ch_info, now, now, *h);
      hello_[robot] = *h;
      run->feed->onHello(*h);
    }
  }
  runs_[robot] = std::move(run);
  log::info(log::tag::kRecord, robot, ": recording run ", id);
  return id;
}

std::optional<std::string> Recorder::stop(const std::string& robot, const std::string& outcome) {
  std::lock_guard lk(mu_);
  if (!runs_.count(robot)) return std::nullopt;
  return stopLocked(robot, outcome);
}

std::string Recorder::stopLocked(const std::string& robot, const std::string& outcome) {
  auto node = runs_.extract(robot);
  Run& r = *node.mapped();
  noteLocked(r, robot, "run " + r.info.id + " ended: " + outcome);
  r.mcap.close();
  if (r.mp4) r.mp4->close();
  const auto fig = r.stats.figures();
  catalog::Summary s;
  s.duration_s = fig.duration_s;
  s.distance_m = fig.distance_m;
  if (fig.min_person_m >= 0) s.min_person_m = fig.min_person_m;
  if (fig.tracking_samples) {
    s.track_max_pos_err_m = fig.max_position_error_m;
    s.track_rms_pos_err_m = fig.rms_position_error_m;
    s.track_max_angle_err_rad = fig.max_angle_error_rad;
  }
  if (video_figures_) {
    if (const auto v = video_figures_(robot)) {
      s.video_frames_received = v->frames_received;
      s.video_frames_decoded = v->frames_decoded;
      s.video_packets_lost = v->packets_lost;
    }
  }
  const auto hello = hello_.find(robot);
  for (const auto& g : fig.gas) {
    const bool named = hello != hello_.end() && g.channel < hello->second.gas_channels_size();
    s.gas.push_back({named ? hello->second.gas_channels(static_cast<int>(g.channel)).name() : "gas" + std::to_string(g.channel),
                     named ? hello->second.gas_channels(static_cast<int>(g.channel)).unit() : "", g.max, g.mean});
  }
  spool_->setSummary(r.info.id, s);
  spool_->addFile(r.info.id, "mcap", r.info.dir + "/run.mcap", fileBytes(r.info.dir + "/run.mcap"));
  if (r.mp4)
    for (const auto& f : r.mp4->files()) spool_->addFile(r.info.id, "video", f, fileBytes(f));
  const auto end = std::chrono::system_clock::now();
  spool_->endRun(r.info.id, outcome, end);
  auto& ended = ended_[robot];
  ended.push_back({r.info.id, r.info.start, end});
  if (ended.size() > 20) ended.erase(ended.begin());
  if (copier_) copier_->copy(r.info.id, r.info.dir, sharedDir(config_.server_id, r.info.id));
  log::info(log::tag::kRecord, robot, ": run ", r.info.id, " ended (", outcome, "): ", r.mcap.stats().messages, " messages, ",
            r.video_frames, " video frames");
  return r.info.id;
}

void Recorder::noteLocked(Run& r, const std::string& robot, const std::string& text, const std::string& kind,
                          uint64_t wall_ns) {
  v1::Event e;
  e.set_kind(v1::Event::INFO);
  e.set_text(text);
  e.set_robot_time_us(monoNowUs());
  const uint64_t t = wall_ns ? wall_ns : wallNowNs();
  r.mcap.write(r.ch_server, t, t, e);
  spool_->addEvent(r.info.id, robot,
                   std::chrono::system_clock::time_point(
                       std::chrono::duration_cast<std::chrono::system_clock::duration>(std::chrono::nanoseconds(t))),
                   kind, text);
}

void Recorder::autoStartLocked(const std::string& robot, const v1::Command& c) {
  std::string name;
  if (c.has_track()) name = "track";
  if (c.has_wheel_test()) name = "identification " + c.wheel_test().name();
  if (c.has_go_to())
    name = c.go_to().name().empty() ? "goto" : (c.go_to().inspection() ? "inspection " : "route ") + c.go_to().name();
  if (name.empty()) return;
  try {
    startLocked(robot, name, c.has_go_to() ? c.go_to().name() : c.has_wheel_test() ? c.wheel_test().name() : "",
                c.id());
  } catch (const std::exception& e) {
    log::error(log::tag::kRecord, robot, ": cannot start a run: ", e.what());
  }
}

std::string Recorder::newRunId(const std::string& robot, catalog::Time start) const {
  const std::string base = catalog::runIdBase(robot, start);
  std::string id = base;
  for (int n = 2; fs::exists(config_.dir + "/" + id); ++n) id = base + "-" + std::to_string(n);
  return id;
}

void Recorder::notePresence(const catalog::ServerInfo& server, const std::vector<catalog::RobotPresence>& robots) {
  spool_->upsertServer(server);
  for (const auto& p : robots) spool_->setPresence(p);
}

catalog::Catalog& Recorder::catalog() {
  if (spool_->status().reachable) spool_->flush(std::chrono::seconds(5));
  return *catalog_;
}

void Recorder::tick() {
  std::lock_guard lk(mu_);
  const uint64_t now = wallNowNs();
  for (auto& [robot, r] : runs_) {
    try {
      r->mcap.tick(now);
    } catch (const std::exception& e) {
      log::error(log::tag::kRecord, robot, ": ", e.what());
    }
  }
}

}  // namespace inspect::server
