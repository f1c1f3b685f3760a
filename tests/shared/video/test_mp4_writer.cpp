// Mp4Writer: real libx264 streams of the synthetic scene into fragmented MP4
// files in a temp directory, read back by ffprobe (frame count, codec, size,
// duration) and by libavformat + our H264Decoder (time codes of the decoded
// pictures). Crash tolerance with a child process killed by SIGKILL, reading
// while writing, skipping before the first keyframe, garbage, timestamp
// repair, picture size change, open and write errors.
#include <gtest/gtest.h>

#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

extern "C" {
#include <libavformat/avformat.h>
}

#include "shared/video/frame_source.hpp"
#include "shared/video/h264_codec.hpp"
#include "shared/video/mp4_writer.hpp"
#include "shared/video/timecode.hpp"

using namespace inspect::video;
namespace fs = std::filesystem;

namespace {

constexpr int kFps = 30;
constexpr const char* kFfprobe = "/usr/bin/ffprobe";

// Capture time of frame i: 30 fps on an arbitrary clock.
uint64_t mp4CaptureUs(uint32_t i) { return 7'000'000'000ull + uint64_t{i} * 1'000'000 / kFps; }

// `n` frames of the synthetic scene, encoded (cached per size and GOP).
const std::vector<EncodedFrame>& stream(int width, int height, int gop, int n = 300) {
  static std::map<std::tuple<int, int, int, int>, std::vector<EncodedFrame>> cache;
  auto& frames = cache[{width, height, gop, n}];
  if (!frames.empty()) return frames;
  EncoderSettings s;
  s.width = width;
  s.height = height;
  s.gop = gop;
  H264Encoder enc(s);
  SyntheticSource src(width, height);
  for (uint32_t i = 0; i < static_cast<uint32_t>(n); ++i) {
    cv::Mat bgr;
    src.read(bgr, mp4CaptureUs(i), i);
    EncodedFrame f;
    if (!enc.encode(bgr, mp4CaptureUs(i), i, false, f)) throw std::runtime_error("encoder gave no frame");
    frames.push_back(std::move(f));
  }
  return frames;
}

bool put(Mp4Writer& w, const EncodedFrame& f) { return w.write(f.annexb.data(), f.annexb.size(), f.keyframe, f.capture_us); }

class TempDir {
 public:
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "mp4_writer_XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  fs::path path_;
};

struct Probe {
  int frames = -1;
  int width = 0;
  int height = 0;
  std::string codec;
  double duration = 0;
  std::string text;  // ffprobe's whole output, for failure messages
};

// The value of "key" in ffprobe's JSON (quotes removed), "" when absent.
std::string jsonValue(const std::string& json, const std::string& key) {
  auto at = json.find("\"" + key + "\"");
  if (at == std::string::npos) return "";
  at = json.find(':', at) + 1;
  const auto end = json.find_first_of(",\n}", at);
  std::string v = json.substr(at, end - at);
  std::erase_if(v, [](char c) { return c == '"' || c == ' '; });
  return v;
}

int toInt(const std::string& s) { return s.empty() ? -1 : std::stoi(s); }

Probe ffprobe(const std::string& path) {
  const std::string cmd = std::string(kFfprobe) +
                          " -v error -count_frames -show_entries "
                          "stream=nb_read_frames,width,height,codec_name:format=duration -of json '" +
                          path + "' 2>&1";
  Probe p;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (pipe == nullptr) return p;
  std::array<char, 4096> buf{};
  for (std::size_t got; (got = std::fread(buf.data(), 1, buf.size(), pipe)) > 0;) p.text.append(buf.data(), got);
  ::pclose(pipe);
  p.frames = toInt(jsonValue(p.text, "nb_read_frames"));
  p.width = toInt(jsonValue(p.text, "width"));
  p.height = toInt(jsonValue(p.text, "height"));
  p.codec = jsonValue(p.text, "codec_name");
  const std::string d = jsonValue(p.text, "duration");
  p.duration = d.empty() ? 0.0 : std::stod(d);
  return p;
}

// The file's samples, back to Annex B, with their times; and the time codes
// of the pictures our decoder makes of them.
struct Readback {
  std::vector<double> pts_s;
  std::vector<bool> key;
  std::vector<int64_t> codes;  // frame index read from each decoded picture, -1 when unreadable
  uint64_t decode_errors = 0;
};

Readback readBack(const std::string& path) {
  Readback r;
  AVFormatContext* ctx = nullptr;
  if (avformat_open_input(&ctx, path.c_str(), nullptr, nullptr) < 0) return r;
  const AVStream* st = ctx->streams[0];
  const AVCodecParameters* par = st->codecpar;
  // avcC gives the NAL unit length size.
  const int len_size = par->extradata_size > 4 && par->extradata[0] == 1 ? (par->extradata[4] & 3) + 1 : 4;
  H264Decoder dec;
  AVPacket* pkt = av_packet_alloc();
  while (av_read_frame(ctx, pkt) >= 0) {
    std::vector<uint8_t> annexb;
    for (int at = 0; at + len_size <= pkt->size;) {
      uint32_t len = 0;
      for (int i = 0; i < len_size; ++i) len = len << 8 | pkt->data[at + i];
      at += len_size;
      if (len > static_cast<uint32_t>(pkt->size - at)) break;
      annexb.insert(annexb.end(), {0, 0, 0, 1});
      annexb.insert(annexb.end(), pkt->data + at, pkt->data + at + len);
      at += static_cast<int>(len);
    }
    r.pts_s.push_back(static_cast<double>(pkt->pts) * av_q2d(st->time_base));
    r.key.push_back((pkt->flags & AV_PKT_FLAG_KEY) != 0);
    cv::Mat bgr;
    if (dec.decode(annexb.data(), annexb.size(), bgr)) {
      const auto code = readTimecode(bgr);
      r.codes.push_back(code ? static_cast<int64_t>(code->frame_index) : -1);
    }
    av_packet_unref(pkt);
  }
  r.decode_errors = dec.counters().errors;
  av_packet_free(&pkt);
  avformat_close_input(&ctx);
  return r;
}

// Top-level box types of an MP4 file.
std::vector<std::string> boxes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<std::string> types;
  for (std::array<unsigned char, 8> h{}; in.read(reinterpret_cast<char*>(h.data()), 8);) {
    uint64_t size = uint64_t{h[0]} << 24 | uint64_t{h[1]} << 16 | uint64_t{h[2]} << 8 | h[3];
    types.emplace_back(reinterpret_cast<const char*>(h.data()) + 4, 4);
    if (size < 8) break;  // 0 (to the end) or 64-bit sizes: the writer makes neither
    in.seekg(static_cast<std::streamoff>(size - 8), std::ios::cur);
  }
  return types;
}

int count(const std::vector<std::string>& v, const std::string& s) {
  return static_cast<int>(std::count(v.begin(), v.end(), s));
}

// Tests that read their file back with ffprobe: skipped without it.
class Mp4File : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kFfprobe)) GTEST_SKIP() << kFfprobe << " missing";
  }
  TempDir dir_;
  const std::string path_ = dir_.file("video.mp4");
};

