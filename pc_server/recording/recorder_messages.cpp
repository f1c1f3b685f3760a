// The recorder's side that takes the robots' messages as they come: the
// catalog's alarms, telemetry and events into a run's MCAP, late (stored)
// events filed under the run they belong to, the camera's access units into
// MP4 and MCAP, and each run's 3-D scene (docs/recording.md). recorder.cpp
// has the runs' life: start, stop, the catalog and the shared copies.
#include "pc_server/recording/recorder.hpp"
#include "pc_server/recording/recorder_run.hpp"

#include <nlohmann/json.hpp>

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

void Recorder::catalogAlarmLocked(const std::string& robot, const v1::Envelope& env, bool inbound,
                                       const std::string& run_id, catalog::Time when) {
  // Gas alarms go into the catalog during runs and outside them.
  if (inbound && env.has_event() && env.event().has_gas_alarm()) {
    const auto& a = env.event().gas_alarm();
    try {
      spool_->addAlarm(run_id, robot, when, a.channel_name(), v1::GasAlarm::Level_Name(a.level()),
                         a.active() ? "raised" : "cleared", a.value(), a.pose().x_m(), a.pose().y_m());
    } catch (const std::exception& e) {
      log::error(log::tag::kRecord, robot, ": alarm not in the catalog: ", e.what());
    }
  }
}

void Recorder::recordTelemetryLocked(Run& r, const std::string& robot, const v1::Envelope& env, uint64_t time_us,
                                     uint64_t log_ns) {
  const auto& t = env.telemetry();
  // A telemetry gap (the link was down, or the robot silent) is marked in the run.
  if (r.last_telemetry_ns && log_ns > r.last_telemetry_ns + kTelemetryGapNs) {
    const double gap_s = static_cast<double>(log_ns - r.last_telemetry_ns) * 1e-9;
    noteLocked(r, robot, "telemetry gap: " + fmtShort(gap_s, 2) + " s without telemetry from " + robot, "gap", log_ns);
  }
  r.last_telemetry_ns = std::max(r.last_telemetry_ns, log_ns);
  r.stats.add(t);
  // The gains in force, as soon as the robot tracks with them.
  if (!r.gains_known && t.mode() == v1::TRACKING && !t.track_controller().empty()) {
    // The full set (from Hello / GAINS_APPLIED) keeps its values; the
    // controller, and kp/ki/kd for robots that announce no set, come from telemetry.
    const auto from_t = nlohmann::json::parse(gainsJson(t), nullptr, false);
    if (from_t.is_object())
      for (const auto& [k, v] : from_t.items())
        if (!r.gains.contains(k)) r.gains[k] = v;
    spool_->setGains(r.info.id, r.gains.dump());
    r.gains_known = true;
  }
  r.mcap.write(r.ch_telemetry, log_ns, env.send_time_us() * 1000, t);
  r.feed->onEnvelope(env, true);
  const int64_t link_offset_us = static_cast<int64_t>(time_us) - static_cast<int64_t>(env.send_time_us());
  if (const auto people = r.feed->cameraPeople(t, link_offset_us))
    r.mcap.write(r.ch_camera_people, log_ns, people->first, people->second);
  if (t.has_wide_video())
    if (const auto people = r.feed->cameraPeople(t, link_offset_us, v1::WIDE_HEAD))
      r.mcap.write(wideChannels(r).second, log_ns, people->first, people->second);
  writeScene(r, robot, log_ns, true);
}

void Recorder::recordEventLocked(Run& r, const std::string& robot, const v1::Envelope& env, uint64_t publish_ns,
                                 uint64_t log_ns, catalog::Time when) {
  const v1::Event& e = env.event();
  r.mcap.write(r.ch_event, log_ns, publish_ns, e);
  r.feed->onEnvelope(env, true);
  r.mcap.write(r.ch_log, log_ns, log_ns, scene::RobotScene::log(robot, e, log_ns));
  if (e.kind() == v1::Event::GAINS_APPLIED && e.has_gains()) {
    // New gains during the run: the catalog keeps the latest set and counts the changes.
    const std::string controller = r.gains.value("controller", "");
    const int changes = r.gains.value("changes_in_run", 0) + 1;
    r.gains = nlohmann::json::parse(runGainsJson(e.gains(), e.gains_version()));
    if (!controller.empty()) r.gains["controller"] = controller;
    r.gains["changes_in_run"] = changes;
    spool_->setGains(r.info.id, r.gains.dump());
  }
  spool_->addEvent(r.info.id, robot, when, v1::Event::Kind_Name(e.kind()), e.text());
}

