// MCAP writer and repair (shared/record), checked with a small MCAP reader of
// our own written here from the spec (linear and indexed), independent of the
// writer's code. The files of the Samples tests are also read by @mcap/core
// (tests/tools/mcap_reader, ctests record_node_*): with INSPECT_MCAP_SAMPLES
// set, they are left in that folder with the counts expected of each.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>
#include <zstd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <google/protobuf/descriptor.h>
#include <google/protobuf/descriptor.pb.h>
#include <google/protobuf/dynamic_message.h>
#include <gtest/gtest.h>

#include "foxglove/CompressedVideo.pb.h"
#include "inspect_robot/v1/link.pb.h"
#include "shared/record/mcap_writer.hpp"
#include "tests/shared/record/mcap_test_files.hpp"

namespace {

using inspect::test::kBase;
using inspect::test::kMs;
using inspect::test::kSecond;
using inspect::test::slurp;
using inspect::test::spit;

namespace fs = std::filesystem;
using inspect::record::McapWriter;
using inspect::record::McapWriterOptions;
using inspect::record::repairMcap;
using Counts = std::map<std::string, uint64_t>;  // topic -> messages

const std::string kMagic("\x89MCAP0\r\n", 8);

// ------------------------------------------------------------ test reader

uint32_t crc(std::string_view s) {
  return static_cast<uint32_t>(::crc32(0, reinterpret_cast<const Bytef*>(s.data()), static_cast<uInt>(s.size())));
}

// Fields of a record, taken from the front.
struct Fields {
  std::string_view s;
  uint64_t num(std::size_t n) {
    if (s.size() < n) throw std::runtime_error("field past the end of its record");
    uint64_t v = 0;
    for (std::size_t i = n; i-- > 0;) v = v << 8 | static_cast<uint8_t>(s[i]);
    s.remove_prefix(n);
    return v;
  }
  std::string_view bytes(uint64_t n) {
    if (s.size() < n) throw std::runtime_error("bytes past the end of their record");
    const std::string_view v = s.substr(0, n);
    s.remove_prefix(n);
    return v;
  }
  std::string_view str() { return bytes(num(4)); }
};

struct Record {
  uint8_t op = 0;
  std::size_t at = 0, end = 0;
  Fields f;
};

// The record at `at`; nullopt when the file ends inside it.
std::optional<Record> recordAt(std::string_view file, std::size_t at) {
  if (at + 9 > file.size()) return std::nullopt;
  Fields prefix{file.substr(at, 9)};
  Record r;
  r.op = static_cast<uint8_t>(prefix.num(1));
  const uint64_t len = prefix.num(8);
  if (len > file.size() - at - 9) return std::nullopt;
  r.at = at;
  r.end = at + 9 + len;
  r.f = Fields{file.substr(at + 9, len)};
  return r;
}

Record needRecord(std::string_view file, std::size_t at, uint8_t op) {
  const auto r = recordAt(file, at);
  if (!r || r->op != op) throw std::runtime_error("no record " + std::to_string(op) + " at " + std::to_string(at));
  return *r;
}

struct Msg {
  uint16_t channel = 0;
  uint32_t sequence = 0;
  uint64_t log = 0, publish = 0;
  std::string data;
};

struct ChunkSeen {
  std::size_t offset = 0, end = 0, index_end = 0;  // record start, record end, end of its message indexes
  uint64_t start_time = 0, end_time = 0;
  std::size_t uncompressed = 0;
  std::string compression;
  std::map<uint16_t, std::size_t> index_at;  // channel -> Message Index record offset
  Counts counts;
};

struct Contents {
  bool complete = false;  // DataEnd, summary and footer there and consistent
  std::size_t data_end = 0;
  std::map<uint16_t, std::pair<std::string, std::string>> schemas;  // id -> name, FileDescriptorSet
  std::map<uint16_t, std::pair<uint16_t, std::string>> channels;    // id -> schema id, topic
  std::vector<ChunkSeen> chunks;
  std::vector<Msg> messages;
  Counts counts;
};

std::string decompress(const std::string& compression, std::string_view data, uint64_t size) {
  if (compression.empty()) return std::string(data);
  if (compression != "zstd") throw std::runtime_error("unexpected compression " + compression);
  std::string out(size, '\0');
  const std::size_t n = ZSTD_decompress(out.data(), out.size(), data.data(), data.size());
  if (ZSTD_isError(n) || n != size) throw std::runtime_error("zstd chunk does not decompress to its size");
  return out;
}

struct ChunkBody {
  uint64_t start_time, end_time, compressed_size;
  std::string compression, records;
};

ChunkBody chunkBody(Fields f) {
  ChunkBody c;
  c.start_time = f.num(8);
  c.end_time = f.num(8);
  const uint64_t size = f.num(8);
  const uint32_t want_crc = static_cast<uint32_t>(f.num(4));
  c.compression = f.str();
  c.compressed_size = f.num(8);
  c.records = decompress(c.compression, f.bytes(c.compressed_size), size);
  if (want_crc == 0 || crc(c.records) != want_crc) throw std::runtime_error("chunk CRC missing or wrong");
  return c;
}

Msg messageAt(std::string_view records, std::size_t at) {
  Record r = needRecord(records, at, 0x05);
  Msg m;
  m.channel = static_cast<uint16_t>(r.f.num(2));
  m.sequence = static_cast<uint32_t>(r.f.num(4));
  m.log = r.f.num(8);
  m.publish = r.f.num(8);
  m.data = std::string(r.f.s);
  return m;
}

void checkSummary(std::string_view file, const Contents& c, std::size_t summary_start);

// Start to end, as a streaming reader would; a file cut off ends at its last
// complete record (complete = false).
Contents readLinear(std::string_view file) {
  Contents c;
  if (file.substr(0, 8) != kMagic) throw std::runtime_error("no magic");
  auto header = recordAt(file, 8);
  if (!header || header->op != 0x01) throw std::runtime_error("no header");
  std::size_t pos = header->end;
  std::string last_records;  // the last chunk's, for its message indexes
  for (auto r = recordAt(file, pos); r; pos = r->end, r = recordAt(file, pos)) {  // pos grows every pass
    if (r->op == 0x03) {
      const auto id = static_cast<uint16_t>(r->f.num(2));
      const std::string name(r->f.str());
      if (r->f.str() != "protobuf") throw std::runtime_error("schema encoding is not protobuf");
      c.schemas[id] = {name, std::string(r->f.str())};
    } else if (r->op == 0x04) {
      const auto id = static_cast<uint16_t>(r->f.num(2));
      const auto schema = static_cast<uint16_t>(r->f.num(2));
      const std::string topic(r->f.str());
      if (!c.schemas.contains(schema)) throw std::runtime_error("channel before its schema");
      if (r->f.str() != "protobuf") throw std::runtime_error("message encoding is not protobuf");
      c.channels[id] = {schema, topic};
    } else if (r->op == 0x06) {
      const ChunkBody body = chunkBody(r->f);
      ChunkSeen seen;
      seen.offset = r->at;
      seen.end = seen.index_end = r->end;
      seen.start_time = body.start_time;
      seen.end_time = body.end_time;
      seen.uncompressed = body.records.size();
      seen.compression = body.compression;
      uint64_t lo = UINT64_MAX, hi = 0;
      for (std::size_t at = 0; at < body.records.size(); at = needRecord(body.records, at, 0x05).end) {
        Msg m = messageAt(body.records, at);
        if (!c.channels.contains(m.channel)) throw std::runtime_error("message before its channel");
        lo = std::min(lo, m.log);
        hi = std::max(hi, m.log);
        ++seen.counts[c.channels[m.channel].second];
        c.messages.push_back(std::move(m));
      }
      if (lo != body.start_time || hi != body.end_time) throw std::runtime_error("chunk time bounds wrong");
      c.chunks.push_back(seen);
      last_records = body.records;
    } else if (r->op == 0x07) {
      if (c.chunks.empty() || c.chunks.back().index_end != r->at) throw std::runtime_error("stray message index");
      ChunkSeen& chunk = c.chunks.back();
      const auto channel = static_cast<uint16_t>(r->f.num(2));
      Fields entries{r->f.str()};
      uint64_t n = 0;
      for (; !entries.s.empty(); ++n) {  // 16 bytes a pass
        const uint64_t log = entries.num(8);
        const Msg m = messageAt(last_records, entries.num(8));
        if (m.channel != channel || m.log != log) throw std::runtime_error("message index entry points elsewhere");
      }
      if (n != chunk.counts[c.channels.at(channel).second]) throw std::runtime_error("message index incomplete");
      chunk.index_at[channel] = r->at;
      chunk.index_end = r->end;
    } else if (r->op == 0x0F) {
      if (r->f.num(4) != crc(file.substr(0, r->at))) throw std::runtime_error("data section CRC wrong");
      c.data_end = r->at;
      checkSummary(file, c, r->end);
      c.complete = true;
      break;
    } else {
      throw std::runtime_error("unexpected record " + std::to_string(r->op) + " in the data section");
    }
  }
  for (const ChunkSeen& chunk : c.chunks) {
    if (chunk.index_at.size() != chunk.counts.size() && (&chunk != &c.chunks.back() || c.complete))
      throw std::runtime_error("a chunk lacks message indexes");
    for (const auto& [topic, n] : chunk.counts) c.counts[topic] += n;
  }
  return c;
}

// The summary and footer after DataEnd, against what the data section holds.
void checkSummary(std::string_view file, const Contents& c, std::size_t summary_start) {
  const std::size_t footer_at = file.size() - 8 - 29;
  if (file.size() < summary_start + 37 || file.substr(file.size() - 8) != kMagic) throw std::runtime_error("no end magic");
  Record footer = needRecord(file, footer_at, 0x02);
  if (footer.f.num(8) != summary_start) throw std::runtime_error("footer summary_start wrong");
  const uint64_t offsets_start = footer.f.num(8);
  if (footer.f.num(4) != crc(file.substr(summary_start, footer_at + 25 - summary_start)))
    throw std::runtime_error("summary CRC wrong");
  std::size_t chunk_index = 0;
  std::set<uint16_t> schemas, channels;
  std::map<uint8_t, std::pair<std::size_t, std::size_t>> groups;  // opcode -> first record, end of the last
  for (std::size_t pos = summary_start; pos < offsets_start; pos = needRecord(file, pos, file[pos]).end) {
    Record r = needRecord(file, pos, file[pos]);
    auto [g, fresh] = groups.try_emplace(r.op, r.at, r.end);
    if (!fresh && g->second.second != r.at) throw std::runtime_error("summary records not grouped");
    g->second.second = r.end;
    if (r.op == 0x03) schemas.insert(static_cast<uint16_t>(r.f.num(2)));
    if (r.op == 0x04) channels.insert(static_cast<uint16_t>(r.f.num(2)));
    if (r.op == 0x0B) {
      if (r.f.num(8) != c.messages.size() || r.f.num(2) != c.schemas.size() || r.f.num(4) != c.channels.size() ||
          r.f.num(4) != 0 || r.f.num(4) != 0 || r.f.num(4) != c.chunks.size())
        throw std::runtime_error("statistics counts wrong");
      const uint64_t start = r.f.num(8), end = r.f.num(8);
      if (!c.chunks.empty() && (start != c.chunks.front().start_time || end < c.chunks.back().end_time))
        throw std::runtime_error("statistics times wrong");
      Fields counts{r.f.str()};
      for (uint64_t sum = 0; !counts.s.empty();) {  // 10 bytes a pass
        const auto channel = static_cast<uint16_t>(counts.num(2));
        sum += counts.num(8);
        if (counts.s.empty() && sum != c.messages.size()) throw std::runtime_error("channel counts wrong");
        if (!c.channels.contains(channel)) throw std::runtime_error("count for an unknown channel");
      }
    }
    if (r.op == 0x08) {
      if (chunk_index >= c.chunks.size()) throw std::runtime_error("more chunk indexes than chunks");
      const ChunkSeen& k = c.chunks[chunk_index++];
      const uint64_t start = r.f.num(8), end = r.f.num(8), offset = r.f.num(8), length = r.f.num(8);
      Fields offsets{r.f.str()};
      std::map<uint16_t, std::size_t> index_at;
      while (!offsets.s.empty()) {  // 10 bytes a pass
        const auto channel = static_cast<uint16_t>(offsets.num(2));
        index_at[channel] = offsets.num(8);
      }
      const uint64_t index_length = r.f.num(8);
      const std::string_view compression = r.f.str();
      const uint64_t compressed = r.f.num(8), uncompressed = r.f.num(8);
      const bool ok = start == k.start_time && end == k.end_time && offset == k.offset && length == k.end - k.offset &&
                      index_at == k.index_at && index_length == k.index_end - k.end && compression == k.compression &&
                      uncompressed == k.uncompressed && length == 9 + 8 + 8 + 8 + 4 + 4 + compression.size() + 8 + compressed;
      if (!ok) throw std::runtime_error("chunk index " + std::to_string(chunk_index - 1) + " wrong");
    }
  }
  if (chunk_index != c.chunks.size()) throw std::runtime_error("chunks without an index");
  for (const auto& [id, s] : c.schemas)
    if (!schemas.contains(id)) throw std::runtime_error("schema missing from the summary");
  for (const auto& [id, ch] : c.channels)
    if (!channels.contains(id)) throw std::runtime_error("channel missing from the summary");
  std::size_t n = 0;
  for (std::size_t pos = offsets_start; pos < footer_at; pos = needRecord(file, pos, 0x0E).end, ++n) {
    Record r = needRecord(file, pos, 0x0E);
    const auto op = static_cast<uint8_t>(r.f.num(1));
    const uint64_t start = r.f.num(8), length = r.f.num(8);
    if (!groups.contains(op) || groups[op].first != start || groups[op].second - start != length)
      throw std::runtime_error("summary offset wrong");
  }
  if (n != groups.size()) throw std::runtime_error("summary groups without an offset");
}

// From the footer, as a seeking reader would: summary, chunk indexes, message
// indexes, then only the messages they point to. Counts per topic.
Counts readIndexed(std::string_view file) {
  if (file.size() < 45 || file.substr(file.size() - 8) != kMagic) throw std::runtime_error("no end magic");
  Record footer = needRecord(file, file.size() - 37, 0x02);
  const std::size_t summary_start = footer.f.num(8);
  const std::size_t offsets_start = footer.f.num(8);
  std::map<uint16_t, std::string> topics;
  Counts counts;
  std::vector<Record> chunk_indexes;
  for (std::size_t pos = summary_start; pos < offsets_start; pos = needRecord(file, pos, file[pos]).end) {
    Record r = needRecord(file, pos, file[pos]);
    if (r.op == 0x04) {
      const auto id = static_cast<uint16_t>(r.f.num(2));
      r.f.num(2);
      topics[id] = r.f.str();
    }
    if (r.op == 0x08) chunk_indexes.push_back(r);
  }
  for (Record& ci : chunk_indexes) {
    ci.f.bytes(16);  // start and end time
    Record chunk = needRecord(file, ci.f.num(8), 0x06);
    if (chunk.end - chunk.at != ci.f.num(8)) throw std::runtime_error("chunk length differs from its index");
    const std::string records = chunkBody(chunk.f).records;
    Fields offsets{ci.f.str()};
    while (!offsets.s.empty()) {  // 10 bytes a pass
      const auto channel = static_cast<uint16_t>(offsets.num(2));
      Record index = needRecord(file, offsets.num(8), 0x07);
      if (index.f.num(2) != channel) throw std::runtime_error("message index of another channel");
      Fields entries{index.f.str()};
      while (!entries.s.empty()) {  // 16 bytes a pass
        entries.num(8);
        if (messageAt(records, entries.num(8)).channel != channel) throw std::runtime_error("index points elsewhere");
        ++counts[topics.at(channel)];
      }
    }
  }
  return counts;
}

// ------------------------------------------------------------ a run to record

// What the server records: 50 Hz telemetry, an event every 0.7 s, 30 fps
// H.264 (Annex B, IDR every 30 frames, incompressible payload like real video).
class SimRun {
 public:
  static constexpr const char* kTelemetry = "/telemetry";
  static constexpr const char* kEvents = "/events";
  static constexpr const char* kVideo = "/video";