// ffprobe and our decoder read `frames` pictures of width x height, one per
// 1/30 s from 0, whose time codes run from `first_code` on. Returns what our
// reader saw, for further checks.
Readback expectReadable(const std::string& path, int frames, int width, int height, int first_code) {
  const Probe p = ffprobe(path);
  EXPECT_EQ(p.frames, frames) << p.text;
  EXPECT_EQ(p.codec, "h264") << p.text;
  EXPECT_EQ(p.width, width) << p.text;
  EXPECT_EQ(p.height, height) << p.text;
  EXPECT_NEAR(p.duration, static_cast<double>(frames) / kFps, 0.05) << p.text;
  Readback r = readBack(path);
  EXPECT_EQ(r.decode_errors, 0u) << path;
  EXPECT_EQ(r.codes.size(), static_cast<std::size_t>(frames)) << path;
  if (r.codes.empty() || r.pts_s.empty()) {
    ADD_FAILURE() << path << ": nothing decoded";
    return r;
  }
  EXPECT_EQ(r.codes.front(), first_code) << path;
  EXPECT_EQ(r.codes.back(), first_code + frames - 1) << path;
  EXPECT_DOUBLE_EQ(r.pts_s.front(), 0.0) << path;
  return r;
}

// A whole 300-frame stream written and closed: every frame is in the file,
// ffprobe and our decoder read it, the times are the capture times.
void expectWholeStream(const std::string& path, int gop) {
  const auto& frames = stream(320, 240, gop);
  Mp4Writer w(path);
  for (const auto& f : frames) ASSERT_TRUE(put(w, f));
  w.close();
  const auto& c = w.counters();
  EXPECT_EQ(c.frames_written, 300u);
  EXPECT_EQ(c.frames_flushed, 300u);
  EXPECT_EQ(c.frames_skipped, 0u);
  EXPECT_EQ(c.frames_dropped, 0u);
  EXPECT_EQ(c.timestamps_fixed, 0u);
  EXPECT_EQ(c.files, 1u);
  EXPECT_EQ(c.fragments, 10u);  // a fragment a second, with 1 s GOPs and with 10 s GOPs
  EXPECT_EQ(c.bytes, fs::file_size(path));
  EXPECT_TRUE(w.error().empty());
  EXPECT_EQ(w.files(), std::vector<std::string>{path});

  const auto b = boxes(path);
  ASSERT_GE(b.size(), 2u);
  EXPECT_EQ(b[0], "ftyp");
  EXPECT_EQ(b[1], "moov");
  EXPECT_EQ(count(b, "moof"), static_cast<int>(c.fragments));
  EXPECT_EQ(count(b, "mdat"), static_cast<int>(c.fragments));
  EXPECT_EQ(b.back(), "mfra");

  const Readback r = expectReadable(path, 300, 320, 240, 0);
  ASSERT_EQ(r.pts_s.size(), 300u);
  for (std::size_t i = 0; i < r.pts_s.size(); ++i) {
    EXPECT_NEAR(r.pts_s[i], static_cast<double>(i) / kFps, 1e-4) << "frame " << i;
    EXPECT_EQ(r.key[i], frames[i].keyframe) << "frame " << i;
  }
}

