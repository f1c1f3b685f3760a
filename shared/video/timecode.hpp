#pragma once
// A machine-readable time code drawn into video frames, so that glass-to-glass
// latency and frame loss can be read off any decoded picture (ours, ffplay's
// or GStreamer's) without trusting a sender's metadata.
//
// Layout (docs/video.md): two rows of black/white blocks across the top of the
// picture, block width = width / 64 (at least 4 px), block height = 2 x block
// width. Row 0: 48-bit capture time in microseconds (low 48 bits of the
// sender's CLOCK_MONOTONIC) followed by CRC-8 of those 6 bytes; row 1: 32-bit
// frame index followed by CRC-8 of those 4 bytes. Bits are most significant
// first, white = 1. The first and last block of each row are white guards.
#include <cstdint>
#include <optional>

#include <opencv2/core.hpp>

namespace inspect::video {

struct Timecode {
  uint64_t capture_us = 0;  // low 48 bits as drawn
  uint32_t frame_index = 0;
};

/// Draws the code into a BGR (CV_8UC3) or grey (CV_8UC1) picture, in place.
void drawTimecode(cv::Mat& image, uint64_t capture_us, uint32_t frame_index);

/// Reads the code back from a BGR or grey picture. nullopt when a CRC fails
/// (picture too damaged, or no code in it).
std::optional<Timecode> readTimecode(const cv::Mat& image);

/// Same, from the luma plane of a YUV picture (e.g. a GStreamer I420 frame).
std::optional<Timecode> readTimecodeLuma(const uint8_t* y, int width, int height, int stride);

/// Puts a 48-bit time read from a code back on the full 64-bit clock, given a
/// full reading `now_us` of the same clock taken shortly after.
uint64_t unwrapCaptureUs(uint64_t low48, uint64_t now_us);

}  // namespace inspect::video
