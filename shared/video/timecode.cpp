#include "shared/video/timecode.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace inspect::video {

namespace {

constexpr int kCaptureBits = 48;
constexpr int kIndexBits = 32;
constexpr int kCrcBits = 8;
constexpr uint64_t kMask48 = (uint64_t{1} << 48) - 1;
// A guard darker than this is no code at all.
constexpr double kMinGuard = 128.0;
// Every valid row has a black block (the CRC of all-ones data is not 0xFF), so
// a row without this much contrast between guard and darkest block is no code.
constexpr double kMinContrast = 64.0;
// A block this close to the threshold (fraction of the contrast) makes its row
// unreadable: rejecting it beats trusting an 8-bit CRC with a guessed bit.
constexpr double kAmbiguous = 0.1;

struct Geometry {
  int block_w;
  int block_h;
};

Geometry geometry(int width) {
  const int bw = std::max(4, width / 64);
  return {bw, 2 * bw};
}

// CRC-8, polynomial 0x07, initial value 0, no reflection.
uint8_t crc8(const uint8_t* data, std::size_t n) {
  uint8_t crc = 0;
  for (std::size_t i = 0; i < n; ++i) {
    crc ^= data[i];
    for (int b = 0; b < 8; ++b) crc = static_cast<uint8_t>((crc & 0x80) ? (crc << 1) ^ 0x07 : crc << 1);
  }
  return crc;
}

// The low N bytes of `v`, most significant first.
template <std::size_t N>
std::array<uint8_t, N> bigEndian(uint64_t v) {
  std::array<uint8_t, N> out{};
  for (std::size_t i = 0; i < N; ++i) out[i] = static_cast<uint8_t>(v >> (8 * (N - 1 - i)));
  return out;
}

// The bits of one row between its guards: `value` (N bytes) then its CRC-8.
template <std::size_t N>
std::vector<bool> rowBits(uint64_t value) {
  const auto bytes = bigEndian<N>(value);
  const uint64_t crc = crc8(bytes.data(), N);
  std::vector<bool> bits;
  for (int i = N * 8 - 1; i >= 0; --i) bits.push_back((value >> i) & 1);
  for (int i = kCrcBits - 1; i >= 0; --i) bits.push_back((crc >> i) & 1);
  return bits;
}

void drawRow(cv::Mat& image, int row, const std::vector<bool>& bits, Geometry g) {
  const cv::Rect bounds(0, 0, image.cols, image.rows);
  const int n = static_cast<int>(bits.size()) + 2;
  for (int i = 0; i < n; ++i) {
    const bool white = i == 0 || i == n - 1 || bits[i - 1];
    const cv::Rect block = cv::Rect(i * g.block_w, row * g.block_h, g.block_w, g.block_h) & bounds;
    if (block.area() > 0) image(block).setTo(cv::Scalar::all(white ? 255 : 0));
  }
}

// Reads one row of `nbits` data bits plus the CRC; `sample(x, y, w, h)` is
// the mean brightness of a patch. nullopt when a guard is dark or the CRC fails.
template <class Sample>
std::optional<uint64_t> readRow(int row, int nbits, Geometry g, int width, int height, const Sample& sample) {
  const int n = nbits + kCrcBits + 2;
  if (n * g.block_w > width || (row + 1) * g.block_h > height) return std::nullopt;
  const int pw = std::max(1, g.block_w / 2), ph = std::max(1, g.block_h / 2);
  std::vector<double> level(n);
  for (int i = 0; i < n; ++i)
    level[i] = sample(i * g.block_w + (g.block_w - pw) / 2, row * g.block_h + (g.block_h - ph) / 2, pw, ph);
  const double white = std::min(level.front(), level.back());
  if (white < kMinGuard) return std::nullopt;
  const double darkest = *std::min_element(level.begin(), level.end());
  if (white - darkest < kMinContrast) return std::nullopt;
  const double threshold = (white + darkest) / 2;
  for (int i = 1; i < n - 1; ++i)
    if (std::abs(level[i] - threshold) < kAmbiguous * (white - darkest)) return std::nullopt;
  uint64_t value = 0;
  for (int i = 1; i <= nbits; ++i) value = (value << 1) | (level[i] > threshold ? 1 : 0);
  uint8_t crc = 0;
  for (int i = nbits + 1; i <= nbits + kCrcBits; ++i) crc = static_cast<uint8_t>((crc << 1) | (level[i] > threshold ? 1 : 0));
  const int nbytes = nbits / 8;
  const auto bytes = bigEndian<8>(value);
  if (crc8(bytes.data() + 8 - nbytes, nbytes) != crc) return std::nullopt;
  return value;
}

template <class Sample>
std::optional<Timecode> readCode(int width, int height, const Sample& sample) {
  const Geometry g = geometry(width);
  const auto capture = readRow(0, kCaptureBits, g, width, height, sample);
  if (!capture) return std::nullopt;
  const auto index = readRow(1, kIndexBits, g, width, height, sample);
  if (!index) return std::nullopt;
  return Timecode{*capture, static_cast<uint32_t>(*index)};
}

}  // namespace

void drawTimecode(cv::Mat& image, uint64_t capture_us, uint32_t frame_index) {
  const Geometry g = geometry(image.cols);
  drawRow(image, 0, rowBits<6>(capture_us & kMask48), g);
  drawRow(image, 1, rowBits<4>(frame_index), g);
}

std::optional<Timecode> readTimecode(const cv::Mat& image) {
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3)) return std::nullopt;
  return readCode(image.cols, image.rows, [&](int x, int y, int w, int h) {
    const cv::Scalar m = cv::mean(image(cv::Rect(x, y, w, h)));
    if (image.channels() == 1) return m[0];
    return 0.114 * m[0] + 0.587 * m[1] + 0.299 * m[2];  // BGR -> grey (BT.601)
  });
}

std::optional<Timecode> readTimecodeLuma(const uint8_t* y, int width, int height, int stride) {
  if (y == nullptr || width <= 0 || height <= 0 || stride < width) return std::nullopt;
  return readCode(width, height, [&](int x0, int y0, int w, int h) {
    unsigned sum = 0;
    for (int r = y0; r < y0 + h; ++r)
      for (int c = x0; c < x0 + w; ++c) sum += y[static_cast<std::size_t>(r) * stride + c];
    return static_cast<double>(sum) / (w * h);
  });
}

uint64_t unwrapCaptureUs(uint64_t low48, uint64_t now_us) {
  constexpr uint64_t kSlackUs = 1'000'000;  // clock jitter between reader and writer
  constexpr uint64_t kWrap = uint64_t{1} << 48;
  low48 &= kMask48;
  const uint64_t latest = now_us + kSlackUs;
  const uint64_t candidate = (latest & ~kMask48) | low48;
  if (candidate <= latest) return candidate;
  return candidate >= kWrap ? candidate - kWrap : low48;  // the clock never wrapped: as read
}

}  // namespace inspect::video