  SimRun(McapWriter& w, bool video, uint32_t video_kbps = 2000) : w_(w), video_kbps_(video_kbps) {
    telemetry_ = w.addProtobufChannel(inspect::v1::Telemetry::descriptor(), kTelemetry);
    events_ = w.addProtobufChannel(inspect::v1::Event::descriptor(), kEvents);
    if (video)
      video_ = w.addProtobufChannel(foxglove::CompressedVideo::descriptor(), kVideo, {{"frame_id", "camera"}});
  }

  // Everything due in [from, to) ms of the run, tick() every 200 ms.
  void play(uint64_t from_ms, uint64_t to_ms) {
    for (uint64_t ms = from_ms; ms < to_ms; ++ms) {  // bounded by to_ms
      const uint64_t now = kBase + ms * kMs;
      if (ms % 20 == 0) telemetry(now, ms);
      if (ms % 700 == 350) event(now, ms);
      if (video_ && (ms == 0 || ms * 30 / 1000 != (ms - 1) * 30 / 1000)) frame(now, ms * 30 / 1000);
      if (ms % 200 == 0) w_.tick(now);
    }
  }

  Counts sent;  // per topic
  uint64_t total = 0;
  double write_ms = 0;  // spent in McapWriter::write

 private:
  void record(uint16_t channel, const char* topic, uint64_t now, uint64_t robot_ns,
              const google::protobuf::MessageLite& m) {
    const auto t0 = std::chrono::steady_clock::now();
    w_.write(channel, now, robot_ns, m);
    write_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ++sent[topic];
    ++total;
  }
  void telemetry(uint64_t now, uint64_t ms) {
    inspect::v1::Telemetry t;
    const double s = ms / 1000.0;
    const uint64_t robot_us = 5'000'000 + ms * 1000 - 3000;  // robot clock, 3 ms behind
    t.set_robot_time_us(robot_us);
    t.mutable_pose()->set_x_m(std::cos(s / 5) + noise());
    t.mutable_pose()->set_y_m(std::sin(s / 5) + noise());
    t.mutable_pose()->set_theta_rad(std::remainder(s / 5 + std::numbers::pi / 2, 2 * std::numbers::pi));
    t.set_wheel_left_rad_s(4.9 + noise());
    t.set_wheel_right_rad_s(5.1 + noise());
    t.set_cmd_wheel_left_rad_s(4.9);
    t.set_cmd_wheel_right_rad_s(5.1);
    t.set_v_m_s(0.3 + noise());
    t.set_w_rad_s(0.2 + noise());
    t.set_cmd_v_m_s(0.3);
    t.set_cmd_w_rad_s(0.2);
    for (int i = 0; i < 4; ++i) t.add_ultrasonic_m(1.5 + i * 0.3 + noise());
    t.add_gas(412 + 10 * noise());
    t.add_gas(0.8 + noise());
    t.set_battery_v(24.1 - s * 1e-4);
    t.set_mode(inspect::v1::TRACKING);
    t.mutable_serial()->set_frames_ok(ms / 5);
    t.mutable_serial()->set_bytes_rx(ms * 40);
    t.set_sensor_rate_hz(200 + noise());
    t.set_last_command_id(3);
    t.mutable_reference()->set_x_m(std::cos(s / 5));
    t.set_position_error_m(std::abs(noise()));
    t.set_track_progress(s / 600);
    t.set_kp(2.5 + noise());
    t.set_track_controller("fuzzy_pid");
    t.set_nearest_person_m(-1);
    t.set_speed_factor(1);
    t.set_nav_mode("GO_TO_GOAL");
    auto* v = t.mutable_video();
    v->set_enabled(true);
    v->set_fps(30);
    v->set_bitrate_kbps(video_kbps_);
    v->set_encoder("libx264");
    v->set_frames_encoded(ms * 30 / 1000);
    v->set_bytes_sent(ms * video_kbps_ / 8);
    record(telemetry_, kTelemetry, now, robot_us * 1000, t);
  }
  void event(uint64_t now, uint64_t ms) {
    inspect::v1::Event e;
    e.set_kind(inspect::v1::Event::INFO);
    e.set_text("waypoint " + std::to_string(ms / 700) + " reached");
    e.set_robot_time_us(5'000'000 + ms * 1000 - 3000);
    record(events_, kEvents, now, e.robot_time_us() * 1000, e);
  }
  void frame(uint64_t now, uint64_t index) {
    const bool idr = index % 30 == 0;
    const std::size_t mean = video_kbps_ * 1000 / 8 / 30;
    const std::size_t size = idr ? mean * 30 / 34 * 5 : mean * 30 / 34;
    foxglove::CompressedVideo f;
    f.mutable_timestamp()->set_seconds(static_cast<int64_t>(now / kSecond));
    f.mutable_timestamp()->set_nanos(static_cast<int32_t>(now % kSecond));
    f.set_frame_id("camera");
    f.set_format("h264");
    std::string data("\0\0\0\1", 4);
    data.push_back(idr ? '\x65' : '\x41');
    for (std::size_t i = data.size(); i < size; ++i) data.push_back(static_cast<char>(rng_()));
    f.set_data(std::move(data));
    record(video_, kVideo, now, now - 40 * kMs, f);
  }
  double noise() { return std::normal_distribution<double>(0, 0.01)(rng_); }

