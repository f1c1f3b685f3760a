#pragma once
// H.264 encode and decode through libavcodec, tuned for the lowest latency.
//
// Encoder: libx264 with zero-latency settings (no B-frames, no lookahead,
// ultrafast preset by default, capped VBR at the bitrate with a one-frame VBV
// buffer, GOP from the settings, optional periodic intra refresh instead of
// IDRs), or h264_v4l2m2m (the Pi's hardware encoder) when asked for and
// present; "auto" takes h264_v4l2m2m when it opens, else libx264. Output is
// Annex B with SPS/PPS in-band before every IDR (never in extradata only).
// Decoder: libavcodec h264, one thread, AV_CODEC_FLAG_LOW_DELAY, every
// decode error survived and counted.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "shared/video/frame_source.hpp"

namespace inspect::video {

struct EncoderSettings {
  int width = 640;             // even, [64, 4096]
  int height = 480;            // even, [64, 4096]
  double fps = 30.0;           // (0, 120]
  int bitrate_kbps = 2000;     // [50, 50000]
  int gop = 30;                // frames between IDRs, [1, 600]
  bool intra_refresh = false;  // periodic intra refresh (a moving intra column) instead of IDRs
  std::string codec = "libx264";   // "libx264", "h264_v4l2m2m" or "auto"
  std::string preset = "ultrafast";  // libx264 preset: ultrafast | superfast | veryfast
  int threads = 1;             // encoder threads (slice threads for libx264); 0 = auto
};

/// Checks the settings; returns "" or a message naming the bad field and its range.
std::string validate(const EncoderSettings& s);

struct EncodedFrame {
  std::vector<uint8_t> annexb;  // one access unit, Annex B start codes
  bool keyframe = false;        // IDR (with SPS/PPS before it)
  uint64_t capture_us = 0;
  uint32_t frame_index = 0;
};

class H264Encoder {
 public:
  /// Opens the encoder; throws VideoError naming the codec and the failure.
  explicit H264Encoder(const EncoderSettings& s);
  ~H264Encoder();
  H264Encoder(const H264Encoder&) = delete;
  H264Encoder& operator=(const H264Encoder&) = delete;

  /// Encodes one BGR picture of the configured size. `force_keyframe` makes
  /// this frame an IDR. Returns true and fills `out` when the encoder gave an
  /// access unit for it (zero-latency encoders always do), false otherwise;
  /// throws VideoError on a codec failure.
  bool encode(const cv::Mat& bgr, uint64_t capture_us, uint32_t frame_index, bool force_keyframe,
              EncodedFrame& out);

  /// Changes the bitrate from the next frame without a keyframe, where the
  /// encoder allows it (libx264 reconfigures its rate control in place:
  /// FFmpeg's libx264.c reconfig_encoder). False when it does not
  /// (h264_v4l2m2m): reopen the encoder. Throws VideoError out of range.
  bool setBitrate(int kbps);

  const std::string& codecName() const;  // the libavcodec encoder in use
  const EncoderSettings& settings() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct DecoderCounters {
  uint64_t frames_in = 0;   // access units given
  uint64_t pictures = 0;    // pictures out
  uint64_t errors = 0;      // access units the decoder refused
};

class H264Decoder {
 public:
  H264Decoder();  // throws VideoError when libavcodec has no h264 decoder
  ~H264Decoder();
  H264Decoder(const H264Decoder&) = delete;
  H264Decoder& operator=(const H264Decoder&) = delete;

  /// Decodes one Annex B access unit. Returns true and fills `bgr` (CV_8UC3)
  /// when a picture came out; false when none did (decoder error: lastError()
  /// names it, counted; or nothing to show yet). Never throws on bad data.
  /// A picture the decoder had to conceal (damaged data) counts as an error
  /// and is not returned.
  bool decode(const uint8_t* data, std::size_t size, cv::Mat& bgr);
  /// Same, without the colour conversion: the luma plane only (cheaper).
  bool decodeLuma(const uint8_t* data, std::size_t size, cv::Mat& grey);

  const DecoderCounters& counters() const;
  const std::string& lastError() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Names of the H.264 encoders this libavcodec has (e.g. "libx264", "h264_v4l2m2m").
std::vector<std::string> availableH264Encoders();

}  // namespace inspect::video
