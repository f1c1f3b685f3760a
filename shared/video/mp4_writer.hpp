#pragma once
// Recording of the encoded stream to a fragmented MP4 (`<run>/video.mp4`)
// through libavformat, without re-encoding. The file is playable while it is
// being written and after a crash (SIGKILL, power loss after the page cache
// reached the disk): it is `ftyp` + an empty `moov` + one `moof`/`mdat` pair
// per fragment, and every complete fragment is on disk.
//
// - Nothing is opened until the first keyframe carrying SPS and PPS; frames
//   before it are skipped (counted). Those SPS/PPS (Annex B) become the
//   stream's extradata; the mp4 muxer turns them into the `avcC` box and
//   rewrites every access unit from Annex B to 4-byte length prefixes.
//   In-band SPS/PPS stay in the samples (harmless, and they keep each
//   fragment decodable on its own).
// - Timestamps come from the capture times: 90 kHz, the file's first frame at
//   0, strictly increasing (a capture time not after the previous one is
//   moved to the previous + 1 tick, counted). Each access unit is held until
//   the next one arrives so that its duration is exact; close() gives the
//   last one the previous frame's duration.
// - A fragment ends at every keyframe (movflags frag_keyframe) and at the
//   latest after `max_fragment_s` of video, so a crash loses at most that
//   much (plus the one held frame); each fragment is flushed to the file at
//   once. close() writes the last fragment and the `mfra` index.
// - A keyframe whose SPS gives another picture size closes the file and
//   continues in `<stem>-2.mp4` (then -3, ...), each starting at time 0.
// - Errors: opening the first file throws VideoError (the path and libav's
//   text). Any later failure (a write, or opening a continuation file) is
//   logged once, kept in error(), and the writer stops: later frames are
//   dropped (counted), nothing throws.
// Not thread-safe: one thread writes.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace inspect::video {

struct Mp4Settings {
  double max_fragment_s = 1.0;  // longest fragment, (0, 60] s: the most a crash loses
  double nominal_fps = 30.0;    // (0, 240]: the last frame's duration when no interval is known
};

/// Checks the settings; returns "" or a message naming the bad field and its range.
std::string validate(const Mp4Settings& s);

struct Mp4Counters {
  uint64_t frames_written = 0;    // access units taken into a file
  uint64_t frames_flushed = 0;    // of those, in complete fragments on disk (what a crash keeps)
  uint64_t frames_skipped = 0;    // before the first keyframe with SPS/PPS
  uint64_t frames_dropped = 0;    // no NAL unit in them, or after a write error
  uint64_t timestamps_fixed = 0;  // capture time not after the previous frame's
  uint64_t fragments = 0;         // moof/mdat pairs written, all files
  uint64_t bytes = 0;             // bytes in the files, all files
  uint64_t files = 0;             // files opened (more than 1 after a picture size change)
};

class Mp4Writer {
 public:
  /// Checks the settings (VideoError when bad); opens nothing yet.
  explicit Mp4Writer(std::string path, Mp4Settings s = {});
  ~Mp4Writer();  // close()
  Mp4Writer(const Mp4Writer&) = delete;
  Mp4Writer& operator=(const Mp4Writer&) = delete;

  /// One access unit (Annex B) with its keyframe flag and capture time (µs,
  /// any monotonic clock). Returns true when it was taken into the file,
  /// false when it was skipped or dropped (counters say which). Throws
  /// VideoError only when the first file cannot be opened.
  bool write(const uint8_t* annexb, std::size_t size, bool keyframe, uint64_t capture_us);

  /// Writes the held frame, the last fragment and the trailer, and closes the
  /// file. Idempotent; later write()s are dropped.
  void close();

  const Mp4Counters& counters() const;
  /// The files opened so far, in order (the path given, then `<stem>-2.mp4` ...).
  const std::vector<std::string>& files() const;
  /// The first error after opening (path and libav's text), "" when none.
  const std::string& error() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace inspect::video
