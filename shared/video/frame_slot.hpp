#pragma once
// A frame slot: one producer hands its newest picture to readers in other
// processes through a shared file mapping (mcu_sim's simulated camera ->
// robot_client's `sim:PATH` video source; docs/video.md "Frame slot").
//
// The file (a path on /dev/shm keeps it in memory) is a 4096-byte header and
// three picture buffers. The writer fills the buffers in turn, each under a
// sequence lock of its own (odd while being written), then publishes the
// frame's number; a reader copies the newest buffer and checks its lock
// before and after, retrying when they differ, so it never returns a torn
// picture, and nobody ever waits for anybody: a slow reader only skips
// frames. A reader waiting for the next frame sleeps on a futex in the
// header (woken at every frame) with a bounded timeout.
//
// Header layout (little-endian, offsets in bytes):
//   0  char[8]  magic "INSPFRM\0"        8  u32 version (1)
//  12  u32 header bytes (4096)          16  u32 width     20 u32 height
//  24  u32 row stride (width x 3)       28  u32 pixel format (1 = BGR, 8 bits each)
//  32  u32 buffers (3)                  36  u32 writer pid
//  40  u32 frame rate x 1000            44  u32 state (1 = writing, 2 = closed)
//  48  u64 buffer stride                56  u64 picture bytes (stride x height)
//  64  u64 newest frame number (0 = none yet; frame n is in buffer n mod 3)
//  72  u32 futex word (+1 per frame and at close)
// Buffer i at 4096 + i x stride: u64 lock (2n - 1 while frame n is written,
// 2n once written), u64 frame number, u64 capture time (us, CLOCK_MONOTONIC),
// u32 frame index; the picture's rows from +64.
#include <sys/types.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

namespace inspect::video {

inline constexpr char kFrameSlotMagic[8] = {'I', 'N', 'S', 'P', 'F', 'R', 'M', '\0'};
inline constexpr uint32_t kFrameSlotVersion = 1;

/// What a reader gets with a picture.
struct SlotFrame {
  uint64_t seq = 0;         // the writer's frame number, 1, 2, ...
  uint64_t capture_us = 0;  // when the picture was taken (CLOCK_MONOTONIC, us)
  uint32_t frame_index = 0; // the producer's frame counter (drawn in the time code)
};

/// The producer's end. Not thread-safe: one thread writes.
class FrameSlotWriter {
 public:
  /// Makes the slot at `path` for width x height BGR pictures: the file is
  /// made under a temporary name and renamed into place, so a reader never
  /// opens a half-made one. A previous frame slot at `path` is replaced (its
  /// readers see it go quiet); any other file there is left alone (error).
  /// Throws VideoError naming the path.
  FrameSlotWriter(std::string path, int width, int height, double fps);
  /// Marks the slot closed (waking the readers) and removes the file if it is
  /// still this writer's.
  ~FrameSlotWriter();
  FrameSlotWriter(const FrameSlotWriter&) = delete;
  FrameSlotWriter& operator=(const FrameSlotWriter&) = delete;

  /// Publishes one picture: `height` rows of width x 3 bytes, `step` bytes apart.
  void write(const uint8_t* bgr, std::size_t step, uint64_t capture_us, uint32_t frame_index);

  const std::string& path() const { return path_; }
  int width() const { return width_; }
  int height() const { return height_; }
  uint64_t framesWritten() const { return seq_; }

 private:
  std::string path_;
  int width_, height_;
  uint8_t* map_ = nullptr;
  std::size_t map_bytes_ = 0;
  uint64_t seq_ = 0;
  dev_t dev_ = 0;
  ino_t ino_ = 0;
};

/// A consumer's end: maps an existing slot read-only.
class FrameSlotReader {
 public:
  /// Throws VideoError "<path>: <why>": not found, cannot open, not a frame
  /// slot, another version, a bad or truncated header.
  explicit FrameSlotReader(std::string path);
  ~FrameSlotReader();
  FrameSlotReader(const FrameSlotReader&) = delete;
  FrameSlotReader& operator=(const FrameSlotReader&) = delete;

  int width() const { return width_; }
  int height() const { return height_; }
  double fps() const { return fps_; }
  pid_t writerPid() const { return writer_pid_; }
  const std::string& path() const { return path_; }

  /// Number of the newest complete frame (0: none yet).
  uint64_t latestSeq() const;
  /// True once the writer has closed the slot (it stopped).
  bool closed() const;
  /// True while the writer's process exists.
  bool writerAlive() const;

  /// Waits (at most `timeout`) for a frame newer than `after`, then copies the
  /// newest one into `dst` (height rows of width x 3 bytes, `step` apart).
  /// nullopt when none came in time or the slot was closed with no frame newer
  /// than `after` (frames written before the close stay readable). Never a torn
  /// picture: a copy overtaken by the writer is taken again.
  std::optional<SlotFrame> readNewer(uint64_t after, uint8_t* dst, std::size_t step,
                                     std::chrono::milliseconds timeout);

 private:
  std::string path_;
  const uint8_t* map_ = nullptr;
  std::size_t map_bytes_ = 0;
  int width_ = 0, height_ = 0;
  double fps_ = 0;
  pid_t writer_pid_ = 0;
};

}  // namespace inspect::video