void Recorder::onEnvelope(const std::string& robot, const std::string& address, const v1::Envelope& env,
                          bool inbound, uint64_t time_us) {
  std::lock_guard lk(mu_);
  if (!inbound && env.has_command() && config_.auto_start && !runs_.contains(robot))
    autoStartLocked(robot, env.command());
  const auto it = runs_.find(robot);
  // When it happened: the receive time, or for an event or ack the robot
  // stored during an outage its own time (store-and-forward).
  const uint64_t log_ns = monoUsToWallNs(time_us);
  const auto when = catalog::Time(
      std::chrono::duration_cast<std::chrono::system_clock::duration>(std::chrono::nanoseconds(log_ns)));
  // A stored entry from before the current run (or from a run that has
  // ended) is filed in the catalog under the run recording then; that run's
  // MCAP is closed and is not reopened (docs/store-and-forward.md).
  const bool in_open_run = it != runs_.end() && !(inbound && when < it->second->info.start);
  const std::string run_id = in_open_run             ? it->second->info.id
                             : inbound && isLate(env) ? runAt(robot, when)
                                                      : std::string();
  catalogAlarmLocked(robot, env, inbound, run_id, when);
  if (!in_open_run) {
    if (inbound && env.has_event() && !run_id.empty()) {
      try {
        spool_->addEvent(run_id, robot, when, v1::Event::Kind_Name(env.event().kind()),
                           env.event().text() + " (stored by the robot; filed after the run's recording closed)");
      } catch (const std::exception& e) {
        log::error(log::tag::kRecord, robot, ": event not in the catalog: ", e.what());
      }
    }
    return;
  }
  Run& r = *it->second;
  if (r.address.empty()) r.address = address;
  if (address != r.address) {
    noteLocked(r, robot, "robot reconnected from " + address + " (was " + r.address + "); run continues");
    r.address = address;
  }
  const uint64_t publish_ns = env.send_time_us() * 1000;  // the sender's clock
  try {
    switch (env.body_case()) {
      case v1::Envelope::kTelemetry: recordTelemetryLocked(r, robot, env, time_us, log_ns); break;
      case v1::Envelope::kCommand:
        r.mcap.write(r.ch_command, log_ns, publish_ns, env.command());
        r.feed->onEnvelope(env, false);
        break;
      case v1::Envelope::kAck: r.mcap.write(r.ch_ack, log_ns, publish_ns, env.ack()); break;
      case v1::Envelope::kEvent: recordEventLocked(r, robot, env, publish_ns, log_ns, when); break;
      default: break;
    }
  } catch (const std::exception& e) {
    log::error(log::tag::kRecord, robot, ": run ", r.info.id, ": ", e.what());
  }
  // The command that started the run ends it.
  if (inbound && env.has_ack() && r.command_id && env.ack().command_id() == r.command_id) {
    const auto st = env.ack().status();
    if (st == v1::Ack::COMPLETED || st == v1::Ack::FAILED || st == v1::Ack::REJECTED)
      stopLocked(robot, st == v1::Ack::COMPLETED ? "completed" : "failed");
  }
}

bool Recorder::isLate(const v1::Envelope& env) {
  return (env.has_event() && env.event().has_stored() && env.event().stored().replayed()) ||
         (env.has_ack() && env.ack().has_stored() && env.ack().stored().replayed());
}

std::string Recorder::runAt(const std::string& robot, catalog::Time t) {
  if (const auto it = ended_.find(robot); it != ended_.end())
    for (auto r = it->second.rbegin(); r != it->second.rend(); ++r)
      if (r->start <= t && t <= r->end) return r->id;
  // A run of an earlier process: the catalog, unless it is away (the link's thread never waits for it).
  if (!spool_->status().reachable) return "";
  try {
    spool_->flush(std::chrono::seconds(2));
    catalog::RunFilter f;
    f.robot = robot;
    f.limit = 20;
    for (const auto& run : catalog_->listRuns(f))
      if (run.start <= t && (!run.end || t <= *run.end)) return run.id;
  } catch (const std::exception& e) {
    log::error(log::tag::kRecord, robot, ": catalog: ", e.what());
  }
  return "";
}

