#pragma once
// One run being recorded (recorder.cpp starts and ends it,
// recorder_messages.cpp writes into it): its MCAP and its channels, its 3-D
// scene, its MP4, its figures. The recorder's own; under its lock.
#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "pc_server/recording/recorder.hpp"
#include "pc_server/recording/run_stats.hpp"
#include "pc_server/scene/scene_feed.hpp"
#include "shared/catalog/catalog.hpp"
#include "shared/record/mcap_writer.hpp"
#include "shared/video/mp4_writer.hpp"

namespace inspect::server {

struct Recorder::Run {
  catalog::RunInfo info;
  record::McapWriter mcap;
  uint16_t ch_telemetry = 0, ch_command = 0, ch_ack = 0, ch_event = 0, ch_server = 0, ch_camera = 0, ch_info = 0;
  // The 3-D scene: the live bridge's SceneFeed, so that the run replays the same view.
  std::unique_ptr<scene::SceneFeed> feed;
  uint16_t ch_tf = 0, ch_scene = 0, ch_log = 0, ch_camera_people = 0;
  // The wide head's, made at its first picture or people (0 = none yet; most robots have no wide stream).
  uint16_t ch_camera_wide = 0, ch_camera_wide_people = 0;
  std::map<std::string, uint16_t> ch_grid;
  uint64_t last_tf_ns = 0, last_scene_ns = 0, last_grid_ns = 0;
  std::unique_ptr<video::Mp4Writer> mp4;
  std::string mp4_error;
  RunStats stats;
  uint64_t command_id = 0;   // the track/goto command that started it (ends it on COMPLETED/FAILED)
  std::string address;       // robot's link address, to notice reconnects
  uint64_t video_frames = 0;
  uint64_t last_telemetry_ns = 0;  // log time of the latest telemetry, to mark gaps
  bool gains_known = false;  // gains_json names the tracking controller
  nlohmann::json gains = nlohmann::json::object();  // the run's gains_json

  explicit Run(record::McapWriterOptions o) : mcap(std::move(o)) {}
};

}  // namespace inspect::server