// Waits up to `timeout_ms` for a child; kills it (SIGKILL) when it does not end.
// Returns its wait status, or -1 after a kill.
int waitChild(pid_t pid, int timeout_ms) {
  int status = 0;
  for (int waited = 0; waited < timeout_ms; waited += 5) {
    if (::waitpid(pid, &status, WNOHANG) == pid) return status;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  return -1;
}

}  // namespace

TEST_F(Mp4File, Gop30StreamReadsBackWhole) { expectWholeStream(path_, 30); }

TEST_F(Mp4File, Gop300StreamIsFragmentedEverySecond) { expectWholeStream(path_, 300); }

// Written by a child that is then SIGKILLed (no close, no trailer): every
// complete fragment reads back, the last second at most is lost.
TEST_F(Mp4File, SurvivesSigkill) {
  const auto& frames = stream(320, 240, 300);  // a 10 s GOP: only the 1 s limit ends fragments
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::close(fds[0]);
    Mp4Writer w(path_);
    for (int i = 0; i < 150; ++i) put(w, frames[i]);
    const uint64_t flushed = w.counters().frames_flushed;
    if (::write(fds[1], &flushed, sizeof flushed) != sizeof flushed) ::_exit(2);
    for (;;) ::pause();  // killed here, the writer open
  }
  ::close(fds[1]);
  uint64_t flushed = 0;
  pollfd pfd{fds[0], POLLIN, 0};
  const bool reported = ::poll(&pfd, 1, 10'000) == 1 && ::read(fds[0], &flushed, sizeof flushed) == sizeof flushed;
  ::close(fds[0]);
  ::kill(pid, SIGKILL);
  const int status = waitChild(pid, 5'000);
  ASSERT_TRUE(reported) << "the writer child did not report";
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);

  EXPECT_GE(flushed, 150u - kFps - 1);
  EXPECT_EQ(count(boxes(path_), "mfra"), 0);
  expectReadable(path_, static_cast<int>(flushed), 320, 240, 0);
}