  McapWriter& w_;
  uint32_t video_kbps_;
  uint16_t telemetry_ = 0, events_ = 0, video_ = 0;
  std::mt19937 rng_{7};
};

std::string expectJson(const Counts& counts, std::size_t schemas) {
  std::string s = "{";
  for (const auto& [topic, n] : counts) s += "\"" + topic + "\": " + std::to_string(n) + ", ";
  return s + "\"schemas\": " + std::to_string(schemas) + "}\n";
}

class Mcap : public ::testing::Test {
 protected:
  void SetUp() override {
    const char* samples = std::getenv("INSPECT_MCAP_SAMPLES");
    keep_ = samples && *samples;
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = keep_ ? fs::path(samples)
                 : fs::temp_directory_path() /
                       ("mcap_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!keep_) fs::remove_all(dir_);
  }
  // A sample for the node reader: the file and the counts expected of it.
  void sample(const std::string& name, std::string_view bytes, const Counts& counts, std::size_t schemas) {
    spit(dir_ / (name + ".mcap"), bytes);
    spit(dir_ / (name + ".expect.json"), expectJson(counts, schemas));
  }
  // A recording of `seconds` of the run; its counts in `sent`.
  std::string record(const std::string& name, McapWriterOptions o, uint64_t seconds, Counts* sent = nullptr) {
    const fs::path p = dir_ / (name + ".mcap");
    McapWriter w(o);
    w.open(p.string());
    SimRun run(w, true);
    run.play(0, seconds * 1000 + 500);
    w.close();
    if (sent) *sent = run.sent;
    return slurp(p);
  }

  fs::path dir_;
  bool keep_ = false;
};

// ------------------------------------------------------------ tests

void expectRoundTrip(const std::string& bytes, const Counts& sent, const std::string& compression) {
  const Contents c = readLinear(bytes);
  ASSERT_TRUE(c.complete);
  EXPECT_EQ(c.counts, sent);
  EXPECT_EQ(readIndexed(bytes), sent);
  EXPECT_EQ(c.schemas.size(), 3u);
  // Time-closed chunks: none spans 1 s of log time, consecutive ones are in order.
  ASSERT_GE(c.chunks.size(), 4u);
  for (std::size_t i = 0; i < c.chunks.size(); ++i) {
    EXPECT_LT(c.chunks[i].end_time - c.chunks[i].start_time, kSecond) << "chunk " << i;
    EXPECT_EQ(c.chunks[i].compression, compression) << "chunk " << i;
    if (i > 0) {
      EXPECT_GT(c.chunks[i].start_time, c.chunks[i - 1].end_time);
    }
  }
  // Sequence numbers count per channel from 1; messages decode with the embedded schemas.
  std::map<uint16_t, uint32_t> seq;
  google::protobuf::DescriptorPool pool;
  for (const auto& [id, schema] : c.schemas) {
    google::protobuf::FileDescriptorSet set;
    ASSERT_TRUE(set.ParseFromString(schema.second));
    for (const auto& file : set.file()) pool.BuildFile(file);  // an already built file returns it again
    ASSERT_NE(pool.FindMessageTypeByName(schema.first), nullptr) << schema.first;
  }
  google::protobuf::DynamicMessageFactory factory(&pool);
  for (const Msg& m : c.messages) {
    ASSERT_EQ(m.sequence, ++seq[m.channel]);
    const auto& [schema_id, topic] = c.channels.at(m.channel);
    const auto* type = pool.FindMessageTypeByName(c.schemas.at(schema_id).first);
    std::unique_ptr<google::protobuf::Message> decoded(factory.GetPrototype(type)->New());
    ASSERT_TRUE(decoded->ParseFromString(m.data)) << topic;
    if (topic == SimRun::kTelemetry) {
      const auto* field = type->FindFieldByName("robot_time_us");
      EXPECT_EQ(decoded->GetReflection()->GetUInt64(*decoded, field) * 1000, m.publish);
    }
    if (topic == SimRun::kVideo) {
      EXPECT_EQ(decoded->GetReflection()->GetString(*decoded, type->FindFieldByName("format")), "h264");
    }
  }
}

TEST_F(Mcap, SamplesRoundTripZstd) {
  Counts sent;
  const std::string bytes = record("zstd", {}, 4, &sent);
  EXPECT_EQ(sent.at(SimRun::kTelemetry), 225u);
  expectRoundTrip(bytes, sent, "zstd");
  sample("zstd", bytes, sent, 3);
}

TEST_F(Mcap, SamplesRoundTripUncompressed) {
  McapWriterOptions o;
  o.compression = "";
  Counts sent;
  const std::string bytes = record("plain", o, 4, &sent);
  expectRoundTrip(bytes, sent, "");
  sample("plain", bytes, sent, 3);
}

TEST_F(Mcap, SizeClosesChunks) {
  McapWriterOptions o;
  o.chunk_size = 64 * 1024;
  Counts sent;
  const Contents c = readLinear(record("small", o, 3, &sent));
  EXPECT_EQ(c.counts, sent);
  EXPECT_GT(c.chunks.size(), 12u);  // 3.5 s of 263 KB/s; time alone closes 4
  for (const ChunkSeen& k : c.chunks) EXPECT_LT(k.uncompressed, 64u * 1024 + 50'000);  // + one IDR frame
}

TEST_F(Mcap, TickClosesAQuietChunkAndTheFileIsReadableWithoutClose) {
  const fs::path p = dir_ / "quiet.mcap";
  McapWriter w;
  w.open(p.string());
  const uint16_t ch = w.addProtobufChannel(inspect::v1::Event::descriptor(), "/events");
  inspect::v1::Event e;
  e.set_text("started");
  w.write(ch, kBase, kBase, e);
  w.tick(kBase + 800 * kMs);
  EXPECT_EQ(w.stats().chunks, 0u);
  w.tick(kBase + 1000 * kMs);
  EXPECT_EQ(w.stats().chunks, 1u);
  EXPECT_EQ(w.stats().open_chunk_bytes, 0u);
  const Contents c = readLinear(slurp(p));  // not closed: what a killed server leaves
  EXPECT_FALSE(c.complete);
  EXPECT_EQ(c.counts, (Counts{{"/events", 1}}));
  w.close();
  EXPECT_EQ(readIndexed(slurp(p)), (Counts{{"/events", 1}}));
}

TEST_F(Mcap, OpenErrorNamesThePath) {
  McapWriter w;
  try {
    w.open("/nonexistent/dir/run.mcap");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/run.mcap"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("No such file or directory"), std::string::npos) << e.what();
  }
  EXPECT_THROW(w.write(1, 0, 0, std::string_view("x")), std::logic_error);
  McapWriterOptions o;
  o.compression = "lz4";
  McapWriter bad(o);
  EXPECT_THROW(bad.open((dir_ / "x.mcap").string()), std::invalid_argument);
}

TEST_F(Mcap, FileDescriptorSetHoldsEveryDependencyFirst) {
  google::protobuf::FileDescriptorSet set;
  ASSERT_TRUE(set.ParseFromString(inspect::record::protobufFileDescriptorSet(foxglove::CompressedVideo::descriptor())));
  ASSERT_EQ(set.file_size(), 2);
  EXPECT_EQ(set.file(0).name(), "google/protobuf/timestamp.proto");
  EXPECT_EQ(set.file(1).name(), "foxglove/CompressedVideo.proto");
  EXPECT_EQ(set.file(1).package(), "foxglove");
}

// A file cut at `cut` bytes and repaired keeps exactly the complete chunks.
struct Cut {
  std::string name;
  std::size_t at;
  std::size_t chunks_kept;  // of the original's chunks
  std::size_t keep;         // bytes of the cut file kept
};

TEST_F(Mcap, SamplesRepairKeepsEveryCompleteChunk) {
  Counts sent;
  const std::string whole = record("whole", {}, 5, &sent);
  const Contents full = readLinear(whole);
  ASSERT_TRUE(full.complete);
  ASSERT_GE(full.chunks.size(), 5u);
  const auto& k = full.chunks;
  const std::size_t first_chunk = k[0].offset;
  const std::vector<Cut> cuts = {
      {"empty", 0, 0, 0},
      {"mid_magic", 5, 0, 0},
      {"mid_header", 8 + 12, 0, 0},
      {"before_chunks", first_chunk, 0, first_chunk},
      {"mid_chunk", (k[2].offset + k[2].end) / 2, 2, k[1].index_end},
      {"chunk_without_index", k[2].end, 3, k[2].end},
      {"mid_index", k[2].end + 13, 3, k[2].end},
      {"after_chunk", k[2].index_end, 3, k[2].index_end},
      {"mid_record_prefix", k[3].offset + 4, 3, k[2].index_end},
      {"before_data_end", full.data_end, k.size(), full.data_end},
      {"in_summary", full.data_end + 40, k.size(), full.data_end},
      {"before_footer_magic", whole.size() - 3, k.size(), full.data_end},
  };
  for (const Cut& cut : cuts) {
    SCOPED_TRACE(cut.name);
    Counts expected;
    for (std::size_t i = 0; i < cut.chunks_kept; ++i)
      for (const auto& [topic, n] : k[i].counts) expected[topic] += n;
    const fs::path p = dir_ / ("repaired_" + cut.name + ".mcap");
    const std::string cut_bytes = whole.substr(0, cut.at);
    spit(p, cut_bytes);
    if (cut.name == "mid_chunk") sample("cut_mid_chunk", cut_bytes, expected, 3);  // unrepaired, for the stream reader
    const auto r = repairMcap(p.string());
    EXPECT_FALSE(r.was_complete);
    EXPECT_EQ(r.chunks_kept, cut.chunks_kept);
    EXPECT_EQ(r.bytes_dropped, cut.at - cut.keep);
    const std::string repaired = slurp(p);
    Contents c;
    ASSERT_NO_THROW(c = readLinear(repaired));
    ASSERT_TRUE(c.complete);
    EXPECT_EQ(c.counts, expected);
    uint64_t total = 0;
    for (const auto& [topic, n] : expected) total += n;
    EXPECT_EQ(r.messages_kept, total);
    EXPECT_EQ(readIndexed(repaired), expected);
    EXPECT_EQ(c.schemas.size(), cut.at >= first_chunk ? 3u : 0u);
    // Repairing again finds a complete file and leaves it alone.
    const auto again = repairMcap(p.string());
    EXPECT_TRUE(again.was_complete);
    EXPECT_EQ(again.messages_kept, total);
    EXPECT_EQ(slurp(p), repaired);
    sample("repaired_" + cut.name, repaired, expected, c.schemas.size());
  }
  const fs::path p = dir_ / "whole.mcap";
  const auto r = repairMcap(p.string());
  EXPECT_TRUE(r.was_complete);
  EXPECT_EQ(r.chunks_kept, k.size());
  EXPECT_EQ(slurp(p), whole);
  spit(p, "not an mcap file at all");
  EXPECT_THROW(repairMcap(p.string()), std::runtime_error);
  EXPECT_THROW(repairMcap((dir_ / "missing.mcap").string()), std::runtime_error);
}

// The real thing: a process SIGKILLed while recording loses at most the open
// chunk, i.e. the last chunk_max_age plus one tick period of log time.
TEST_F(Mcap, SamplesSigkillLosesAtMostTheOpenChunk) {
  const fs::path p = dir_ / "killed.mcap";
  const fs::path log = dir_ / "killed.log";
  const uint64_t kill_ms = 3'650;
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    McapWriter w;
    w.open(p.string());
    SimRun run(w, true);
    run.play(0, kill_ms);
    std::ofstream(log) << run.total << "\n";
    ::kill(::getpid(), SIGKILL);
    ::_exit(1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
  std::size_t written = 0;
  std::ifstream(log) >> written;
  ASSERT_GT(written, 100u);
  const Contents before = readLinear(slurp(p));
  const auto r = repairMcap(p.string());
  const std::string repaired = slurp(p);
  const Contents c = readLinear(repaired);
  ASSERT_TRUE(c.complete);
  EXPECT_EQ(c.messages.size(), before.messages.size());
  EXPECT_EQ(r.messages_kept, c.messages.size());
  EXPECT_LT(c.messages.size(), written);
  ASSERT_FALSE(c.messages.empty());
  uint64_t last = 0;
  for (const Msg& m : c.messages) last = std::max(last, m.log);
  EXPECT_GE(last + 1200 * kMs, kBase + kill_ms * kMs) << "more than chunk_max_age + a tick lost";
  sample("killed", repaired, c.counts, 3);
}

// Figures for docs/mcap.md: a minute of 50 Hz telemetry + 30 fps 2 Mbit/s video.
TEST_F(Mcap, FiguresPerMinute) {
  for (const bool video : {false, true}) {
    for (const char* compression : {"", "zstd"}) {
      McapWriterOptions o;
      o.compression = compression;
      const fs::path p = dir_ / "minute.mcap";
      McapWriter w(o);
      w.open(p.string());
      SimRun run(w, video);
      run.play(0, 60'000);
      w.close();
      const auto s = w.stats();
      const Contents c = readLinear(slurp(p));
      EXPECT_EQ(c.messages.size(), s.messages);
      std::printf("figures: %-9s compression %-4s: %9llu bytes/min (%llu uncompressed), %u chunks of %.1f KiB "
                  "(uncompressed), %.0f ms in write()\n",
                  video ? "telem+vid" : "telemetry", *compression ? compression : "none",
                  static_cast<unsigned long long>(s.file_bytes), static_cast<unsigned long long>(s.uncompressed_bytes),
                  s.chunks, s.uncompressed_bytes / 1024.0 / s.chunks, run.write_ms);
    }
  }
}

// Cost of fdatasync after every chunk (sync_chunks) on this machine's disk.
TEST_F(Mcap, FiguresFdatasyncPerChunk) {
  double ms[2] = {0, 0};
  uint32_t chunks = 0;
  for (const bool sync : {false, true}) {
    McapWriterOptions o;
    o.sync_chunks = sync;
    McapWriter w(o);
    w.open((dir_ / "sync.mcap").string());
    SimRun run(w, true);
    const auto t0 = std::chrono::steady_clock::now();
    run.play(0, 20'000);
    w.flushChunk();
    ms[sync] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    chunks = w.stats().chunks;
    w.close();
  }
  std::printf("figures: fdatasync per chunk (%u chunks of ~1 s): %.2f ms\n", chunks, (ms[1] - ms[0]) / chunks);
}

}  // namespace
