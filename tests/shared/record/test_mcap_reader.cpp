// McapReader and exportCsv (shared/record): files written by McapWriter read
// back with their embedded schemas only, cut-off and corrupt files, CSV export.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>
#include <gtest/gtest.h>

#include <algorithm>

#include "foxglove/CompressedVideo.pb.h"
#include "inspect_robot/v1/link.pb.h"
#include "shared/record/csv_export.hpp"
#include "shared/record/mcap_reader.hpp"
#include "shared/record/mcap_writer.hpp"
#include "tests/shared/record/mcap_test_files.hpp"

namespace {

using inspect::test::kBase;
using inspect::test::kMs;
using inspect::test::kSecond;
using inspect::test::slurp;
using inspect::test::spit;

namespace fs = std::filesystem;
using inspect::record::exportCsv;
using inspect::record::McapReader;
using inspect::record::McapWriter;
using inspect::record::McapWriterOptions;

constexpr int kBatches = 4;                            // one chunk each
constexpr int kTicks = 10;                             // telemetry messages per batch
const std::string kTelemetry = "/telemetry", kEvent = "/event", kVideo = "/camera/front";

struct Sent {
  std::string topic;
  uint64_t log = 0, publish = 0;
  std::string data, debug;  // serialized, ShortDebugString
};

std::vector<std::string> lines(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

std::vector<std::string> split(const std::string& line) {  // no quoted cells
  std::vector<std::string> out;
  std::stringstream s(line);
  for (std::string c; std::getline(s, c, ',');) out.push_back(c);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

// Offsets of the top-level Chunk records of a file.
std::vector<std::size_t> chunkOffsets(std::string_view file) {
  std::vector<std::size_t> out;
  for (std::size_t pos = 8; pos + 9 <= file.size();) {  // pos grows by a whole record every pass
    uint64_t len = 0;
    for (int i = 8; i >= 1; --i) len = len << 8 | static_cast<uint8_t>(file[pos + i]);
    if (file[pos] == 0x06) out.push_back(pos);
    pos += 9 + len;
  }
  return out;
}

// kBatches chunks of kTicks telemetry (every 20 ms), an event and 4 video frames each.
std::vector<Sent> writeRun(const fs::path& path, const std::string& compression) {
  McapWriterOptions o;
  o.compression = compression;
  o.chunk_size = 1 << 30;
  o.chunk_max_age_ns = 3600'000 * kMs;  // chunks close at flushChunk() only
  McapWriter w(o);
  w.open(path.string());
  const uint16_t tel = w.addProtobufChannel(inspect::v1::Telemetry::descriptor(), kTelemetry);
  const uint16_t ev = w.addProtobufChannel(inspect::v1::Event::descriptor(), kEvent);
  const uint16_t vid = w.addProtobufChannel(foxglove::CompressedVideo::descriptor(), kVideo);
  std::vector<Sent> sent;
  auto send = [&](uint16_t channel, const std::string& topic, uint64_t log, uint64_t publish,
                  const google::protobuf::Message& m) {
    w.write(channel, log, publish, m);
    sent.push_back({topic, log, publish, m.SerializeAsString(), m.ShortDebugString()});
  };
  for (int b = 0; b < kBatches; ++b) {
    for (int j = 0; j < kTicks; ++j) {
      const int i = b * kTicks + j;
      const uint64_t log = kBase + static_cast<uint64_t>(i) * 20 * kMs;
      const uint64_t robot_us = 5000 + static_cast<uint64_t>(i) * 20'000;
      inspect::v1::Telemetry t;
      t.set_robot_time_us(robot_us);
      t.mutable_pose()->set_x_m(i * 0.5);
      t.mutable_pose()->set_y_m(-i);
      for (int k = 0; k < i % 5; ++k) t.add_ultrasonic_m(0.25 * (k + 1) + i);
      t.add_gas(400 + i);
      t.add_gas(0.1);
      t.set_mode(i % 2 ? inspect::v1::TELEOP : inspect::v1::IDLE);
      t.set_track_controller(i % 3 ? "fuzzy_pid" : "");
      if (i % 2 == 0) {
        t.mutable_video()->set_enabled(true);
        t.mutable_video()->set_width(640);
        t.mutable_video()->set_encoder("libx264");
      }
      send(tel, kTelemetry, log, robot_us * 1000, t);
      if (j == 5) {
        inspect::v1::Event e;
        e.set_kind(inspect::v1::Event::MODE_CHANGE);
        e.set_text("stop, then \"go\", batch " + std::to_string(b));
        e.set_robot_time_us(robot_us);
        send(ev, kEvent, log + 1, robot_us * 1000, e);
      }
      if (j % 3 == 0) {
        foxglove::CompressedVideo v;
        v.mutable_timestamp()->set_seconds(static_cast<int64_t>(log / 1'000'000'000));
        v.mutable_timestamp()->set_nanos(static_cast<int32_t>(log % 1'000'000'000));
        v.set_frame_id("camera");
        v.set_format("h264");
        v.set_data(std::string(100 + i, static_cast<char>(i)));
        send(vid, kVideo, log + 2, log, v);
      }
    }
    w.flushChunk();
  }
  w.close();
  return sent;
}

class McapRead : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("mcap_read_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!std::getenv("MCAP_READ_KEEP")) fs::remove_all(dir_);
  }
  fs::path dir_;
};

// Every message back in file order, with its times, and decoded from the
// embedded schema to exactly what was written.
void expectReadsBack(const McapReader& r, const std::vector<Sent>& sent, std::size_t prefix) {
  ASSERT_EQ(r.messageCount(), prefix);
  std::size_t n = 0;
  r.forEach([&](const McapReader::MessageView& m) {
    const Sent& s = sent.at(n++);
    EXPECT_EQ(m.topic, s.topic) << n;
    EXPECT_EQ(m.log_time_ns, s.log) << n;
    EXPECT_EQ(m.publish_time_ns, s.publish) << n;
    EXPECT_EQ(m.data, s.data) << n;
    const auto decoded = r.decode(m);
    EXPECT_EQ(decoded->ShortDebugString(), s.debug) << n;
    return true;
  });
  EXPECT_EQ(n, prefix);
}

TEST_F(McapRead, ReadsBackEveryChannelWithEmbeddedSchemas) {
  for (const std::string compression : {"zstd", ""}) {
    SCOPED_TRACE("compression '" + compression + "'");
    const fs::path p = dir_ / "run.mcap";
    const std::vector<Sent> sent = writeRun(p, compression);
    const McapReader r = McapReader::open(p.string());
    EXPECT_FALSE(r.truncated());
    EXPECT_EQ(r.chunkCount(), static_cast<uint32_t>(kBatches));
    ASSERT_EQ(r.channels().size(), 3u);
    ASSERT_EQ(r.schemas().size(), 3u);
    std::map<std::string, uint64_t> by_topic;
    for (const auto& [id, n] : r.channelMessageCounts()) by_topic[r.channels().at(id).topic] = n;
    EXPECT_EQ(by_topic, (std::map<std::string, uint64_t>{{kTelemetry, 40}, {kEvent, 4}, {kVideo, 16}}));
    const McapReader::Channel& tel = r.channels().at(1);
    EXPECT_EQ(tel.topic, kTelemetry);
    EXPECT_EQ(tel.schema_name, "inspect.v1.Telemetry");
    EXPECT_EQ(tel.message_encoding, "protobuf");
    EXPECT_EQ(r.channels().at(3).schema_name, "foxglove.CompressedVideo");
    expectReadsBack(r, sent, sent.size());

    // Field values through reflection on the dynamic type (not the compiled one).
    std::size_t seen = 0;
    r.forEach([&](const McapReader::MessageView& m) {
      if (m.topic != kTelemetry || seen++ != 7) return true;
      const auto msg = r.decode(m);
      const google::protobuf::Descriptor* d = msg->GetDescriptor();
      EXPECT_NE(d, inspect::v1::Telemetry::descriptor());
      const google::protobuf::Reflection* ref = msg->GetReflection();
      const auto& pose = ref->GetMessage(*msg, d->FindFieldByName("pose"));
      EXPECT_EQ(pose.GetReflection()->GetDouble(pose, pose.GetDescriptor()->FindFieldByName("x_m")), 3.5);
      const auto* us = d->FindFieldByName("ultrasonic_m");
      EXPECT_EQ(ref->FieldSize(*msg, us), 2);
      if (ref->FieldSize(*msg, us) == 2) {
        EXPECT_EQ(ref->GetRepeatedDouble(*msg, us, 1), 7.5);
      }
      EXPECT_EQ(ref->GetEnum(*msg, d->FindFieldByName("mode"))->name(), "TELEOP");
      EXPECT_FALSE(ref->HasField(*msg, d->FindFieldByName("video")));  // odd ticks: no video status
      return false;  // stops the walk
    });
    EXPECT_EQ(seen, 8u);
  }
}

TEST_F(McapRead, CutFileReadsTheCompleteChunksAndSaysTruncated) {
  const fs::path p = dir_ / "run.mcap";
  const std::vector<Sent> sent = writeRun(p, "zstd");
  const std::string bytes = slurp(p);
  const std::vector<std::size_t> chunks = chunkOffsets(bytes);
  ASSERT_EQ(chunks.size(), static_cast<std::size_t>(kBatches));
  const std::size_t per_batch = sent.size() / kBatches;  // 10 telemetry, 1 event, 4 frames
  const fs::path cut = dir_ / "cut.mcap";

  spit(cut, std::string_view(bytes).substr(0, chunks[2] + (chunks[3] - chunks[2]) / 2));  // mid chunk 3
  McapReader r = McapReader::open(cut.string());
  EXPECT_TRUE(r.truncated());
  EXPECT_EQ(r.chunkCount(), 2u);
  EXPECT_LE(r.completeBytes(), chunks[2]);
  expectReadsBack(r, sent, 2 * per_batch);

  spit(cut, std::string_view(bytes).substr(0, chunks[3]));  // right before chunk 4, no DataEnd
  r = McapReader::open(cut.string());
  EXPECT_TRUE(r.truncated());
  EXPECT_EQ(r.completeBytes(), chunks[3]);
  expectReadsBack(r, sent, 3 * per_batch);

  spit(cut, std::string_view(bytes).substr(0, bytes.size() - 20));  // in the footer: every message there
  r = McapReader::open(cut.string());
  EXPECT_TRUE(r.truncated());
  expectReadsBack(r, sent, sent.size());

  spit(cut, std::string_view(bytes).substr(0, chunks[1] + 30));  // repaired: complete again
  inspect::record::repairMcap(cut.string());
  r = McapReader::open(cut.string());
  EXPECT_FALSE(r.truncated());
  expectReadsBack(r, sent, per_batch);

  spit(cut, std::string_view(bytes).substr(0, 12));  // mid header: nothing, but no error
  r = McapReader::open(cut.string());
  EXPECT_TRUE(r.truncated());
  EXPECT_EQ(r.messageCount(), 0u);
}

void expectOpenThrows(const fs::path& p, const std::string& what) {
  try {
    McapReader::open(p.string());
    ADD_FAILURE() << "no exception for " << p;
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

TEST_F(McapRead, BadFilesThrowNamingTheFile) {
  const fs::path text = dir_ / "notes.txt";
  spit(text, "time,value\n1,2\n");
  expectOpenThrows(text, "not an MCAP file");
  expectOpenThrows(dir_ / "missing.mcap", "cannot open");

  const fs::path p = dir_ / "run.mcap";
  writeRun(p, "");
  std::string bytes = slurp(p);
  const std::vector<std::size_t> chunks = chunkOffsets(bytes);
  ASSERT_GE(chunks.size(), 2u);
  bytes[(chunks[0] + chunks[1]) / 2] ^= 0x40;  // a byte in chunk 1's records (uncompressed)
  const fs::path bad = dir_ / "bad_crc.mcap";
  spit(bad, bytes);
  expectOpenThrows(bad, "CRC");
}

TEST_F(McapRead, ExportCsvFlattensEveryChannel) {
  const fs::path p = dir_ / "run.mcap";
  writeRun(p, "zstd");
  const fs::path out = dir_ / "csv";
  const auto result = exportCsv(p.string(), out.string());
  EXPECT_EQ(result.rows, (std::map<std::string, uint64_t>{{kTelemetry, 40}, {kEvent, 4}, {kVideo, 16}}));
  ASSERT_EQ(result.files.at(kVideo), (out / "camera_front.csv").string());

  const std::vector<std::string> tel = lines(result.files.at(kTelemetry));
  ASSERT_EQ(tel.size(), 41u);
  const std::vector<std::string> header = split(tel[0]);
  auto col = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    return it == header.end() ? -1 : static_cast<int>(it - header.begin());
  };
  EXPECT_EQ(col("log_time_s"), 0);
  EXPECT_EQ(col("publish_time_s"), 1);
  for (const char* name : {"robot_time_us", "pose.x_m", "pose.theta_rad", "ultrasonic_m[0]", "ultrasonic_m[3]",
                           "gas[1]", "mode", "serial.bad_crc", "video.encoder", "track_controller"})
    EXPECT_GE(col(name), 0) << name;
  EXPECT_EQ(col("ultrasonic_m[4]"), -1);  // at most 4 in the file
  EXPECT_LT(col("pose.x_m"), col("pose.y_m"));
  const std::vector<std::string> row = split(tel[1 + 7]);  // tick 7
  ASSERT_EQ(row.size(), header.size());
  EXPECT_EQ(row[0], "1763800000.140000000");
  EXPECT_EQ(row[1], "0.145000000");
  EXPECT_EQ(row[col("pose.x_m")], "3.5");
  EXPECT_EQ(row[col("pose.y_m")], "-7");
  EXPECT_EQ(row[col("ultrasonic_m[1]")], "7.5");
  EXPECT_EQ(row[col("ultrasonic_m[2]")], "");  // tick 7 has 2 readings
  EXPECT_EQ(row[col("gas[0]")], "407");
  EXPECT_EQ(row[col("mode")], "TELEOP");
  EXPECT_EQ(row[col("video.encoder")], "");  // no video status on odd ticks
  EXPECT_EQ(row[col("serial.bad_crc")], "");  // never set
  EXPECT_EQ(split(tel[1 + 8])[col("video.encoder")], "libx264");
  EXPECT_EQ(split(tel[1 + 8])[col("video.width")], "640");

  const std::vector<std::string> ev = lines(result.files.at(kEvent));
  ASSERT_EQ(ev.size(), 5u);
  // Every field the schema declares is a column, nested gas_alarm ones too (empty here).
  EXPECT_EQ(ev[0].rfind("log_time_s,publish_time_s,kind,text,robot_time_us,gas_alarm.id,", 0), 0u) << ev[0];
  EXPECT_NE(ev[0].find(",gas_alarm.pose.x_m,"), std::string::npos) << ev[0];
  const std::string row2 = "1763800000.300000001,0.305000000,MODE_CHANGE,\"stop, then \"\"go\"\", batch 1\",305000";
  EXPECT_EQ(ev[2].rfind(row2 + ",", 0), 0u) << ev[2];
  // The rest empty (nested messages not set: gas_alarm, gains, stored), but
  // for the scalar gains_version, 0, after the gains columns.
  const auto zero = ev[2].find_first_not_of(',', row2.size());
  ASSERT_NE(zero, std::string::npos) << ev[2];
  EXPECT_EQ(ev[2][zero], '0') << ev[2];
  EXPECT_EQ(ev[2].find_first_not_of(',', zero + 1), std::string::npos) << "the rest empty: " << ev[2];
  const std::string header_before = ev[0].substr(0, ev[0].find(",gains_version,") + 1);
  EXPECT_EQ(std::count(ev[2].begin(), ev[2].begin() + static_cast<std::ptrdiff_t>(zero), ',') - 2,
            std::count(header_before.begin(), header_before.end(), ','))
      << "the 0 is in the gains_version column: " << ev[0];
  EXPECT_EQ(std::count(ev[2].begin(), ev[2].end(), ',') - 2, std::count(ev[0].begin(), ev[0].end(), ','))
      << "as many columns as the header (2 commas are in the quoted text)";

  const std::vector<std::string> video = lines(result.files.at(kVideo));
  ASSERT_EQ(video.size(), 17u);
  EXPECT_EQ(video[0], "log_time_s,publish_time_s,timestamp.seconds,timestamp.nanos,frame_id,format");
  EXPECT_EQ(video[2], "1763800000.060000002,1763800000.060000000,1763800000,60000000,camera,h264");
  const auto with_bytes = exportCsv(p.string(), (dir_ / "csv_bytes").string(), true);
  const std::vector<std::string> sized = lines(with_bytes.files.at(kVideo));
  EXPECT_EQ(sized[0], "log_time_s,publish_time_s,timestamp.seconds,timestamp.nanos,frame_id,data_bytes,format");
  EXPECT_EQ(split(sized[2])[5], "103");

  EXPECT_THROW(exportCsv((dir_ / "missing.mcap").string(), out.string()), std::runtime_error);
  spit(dir_ / "file", "x");
  try {
    exportCsv(p.string(), (dir_ / "file" / "sub").string());
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find((dir_ / "file").string()), std::string::npos) << e.what();
  }
}

}  // namespace