// ffprobe reads the file while it is open: every complete fragment.
TEST_F(Mp4File, ReadableWhileWriting) {
  const auto& frames = stream(320, 240, 30);
  Mp4Writer w(path_);
  for (int i = 0; i < 100; ++i) ASSERT_TRUE(put(w, frames[i]));
  EXPECT_EQ(w.counters().frames_flushed, 90u);  // 3 fragments of 1 s; frames 90..99 not yet on disk
  EXPECT_EQ(w.counters().bytes, fs::file_size(path_));
  expectReadable(path_, 90, 320, 240, 0);
  for (int i = 100; i < 300; ++i) ASSERT_TRUE(put(w, frames[i]));
  w.close();
  expectReadable(path_, 300, 320, 240, 0);
}

// Frames before the first keyframe with SPS/PPS are skipped; garbage neither
// crashes the writer nor spoils the file.
TEST_F(Mp4File, SkipsUntilKeyframeAndSurvivesGarbage) {
  const auto& frames = stream(320, 240, 30);
  std::mt19937 rng(7);
  std::vector<uint8_t> noise(2000);
  for (auto& b : noise) b = static_cast<uint8_t>(rng());
  std::erase(noise, 0);  // no start code in it
  std::vector<uint8_t> fake_idr = {0, 0, 0, 1, 0x67};  // SPS, PPS and IDR slice of noise
  fake_idr.insert(fake_idr.end(), noise.begin(), noise.begin() + 40);
  fake_idr.insert(fake_idr.end(), {0, 0, 0, 1, 0x68});
  fake_idr.insert(fake_idr.end(), noise.begin() + 40, noise.begin() + 60);
  fake_idr.insert(fake_idr.end(), {0, 0, 0, 1, 0x65});
  fake_idr.insert(fake_idr.end(), noise.begin() + 60, noise.end());

  Mp4Writer w(path_);
  EXPECT_FALSE(w.write(noise.data(), noise.size(), true, mp4CaptureUs(0)));
  EXPECT_FALSE(w.write(fake_idr.data(), fake_idr.size(), true, mp4CaptureUs(1)));
  for (int i = 5; i < 30; ++i) EXPECT_FALSE(put(w, frames[i]));  // the stream joined mid-GOP
  EXPECT_TRUE(w.files().empty());
  EXPECT_FALSE(fs::exists(path_));
  EXPECT_EQ(w.counters().frames_skipped, 27u);

  for (int i = 30; i < 300; ++i) {
    ASSERT_TRUE(put(w, frames[i]));
    if (i == 100) {  // no NAL unit in these: dropped
      EXPECT_FALSE(w.write(noise.data(), noise.size(), false, mp4CaptureUs(i) + 1));
      EXPECT_FALSE(w.write(nullptr, 0, false, mp4CaptureUs(i) + 2));
      EXPECT_FALSE(w.write(noise.data(), 0, true, mp4CaptureUs(i) + 3));
    }
  }
  w.close();
  const auto& c = w.counters();
  EXPECT_EQ(c.frames_written, 270u);
  EXPECT_EQ(c.frames_skipped, 27u);
  EXPECT_EQ(c.frames_dropped, 3u);
  EXPECT_TRUE(w.error().empty());
  EXPECT_FALSE(w.write(frames[0].annexb.data(), frames[0].annexb.size(), true, mp4CaptureUs(400)));  // closed
  expectReadable(path_, 270, 320, 240, 30);
}