std::pair<uint16_t, uint16_t> Recorder::wideChannels(Run& r) {
  if (!r.ch_camera_wide) {
    using scene::TopicKind;
    const auto add = [&](TopicKind kind) {
      return r.mcap.addProtobufChannel(scene::topicDef(kind).type(), scene::topicName(r.info.robot, kind));
    };
    r.ch_camera_wide = add(TopicKind::kCameraWide);
    r.ch_camera_wide_people = add(TopicKind::kCameraWidePeople);
  }
  return {r.ch_camera_wide, r.ch_camera_wide_people};
}

void Recorder::onAccessUnit(const std::string& robot, v1::CameraHead head, const video::Frame& frame,
                            uint64_t capture_us) {
  std::lock_guard lk(mu_);
  auto it = runs_.find(robot);
  if (it == runs_.end()) return;
  Run& r = *it->second;
  const uint64_t capture_wall_ns = capture_us ? monoUsToWallNs(capture_us) : wallNowNs();
  r.feed->onAccessUnit(frame, capture_us, capture_wall_ns, head);
  const auto v = scene::RobotScene::cameraFrame(robot, frame, capture_wall_ns, head);
  if (head == v1::WIDE_HEAD) {  // in run.mcap only; video.mp4 is the PTZ head's
    try {
      r.mcap.write(wideChannels(r).first, wallNowNs(), capture_wall_ns, v);
    } catch (const std::exception& e) {
      log::error(log::tag::kRecord, robot, ": run ", r.info.id, " wide video: ", e.what());
    }
    return;
  }
  ++r.video_frames;
  try {
    r.mcap.write(r.ch_camera, wallNowNs(), capture_wall_ns, v);
    if (r.mp4) r.mp4->write(frame.annexb.data(), frame.annexb.size(), frame.keyframe, capture_us ? capture_us : monoNowUs());
  } catch (const std::exception& e) {
    if (r.mp4_error.empty()) log::error(log::tag::kRecord, robot, ": run ", r.info.id, " video: ", e.what());
    r.mp4_error = e.what();
    r.mp4.reset();
  }
}

void Recorder::setScene(scene::SiteMaps* maps, const scene::Geometry& geometry) {
  std::lock_guard lk(mu_);
  site_maps_ = maps;
  geometry_ = geometry;
}

void Recorder::writeScene(Run& r, const std::string& robot, uint64_t ns, bool telemetry) {
  // The live view's rates, thinned: transforms at 10 Hz (the 3-D panel
  // interpolates), the scene at 5 Hz, the gas grids at 1 Hz.
  constexpr uint64_t kTfNs = 100'000'000, kSceneNs = 200'000'000, kGridNs = 1'000'000'000;
  if (telemetry && ns - r.last_tf_ns >= kTfNs) {
    r.last_tf_ns = ns;
    r.mcap.write(r.ch_tf, ns, ns, r.feed->scene().transforms(ns));
  }
  if (ns - r.last_scene_ns >= kSceneNs) {
    r.last_scene_ns = ns;
    if (site_maps_) r.feed->followMap(*site_maps_, robot);
    r.mcap.write(r.ch_scene, ns, ns, r.feed->scene().scene(ns));
  }
  if (ns - r.last_grid_ns >= kGridNs) {
    r.last_grid_ns = ns;
    for (const auto& name : r.feed->scene().gridChannels()) {
      auto& ch = r.ch_grid[name];
      if (ch == 0)
        ch = r.mcap.addProtobufChannel(::foxglove::Grid::descriptor(),
                                       scene::topicName(r.info.robot, scene::TopicKind::kGasGrid, name));
      if (const auto g = r.feed->scene().grid(name, ns)) r.mcap.write(ch, ns, ns, *g);
    }
  }
}

}  // namespace inspect::server
