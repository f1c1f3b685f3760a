// Time code, frame sources and the H.264 encoder/decoder (libavcodec): round
// trips on raw and coded pictures, GOP structure and in-band SPS/PPS, intra
// refresh, RTP packetization of real access units, decoder robustness, and
// settings/source errors.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>

#include <opencv2/imgproc.hpp>

#include "shared/video/frame_source.hpp"
#include "shared/video/h264_codec.hpp"
#include "shared/video/rtp_h264.hpp"
#include "shared/video/timecode.hpp"

using namespace inspect::video;

namespace {

constexpr uint64_t kMask48 = (uint64_t{1} << 48) - 1;

EncoderSettings settings(int width, int height, int kbps = 2000, int gop = 30) {
  EncoderSettings s;
  s.width = width;
  s.height = height;
  s.bitrate_kbps = kbps;
  s.gop = gop;
  return s;
}

// Capture time of frame i (arbitrary, beyond 32 bits so that all 48 are used).
uint64_t captureUs(uint32_t i) { return 0x1234'5678'9ABCull + 33'333ull * i; }

struct Coded {
  std::vector<cv::Mat> pictures;  // what went in
  std::vector<EncodedFrame> frames;
};

// `n` synthetic pictures through the encoder; frames listed in `force` are forced IDRs.
Coded encodeSynthetic(const EncoderSettings& s, int n, const std::vector<int>& force = {}) {
  H264Encoder enc(s);
  SyntheticSource src(s.width, s.height);
  Coded c;
  for (int i = 0; i < n; ++i) {
    cv::Mat bgr;
    const auto idx = static_cast<uint32_t>(i);
    src.read(bgr, captureUs(idx), idx);
    EncodedFrame f;
    const bool forced = std::find(force.begin(), force.end(), i) != force.end();
    EXPECT_TRUE(enc.encode(bgr, captureUs(idx), idx, forced, f)) << "frame " << i;
    EXPECT_EQ(f.frame_index, idx);
    EXPECT_EQ(f.capture_us, captureUs(idx));
    c.pictures.push_back(bgr);
    c.frames.push_back(std::move(f));
  }
  return c;
}

std::vector<uint8_t> nalTypes(const std::vector<uint8_t>& annexb) {
  std::vector<uint8_t> types;
  for (const auto& nal : splitAnnexB(annexb)) types.push_back(nalType(nal[0]));
  return types;
}

bool hasIdr(const std::vector<uint8_t>& annexb) {
  const auto t = nalTypes(annexb);
  return std::find(t.begin(), t.end(), kNalIdr) != t.end();
}

// A keyframe starts SPS, PPS (then SEI or the IDR slice).
void expectParameterSetsFirst(const EncodedFrame& f, int i) {
  const auto t = nalTypes(f.annexb);
  ASSERT_GE(t.size(), 3u) << "frame " << i;
  EXPECT_EQ(t[0], kNalSps) << "frame " << i;
  EXPECT_EQ(t[1], kNalPps) << "frame " << i;
}

// A busy picture to draw codes on: noise, so that nothing reads by accident.
cv::Mat noise(int width, int height, int type, unsigned seed) {
  cv::Mat m(height, width, type);
  cv::theRNG().state = seed;
  cv::randu(m, 0, 256);
  return m;
}

std::filesystem::path tempPath(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("inspect_test_codec_" + std::to_string(::getpid()) + "_" + name);
}

}  // namespace

// ---------------------------------------------------------------- time code

TEST(Timecode, RoundTripBgrGreyAndLuma) {
  const std::vector<std::pair<uint64_t, uint32_t>> values = {
      {0, 0}, {kMask48, 0xFFFFFFFFu}, {0xA5A5'5A5A'F00Dull, 0x8000'0001u}, {123'456'789, 42}};
  for (const auto& size : {cv::Size(640, 480), cv::Size(1280, 720), cv::Size(320, 240)}) {
    for (const auto& [us, idx] : values) {
      cv::Mat bgr = noise(size.width, size.height, CV_8UC3, 7);
      drawTimecode(bgr, us, idx);
      auto tc = readTimecode(bgr);
      ASSERT_TRUE(tc) << size;
      EXPECT_EQ(tc->capture_us, us & kMask48);
      EXPECT_EQ(tc->frame_index, idx);

      cv::Mat grey = noise(size.width, size.height, CV_8UC1, 8);
      drawTimecode(grey, us, idx);
      tc = readTimecode(grey);
      ASSERT_TRUE(tc) << size;
      EXPECT_EQ(tc->capture_us, us & kMask48);
      EXPECT_EQ(tc->frame_index, idx);

      // A luma plane with a stride wider than the picture.
      cv::Mat padded = noise(size.width + 32, size.height, CV_8UC1, 9);
      cv::Mat luma = padded(cv::Rect(0, 0, size.width, size.height));
      drawTimecode(luma, us, idx);
      tc = readTimecodeLuma(luma.data, luma.cols, luma.rows, static_cast<int>(luma.step));
      ASSERT_TRUE(tc) << size;
      EXPECT_EQ(tc->capture_us, us & kMask48);
      EXPECT_EQ(tc->frame_index, idx);
    }
  }
}

TEST(Timecode, HighBitsDroppedAndDamageRejected) {
  cv::Mat bgr(480, 640, CV_8UC3, cv::Scalar(90, 90, 90));
  drawTimecode(bgr, (uint64_t{0xBEEF} << 48) | 77, 5);
  auto tc = readTimecode(bgr);
  ASSERT_TRUE(tc);
  EXPECT_EQ(tc->capture_us, 77u);

  EXPECT_FALSE(readTimecode(cv::Mat(480, 640, CV_8UC3, cv::Scalar(128, 128, 128))));  // no code
  EXPECT_FALSE(readTimecode(cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(255))));        // no black block
  EXPECT_FALSE(readTimecode(cv::Mat()));
  EXPECT_FALSE(readTimecodeLuma(nullptr, 640, 480, 640));

  // One flipped block in either row fails its CRC (blocks are 10 x 20 px at 640 wide).
  for (int row = 0; row < 2; ++row) {
    cv::Mat damaged = bgr.clone();
    cv::Mat block = damaged(cv::Rect(10 * 20, 20 * row, 10, 20));
    block = cv::Scalar::all(255) - block;
    EXPECT_FALSE(readTimecode(damaged)) << "row " << row;
  }
}

TEST(Timecode, UnwrapCaptureUs) {
  constexpr uint64_t kWrap = uint64_t{1} << 48;
  const uint64_t now = 5 * kWrap + 1'000'000'000;
  EXPECT_EQ(unwrapCaptureUs((now - 40'000) & kMask48, now), now - 40'000);  // 40 ms ago
  EXPECT_EQ(unwrapCaptureUs((now + 500'000) & kMask48, now), now + 500'000);  // within the slack
  EXPECT_EQ(unwrapCaptureUs((now + 2'000'000) & kMask48, now), now + 2'000'000 - kWrap);  // beyond: a wrap ago
  // Across a 48-bit wrap: the code was written just before the low bits wrapped.
  const uint64_t after_wrap = 3 * kWrap + 10'000;
  EXPECT_EQ(unwrapCaptureUs(kWrap - 20'000, after_wrap), 3 * kWrap - 20'000);
  // A clock that never wrapped.
  EXPECT_EQ(unwrapCaptureUs(1'000, 2'000), 1'000u);
}

// Two GOPs at 1000 kbps. Every picture reads at 640x480; at 1280x720 the
// one-frame VBV leaves a mid-stream IDR about 4 KB, which can blur the code
// on it and the P frame after it (297 of 300 frames read, measured), so
// there at most those two may go unread. A code read is never wrong.
TEST(Timecode, SurvivesH264At1000Kbps) {
  for (const auto& size : {cv::Size(640, 480), cv::Size(1280, 720)}) {
    const Coded c = encodeSynthetic(settings(size.width, size.height, 1000, 30), 60);
    H264Decoder bgr_dec, luma_dec;
    int unread = 0;
    for (std::size_t i = 0; i < c.frames.size(); ++i) {
      const auto& au = c.frames[i].annexb;
      cv::Mat bgr, grey;
      ASSERT_TRUE(bgr_dec.decode(au.data(), au.size(), bgr)) << size << " frame " << i << ": " << bgr_dec.lastError();
      ASSERT_TRUE(luma_dec.decodeLuma(au.data(), au.size(), grey)) << size << " frame " << i;
      ASSERT_EQ(grey.type(), CV_8UC1);
      ASSERT_EQ(grey.size(), size);
      const auto tc = readTimecode(bgr);
      const auto tl = readTimecodeLuma(grey.data, grey.cols, grey.rows, static_cast<int>(grey.step));
      EXPECT_EQ(tc.has_value(), tl.has_value()) << size << " frame " << i;
      if (!tc) {
        ++unread;
        continue;
      }
      EXPECT_EQ(tc->capture_us, captureUs(static_cast<uint32_t>(i)) & kMask48) << size << " frame " << i;
      EXPECT_EQ(tc->frame_index, i) << size << " frame " << i;
      if (tl) {
        EXPECT_EQ(tl->frame_index, i) << size << " frame " << i;
      }
    }
    EXPECT_LE(unread, size.width == 640 ? 0 : 2) << size;
  }
}

// ---------------------------------------------------------------- sources

TEST(FrameSource, SyntheticIsDeterministicAndMoves) {
  SyntheticSource src(640, 480);
  EXPECT_FALSE(src.paced());
  EXPECT_EQ(src.describe(), "synthetic 640x480");
  cv::Mat a, b, c;
  ASSERT_TRUE(src.read(a, 1000, 10));
  ASSERT_TRUE(src.read(b, 1000, 10));
  ASSERT_TRUE(src.read(c, 1000, 11));
  EXPECT_EQ(a.type(), CV_8UC3);
  EXPECT_EQ(a.size(), cv::Size(640, 480));
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a, c, cv::NORM_L1), 1000.0);
  const auto tc = readTimecode(c);
  ASSERT_TRUE(tc);
  EXPECT_EQ(tc->frame_index, 11u);
  EXPECT_EQ(tc->capture_us, 1000u);

  auto s = openFrameSource(SourceSettings{});
  EXPECT_EQ(s->describe(), "synthetic 640x480");
}

TEST(FrameSource, MissingDeviceOrFileThrows) {
  SourceSettings s;
  for (const std::string uri : {"v4l2:/dev/video99", "/dev/video99"}) {
    s.uri = uri;
    try {
      openFrameSource(s);
      ADD_FAILURE() << uri << " opened";
    } catch (const VideoError& e) {
      EXPECT_NE(std::string(e.what()).find("/dev/video99"), std::string::npos) << e.what();
    }
  }
  s.uri = "file:/nonexistent.mp4";
  EXPECT_THROW(openFrameSource(s), VideoError);
  s.uri = "/nonexistent.mkv";
  EXPECT_THROW(openFrameSource(s), VideoError);
  s.uri = "webcam";
  EXPECT_THROW(openFrameSource(s), VideoError);
  // A file that is no video.
  const auto junk = tempPath("junk.mp4");
  std::ofstream(junk) << "not a video";
  s.uri = "file:" + junk.string();
  EXPECT_THROW(openFrameSource(s), VideoError);
  std::filesystem::remove(junk);
}

// Raw Annex B from our encoder at 320x240, read back at 640x480, looping or not.
TEST(FrameSource, FileSourceResizesAndLoops) {
  constexpr int kFileFrames = 12;
  const auto path = tempPath("clip.h264");
  {
    const Coded c = encodeSynthetic(settings(320, 240, 500, 6), kFileFrames);
    std::ofstream out(path, std::ios::binary);
    for (const auto& f : c.frames) out.write(reinterpret_cast<const char*>(f.annexb.data()), f.annexb.size());
  }
  SourceSettings s;
  s.uri = "file:" + path.string();
  s.loop_file = true;
  auto looping = openFrameSource(s);
  EXPECT_FALSE(looping->paced());
  cv::Mat bgr;
  for (int i = 0; i < kFileFrames + 5; ++i) {
    ASSERT_TRUE(looping->read(bgr, 0, i)) << "frame " << i << ": " << looping->error();
    ASSERT_EQ(bgr.type(), CV_8UC3);
    ASSERT_EQ(bgr.size(), cv::Size(640, 480));
  }

  s.uri = path.string();  // a bare path with a video extension
  s.loop_file = false;
  s.width = 160;
  s.height = 120;
  auto once = openFrameSource(s);
  int n = 0;
  while (n < 3 * kFileFrames && once->read(bgr, 0, n)) {
    ASSERT_EQ(bgr.size(), cv::Size(160, 120));
    ++n;
  }
  EXPECT_EQ(n, kFileFrames);
  EXPECT_NE(once->error().find("end of file"), std::string::npos) << once->error();
  std::filesystem::remove(path);
}

// ---------------------------------------------------------------- encoder / decoder

TEST(H264, SettingsValidated) {
  EXPECT_EQ(validate(EncoderSettings{}), "");
  auto bad = [](auto change) {
    EncoderSettings s;
    change(s);
    return validate(s);
  };
  EXPECT_EQ(bad([](auto& s) { s.bitrate_kbps = 20; }), "video.bitrate_kbps: 20 out of range [50, 50000]");
  EXPECT_EQ(bad([](auto& s) { s.width = 32; }), "video.width: 32 out of range [64, 4096]");
  EXPECT_EQ(bad([](auto& s) { s.height = 5000; }), "video.height: 5000 out of range [64, 4096]");
  EXPECT_EQ(bad([](auto& s) { s.width = 641; }), "video.width: 641 is odd (must be even)");
  EXPECT_EQ(bad([](auto& s) { s.fps = 0; }), "video.fps: 0 out of range (0, 120]");
  EXPECT_EQ(bad([](auto& s) { s.gop = 0; }), "video.gop: 0 out of range [1, 600]");
  EXPECT_EQ(bad([](auto& s) { s.threads = -1; }), "video.threads: -1 out of range [0, 16]");
  EXPECT_NE(bad([](auto& s) { s.codec = "vp8"; }).find("video.codec: 'vp8'"), std::string::npos);
  EXPECT_NE(bad([](auto& s) { s.preset = "slow"; }).find("video.preset: 'slow'"), std::string::npos);
  try {
    H264Encoder enc(settings(640, 480, 20));
    ADD_FAILURE() << "opened";
  } catch (const VideoError& e) {
    EXPECT_NE(std::string(e.what()).find("video.bitrate_kbps: 20"), std::string::npos) << e.what();
  }
}

TEST(H264, EncodersListedAndAutoOpens) {
  const auto names = availableH264Encoders();
  EXPECT_NE(std::find(names.begin(), names.end(), "libx264"), names.end());
  EncoderSettings s = settings(320, 240);
  s.codec = "auto";
  H264Encoder enc(s);  // h264_v4l2m2m where there is one, else libx264
  EXPECT_TRUE(enc.codecName() == "libx264" || enc.codecName() == "h264_v4l2m2m") << enc.codecName();
  EXPECT_EQ(enc.settings().width, 320);
  cv::Mat wrong(100, 100, CV_8UC3, cv::Scalar::all(0));
  EncodedFrame f;
  EXPECT_THROW(enc.encode(wrong, 0, 0, false, f), VideoError);
}

// Slice threads and the faster presets keep one access unit out per frame in.
TEST(H264, ThreadsAndPresetsAddNoDelay) {
  for (const auto& [threads, preset] : {std::pair{2, "superfast"}, std::pair{0, "veryfast"}}) {
    EncoderSettings s = settings(640, 480);
    s.threads = threads;
    s.preset = preset;
    const Coded c = encodeSynthetic(s, 5);  // checks every encode() gives its frame
    H264Decoder dec;
    for (const auto& f : c.frames) {
      cv::Mat bgr;
      EXPECT_TRUE(dec.decode(f.annexb.data(), f.annexb.size(), bgr)) << preset << ": " << dec.lastError();
    }
  }
}

TEST(H264, SyntheticRoundTripQualityAndIndex) {
  const Coded c = encodeSynthetic(settings(640, 480), 60);
  H264Decoder dec;
  for (std::size_t i = 0; i < c.frames.size(); ++i) {
    cv::Mat bgr;
    const auto& au = c.frames[i].annexb;
    ASSERT_TRUE(dec.decode(au.data(), au.size(), bgr)) << "frame " << i << ": " << dec.lastError();
    ASSERT_EQ(bgr.size(), c.pictures[i].size());
    EXPECT_GT(cv::PSNR(c.pictures[i], bgr), 30.0) << "frame " << i;
    const auto tc = readTimecode(bgr);
    ASSERT_TRUE(tc) << "frame " << i;
    EXPECT_EQ(tc->frame_index, i);
  }
  EXPECT_EQ(dec.counters().frames_in, 60u);
  EXPECT_EQ(dec.counters().pictures, 60u);
  EXPECT_EQ(dec.counters().errors, 0u);
}

TEST(H264, KeyframeEveryGopWithSpsPps) {
  constexpr int kGop = 10;
  const Coded c = encodeSynthetic(settings(320, 240, 1000, kGop), 35);
  for (std::size_t i = 0; i < c.frames.size(); ++i) {
    const auto& f = c.frames[i];
    const bool expect_key = i % kGop == 0;
    EXPECT_EQ(f.keyframe, expect_key) << "frame " << i;
    EXPECT_EQ(hasIdr(f.annexb), expect_key) << "frame " << i;
    if (expect_key) expectParameterSetsFirst(f, static_cast<int>(i));
  }
}

TEST(H264, ForcedKeyframeIsIdrMidGop) {
  const Coded c = encodeSynthetic(settings(320, 240, 1000, 30), 12, {7});
  for (std::size_t i = 1; i < c.frames.size(); ++i) EXPECT_EQ(c.frames[i].keyframe, i == 7) << "frame " << i;
  EXPECT_TRUE(hasIdr(c.frames[7].annexb));
  expectParameterSetsFirst(c.frames[7], 7);
}


// Rate adaptation's path into libx264: a new bitrate takes effect from the
// next frames without an IDR (rate control reconfigured in place).
TEST(H264, BitrateChangesInPlaceWithoutAKeyframe) {
  const EncoderSettings s = settings(640, 480, 3000, 300);
  H264Encoder enc(s);
  SyntheticSource src(s.width, s.height);
  H264Decoder dec;
  std::size_t before = 0, after = 0;
  for (uint32_t i = 0; i < 90; ++i) {
    if (i == 45) {
      ASSERT_TRUE(enc.setBitrate(300));
    }
    cv::Mat bgr, out;
    src.read(bgr, captureUs(i), i);
    EncodedFrame f;
    ASSERT_TRUE(enc.encode(bgr, captureUs(i), i, false, f)) << "frame " << i;
    EXPECT_EQ(f.keyframe, i == 0) << "frame " << i;
    ASSERT_TRUE(dec.decode(f.annexb.data(), f.annexb.size(), out)) << "frame " << i;
    if (i >= 15 && i < 45) before += f.annexb.size();
    if (i >= 60) after += f.annexb.size();
  }
  EXPECT_EQ(enc.settings().bitrate_kbps, 300);
  // 30 frames each: about 3000 vs 300 kbit/s (12.5 kB vs 1.25 kB a frame).
  EXPECT_LT(after * 4, before) << "before " << before << " after " << after;
  EXPECT_GT(after, 30u * 300);  // still a picture: not starved
  EXPECT_THROW(enc.setBitrate(20), VideoError);
  EXPECT_EQ(dec.counters().errors, 0u);
}
TEST(H264, IntraRefreshHasOneIdrAndDecodes) {
  EncoderSettings s = settings(640, 480, 1500, 15);
  s.intra_refresh = true;
  const Coded c = encodeSynthetic(s, 45);
  EXPECT_TRUE(c.frames[0].keyframe);
  expectParameterSetsFirst(c.frames[0], 0);
  H264Decoder dec;
  for (std::size_t i = 0; i < c.frames.size(); ++i) {
    if (i > 0) {
      EXPECT_FALSE(hasIdr(c.frames[i].annexb)) << "frame " << i;
      EXPECT_FALSE(c.frames[i].keyframe) << "frame " << i;
    }
    cv::Mat bgr;
    ASSERT_TRUE(dec.decode(c.frames[i].annexb.data(), c.frames[i].annexb.size(), bgr)) << "frame " << i;
    EXPECT_GT(cv::PSNR(c.pictures[i], bgr), 30.0) << "frame " << i;
  }
  EXPECT_EQ(dec.counters().errors, 0u);
}

// Real access units through the RTP layer (payload 1160, reordered in
// pairs) decode to exactly the pictures the unpacketized stream gives.
TEST(H264, RtpPacketizedStreamDecodesIdentically) {
  const Coded c = encodeSynthetic(settings(640, 480, 2000, 15), 40);
  H264Packetizer pz(0x1234, 1160, 65500);  // sequence numbers wrap on the way
  std::vector<std::vector<uint8_t>> packets;
  for (std::size_t i = 0; i < c.frames.size(); ++i)
    pz.packetize(c.frames[i].annexb, static_cast<uint32_t>(i * 3000), c.frames[i].capture_us, packets);
  EXPECT_GT(packets.size(), c.frames.size());  // the IDRs took several packets
  for (std::size_t i = 1; i + 1 < packets.size(); i += 3) std::swap(packets[i], packets[i + 1]);

  ReorderBuffer reorder;
  H264Depacketizer depack;
  std::vector<Frame> received;
  std::vector<std::pair<uint32_t, std::vector<uint8_t>>> ready;
  auto drain = [&] {
    for (auto& [skipped, datagram] : ready) {
      RtpPacket p;
      ASSERT_EQ(parseRtp(datagram, p), RtpError::kNone);
      if (auto f = depack.push(p, skipped)) received.push_back(std::move(*f));
    }
    ready.clear();
  };
  for (auto& d : packets) {
    RtpPacket p;
    ASSERT_EQ(parseRtp(d, p), RtpError::kNone);
    const uint16_t seq = p.seq;
    ASSERT_TRUE(reorder.push(seq, std::move(d)));
    reorder.pop(ready);
    drain();
  }
  reorder.flush(ready);
  drain();
  ASSERT_EQ(received.size(), c.frames.size());
  EXPECT_EQ(depack.counters().frames_dropped, 0u);

  H264Decoder direct, via_rtp;
  for (std::size_t i = 0; i < received.size(); ++i) {
    EXPECT_EQ(received[i].capture_us, c.frames[i].capture_us);
    EXPECT_EQ(received[i].keyframe, c.frames[i].keyframe) << "frame " << i;
    EXPECT_EQ(received[i].has_parameter_sets, c.frames[i].keyframe) << "frame " << i;
    cv::Mat a, b;
    ASSERT_TRUE(direct.decode(c.frames[i].annexb.data(), c.frames[i].annexb.size(), a));
    ASSERT_TRUE(via_rtp.decode(received[i].annexb.data(), received[i].annexb.size(), b)) << via_rtp.lastError();
    EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << "frame " << i;
  }
}

TEST(H264, DecoderSurvivesBadInputAndRecoversAtIdr) {
  constexpr int kGop = 10;
  const Coded c = encodeSynthetic(settings(640, 480, 2000, kGop), 21);
  const auto& idr0 = c.frames[0].annexb;
  const auto& p1 = c.frames[1].annexb;
  cv::Mat bgr;

  // A P frame before any IDR: nothing to decode it against.
  H264Decoder dec;
  EXPECT_FALSE(dec.decode(p1.data(), p1.size(), bgr));
  EXPECT_EQ(dec.counters().errors, 1u);
  EXPECT_FALSE(dec.lastError().empty());

  // Garbage: random bytes, random bytes behind start codes, empty and tiny units.
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> byte(0, 255);
  uint64_t garbage = 0;
  for (int k = 0; k < 40; ++k) {
    std::vector<uint8_t> junk(1 + k * 97);
    for (auto& b : junk) b = static_cast<uint8_t>(byte(rng));
    if (k % 2 == 1 && junk.size() > 5) junk[0] = 0, junk[1] = 0, junk[2] = 0, junk[3] = 1;  // a "NAL" of random type
    EXPECT_FALSE(dec.decode(junk.data(), junk.size(), bgr)) << "junk " << k;
    ++garbage;
  }
  EXPECT_FALSE(dec.decode(nullptr, 0, bgr));
  EXPECT_GE(dec.counters().errors, 2u);
  EXPECT_EQ(dec.counters().pictures, 0u);

  // A truncated IDR: decoded with errors, concealed, refused.
  EXPECT_FALSE(dec.decode(idr0.data(), idr0.size() / 2, bgr));
  const uint64_t errors = dec.counters().errors;
  EXPECT_NE(dec.lastError().find("concealed"), std::string::npos) << dec.lastError();

  // The next intact IDR gives a clean picture again, and the P frames after it.
  for (int i = kGop; i < kGop + 3; ++i) {
    const auto& au = c.frames[i].annexb;
    ASSERT_TRUE(dec.decode(au.data(), au.size(), bgr)) << "frame " << i << ": " << dec.lastError();
    EXPECT_GT(cv::PSNR(c.pictures[i], bgr), 30.0) << "frame " << i;
  }
  EXPECT_EQ(dec.counters().errors, errors);

  // Truncated P frame, then garbage mid-stream: refused or concealed, never a crash.
  const auto& p = c.frames[kGop + 3].annexb;
  EXPECT_FALSE(dec.decode(p.data(), p.size() / 3, bgr));
  EXPECT_GT(dec.counters().errors, errors);
  for (int k = 0; k < 10; ++k) {
    std::vector<uint8_t> junk(500);
    for (auto& b : junk) b = static_cast<uint8_t>(byte(rng));
    junk[0] = 0, junk[1] = 0, junk[2] = 1, junk[3] = 0x41;  // a P slice header of random bits
    dec.decode(junk.data(), junk.size(), bgr);
  }
  const auto& idr2 = c.frames[2 * kGop].annexb;
  ASSERT_TRUE(dec.decode(idr2.data(), idr2.size(), bgr)) << dec.lastError();
  EXPECT_GT(cv::PSNR(c.pictures[2 * kGop], bgr), 30.0);
  EXPECT_EQ(dec.counters().frames_in, 1 + garbage + 1 + 1 + 3 + 1 + 10 + 1);
}