// Capture times that do not increase become previous + 1 tick.
TEST_F(Mp4File, RepairsNonIncreasingCaptureTimes) {
  const auto& frames = stream(320, 240, 30);
  Mp4Writer w(path_);
  for (int i = 0; i < 60; ++i) {
    uint64_t t = frames[i].capture_us;
    if (i == 10) t = frames[9].capture_us;       // repeated
    if (i == 20) t = frames[19].capture_us - 5;  // backwards
    ASSERT_TRUE(w.write(frames[i].annexb.data(), frames[i].annexb.size(), frames[i].keyframe, t));
  }
  w.close();
  EXPECT_EQ(w.counters().timestamps_fixed, 2u);
  const Readback r = expectReadable(path_, 60, 320, 240, 0);
  ASSERT_EQ(r.pts_s.size(), 60u);
  for (std::size_t i = 1; i < r.pts_s.size(); ++i) EXPECT_GT(r.pts_s[i], r.pts_s[i - 1]) << "frame " << i;
  EXPECT_NEAR(r.pts_s[10], r.pts_s[9] + 1.0 / 90000, 1e-6);
  EXPECT_NEAR(r.pts_s[11], 11.0 / kFps, 1e-4);
}

// A keyframe with another picture size closes the file and continues in <stem>-2.mp4.
TEST_F(Mp4File, PictureSizeChangeContinuesInNextFile) {
  const auto& small = stream(256, 192, 30, 60);
  const auto& large = stream(320, 240, 30);
  Mp4Writer w(path_);
  for (int i = 0; i < 60; ++i) ASSERT_TRUE(put(w, large[i]));
  for (int i = 0; i < 60; ++i) {
    EncodedFrame f = small[i];
    f.capture_us = mp4CaptureUs(60 + i);
    ASSERT_TRUE(put(w, f));
  }
  w.close();
  const std::string second = dir_.file("video-2.mp4");
  EXPECT_EQ(w.files(), (std::vector<std::string>{path_, second}));
  EXPECT_EQ(w.counters().files, 2u);
  EXPECT_EQ(w.counters().frames_written, 120u);
  EXPECT_EQ(w.counters().bytes, fs::file_size(path_) + fs::file_size(second));
  expectReadable(path_, 60, 320, 240, 0);
  expectReadable(second, 60, 256, 192, 0);
}

TEST(Mp4Writer, OpenErrorNamesPathAndCause) {
  const auto& frames = stream(320, 240, 30);
  const std::string path = "/nonexistent-dir-for-mp4-test/video.mp4";
  Mp4Writer w(path);
  EXPECT_FALSE(put(w, frames[1]));  // nothing opened before a keyframe
  try {
    put(w, frames[0]);
    FAIL() << "no VideoError";
  } catch (const VideoError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("No such file or directory"), std::string::npos) << e.what();
  }
  Mp4Settings bad;
  bad.max_fragment_s = 0;
  EXPECT_THROW(Mp4Writer("x.mp4", bad), VideoError);
  EXPECT_THROW(Mp4Writer(""), VideoError);
}

// A write error after open (the file size limit, in a child) is reported once
// and stops the writer; nothing crashes or throws.
TEST(Mp4Writer, WriteErrorStopsTheWriter) {
  const auto& frames = stream(320, 240, 30);
  TempDir dir;
  const std::string path = dir.file("video.mp4");
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::signal(SIGXFSZ, SIG_IGN);  // write() fails with EFBIG instead
    const rlimit limit{20'000, 20'000};
    if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) ::_exit(10);
    try {
      Mp4Writer w(path);
      int refused = 0;
      for (int i = 0; i < 120; ++i) refused += put(w, frames[i]) ? 0 : 1;
      w.close();
      if (w.error().find(path) == std::string::npos) ::_exit(11);
      if (refused == 0 || w.counters().frames_dropped != static_cast<uint64_t>(refused)) ::_exit(12);
      if (w.counters().files != 1 || w.counters().fragments != 0) ::_exit(13);
    } catch (...) {
      ::_exit(14);
    }
    ::_exit(0);
  }
  const int status = waitChild(pid, 10'000);
  ASSERT_TRUE(WIFEXITED(status)) << "status " << status;
  EXPECT_EQ(WEXITSTATUS(status), 0);
}
