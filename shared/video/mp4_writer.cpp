#include "shared/video/mp4_writer.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <filesystem>
#include <optional>
#include <tuple>
#include <utility>
#include <sstream>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/error.h>
#include <libavutil/log.h>
#include <libavutil/mem.h>
}

#include "shared/util/log.hpp"
#include "shared/video/frame_source.hpp"
#include "shared/video/rtp_h264.hpp"

namespace inspect::video {

namespace {

constexpr AVRational kMicros{1, 1'000'000};
constexpr AVRational kTimeBase{1, static_cast<int>(kClockRate)};  // 90 kHz, as RTP
// Fragmented from the start (an empty moov, then moof/mdat pairs), a fragment
// at each keyframe, and sample offsets relative to their own moof.
constexpr const char* kMovflags = "frag_keyframe+empty_moov+default_base_moof";

// "<path>: <what>: <libav's text for err>"
std::string failure(const std::string& path, const char* what, int err) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(err, text, sizeof text);
  return path + ": " + what + ": " + text;
}

struct ParameterSets {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> annexb;  // the SPS and PPS NAL units, 4-byte start codes
};

// The picture size the SPS of an access unit gives, read by libavcodec's h264
// parser (it needs the SPS, the PPS and a slice header).
std::optional<std::pair<int, int>> pictureSize(const uint8_t* data, std::size_t size) {
  const std::unique_ptr<AVCodecParserContext, decltype(&av_parser_close)> parser(av_parser_init(AV_CODEC_ID_H264),
                                                                                  &av_parser_close);
  AVCodecContext* ctx = avcodec_alloc_context3(nullptr);
  if (parser == nullptr || ctx == nullptr) {
    avcodec_free_context(&ctx);
    return std::nullopt;
  }
  ctx->codec_type = AVMEDIA_TYPE_VIDEO;
  ctx->codec_id = AV_CODEC_ID_H264;
  ctx->log_level_offset = AV_LOG_DEBUG - AV_LOG_ERROR;  // garbage is counted as skipped, not printed
  parser->flags |= PARSER_FLAG_COMPLETE_FRAMES;
  std::vector<uint8_t> padded(size + AV_INPUT_BUFFER_PADDING_SIZE, 0);  // the parser reads past the end
  std::copy(data, data + size, padded.begin());
  uint8_t* out = nullptr;
  int out_size = 0;
  av_parser_parse2(parser.get(), ctx, &out, &out_size, padded.data(), static_cast<int>(size), AV_NOPTS_VALUE,
                   AV_NOPTS_VALUE, 0);
  avcodec_free_context(&ctx);
  if (parser->width <= 0 || parser->height <= 0) return std::nullopt;
  return std::make_pair(parser->width, parser->height);
}

// The SPS/PPS of a keyframe and the picture size they give; nullopt when the
// access unit lacks either or they do not parse.
std::optional<ParameterSets> parameterSets(const uint8_t* data, std::size_t size) {
  ParameterSets ps;
  bool sps = false, pps = false;
  for (const auto& nal : splitAnnexB({data, size})) {
    const uint8_t type = nalType(nal[0]);
    if (type != kNalSps && type != kNalPps) continue;
    (type == kNalSps ? sps : pps) = true;
    ps.annexb.insert(ps.annexb.end(), {0, 0, 0, 1});
    ps.annexb.insert(ps.annexb.end(), nal.begin(), nal.end());
  }
  if (!sps || !pps) return std::nullopt;
  const auto wh = pictureSize(data, size);
  if (!wh) return std::nullopt;
  std::tie(ps.width, ps.height) = *wh;
  return ps;
}

}  // namespace

std::string validate(const Mp4Settings& s) {
  std::ostringstream os;
  if (!(s.max_fragment_s > 0.0 && s.max_fragment_s <= 60.0)) {
    os << "video.mp4.max_fragment_s: " << s.max_fragment_s << " out of range (0, 60]";
  } else if (!(s.nominal_fps > 0.0 && s.nominal_fps <= 240.0)) {
    os << "video.mp4.nominal_fps: " << s.nominal_fps << " out of range (0, 240]";
  }
  return os.str();
}

struct Mp4Writer::Impl {
  std::string base_path;
  Mp4Settings settings;
  Mp4Counters c;
  std::vector<std::string> files;
  std::string error;
  bool closed = false;

  // The open file.
  AVFormatContext* fmt = nullptr;
  AVPacket* pkt = nullptr;
  int width = 0, height = 0;
  uint64_t first_us = 0;        // capture time of the file's first frame (time 0)
  int64_t last_duration = 0;    // the previous frame's duration, stream ticks
  int64_t max_fragment = 0;     // longest fragment, stream ticks
  int64_t frag_start = 0;       // dts of the current fragment's first frame
  uint64_t frag_frames = 0;     // frames in the current (unflushed) fragment
  uint64_t closed_bytes = 0;    // bytes of the files already closed

  // The last access unit, written when the next one gives its duration.
  std::vector<uint8_t> held;
  bool held_key = false;
  int64_t held_dts = 0;
  bool have_held = false;

  ~Impl() { release(); }

  AVRational timeBase() const { return fmt->streams[0]->time_base; }

  std::string nextPath() const {
    if (files.empty()) return base_path;
    const std::filesystem::path p(base_path);
    const std::string name = p.stem().string() + "-" + std::to_string(files.size() + 1) + p.extension().string();
    return (p.parent_path() / name).string();
  }

  // Opens the next file for a stream with these parameter sets, header written
  // and on disk. Throws VideoError; on success the writer state is reset.
  void open(const ParameterSets& ps, uint64_t capture_us) {
    const std::string path = nextPath();
    AVFormatContext* ctx = nullptr;
    int err = avformat_alloc_output_context2(&ctx, nullptr, "mp4", path.c_str());
    if (err < 0) throw VideoError(failure(path, "no mp4 muxer", err));
    std::unique_ptr<AVFormatContext, void (*)(AVFormatContext*)> guard(ctx, [](AVFormatContext* f) {
      avio_closep(&f->pb);
      avformat_free_context(f);
    });
    AVStream* st = avformat_new_stream(ctx, nullptr);
    auto* extradata = static_cast<uint8_t*>(av_mallocz(ps.annexb.size() + AV_INPUT_BUFFER_PADDING_SIZE));
    if (st == nullptr || extradata == nullptr) {
      av_free(extradata);
      throw VideoError(failure(path, "cannot set up the stream", AVERROR(ENOMEM)));
    }
    std::copy(ps.annexb.begin(), ps.annexb.end(), extradata);
    st->time_base = kTimeBase;
    AVCodecParameters* par = st->codecpar;
    par->codec_type = AVMEDIA_TYPE_VIDEO;
    par->codec_id = AV_CODEC_ID_H264;
    par->width = ps.width;
    par->height = ps.height;
    par->extradata = extradata;  // Annex B: the muxer writes it as avcC
    par->extradata_size = static_cast<int>(ps.annexb.size());
    if ((err = avio_open(&ctx->pb, path.c_str(), AVIO_FLAG_WRITE)) < 0) throw VideoError(failure(path, "cannot open", err));
    AVDictionary* opts = nullptr;
    av_dict_set(&opts, "movflags", kMovflags, 0);
    err = avformat_write_header(ctx, &opts);
    av_dict_free(&opts);
    if (err < 0) throw VideoError(failure(path, "cannot write the header", err));
    avio_flush(ctx->pb);  // ftyp + moov on disk now: the file is readable from the first fragment on
    if (ctx->pb->error < 0) throw VideoError(failure(path, "cannot write the header", ctx->pb->error));

    if (pkt == nullptr && (pkt = av_packet_alloc()) == nullptr) throw VideoError(failure(path, "no packet", AVERROR(ENOMEM)));
    fmt = guard.release();
    width = ps.width;
    height = ps.height;
    first_us = capture_us;
    last_duration = std::max<int64_t>(1, av_rescale_q(std::llround(1e6 / settings.nominal_fps), kMicros, timeBase()));
    max_fragment = av_rescale_q(std::llround(settings.max_fragment_s * 1e6), kMicros, timeBase());
    frag_frames = 0;
    have_held = false;
    files.push_back(path);
    ++c.files;
    c.bytes = closed_bytes + static_cast<uint64_t>(avio_tell(fmt->pb));
    log::info(log::tag::kVideo, "recording ", path, " (", width, "x", height, ", fragmented MP4)");
  }

  void release() {
    if (fmt != nullptr) {
      avio_closep(&fmt->pb);
      avformat_free_context(fmt);
      fmt = nullptr;
    }
    av_packet_free(&pkt);
    have_held = false;
  }

  // Records the first error after opening and stops the writer.
  void fail(const std::string& message) {
    if (error.empty()) {
      error = message;
      log::error(log::tag::kVideo, message, "; recording stopped");
    }
    release();
  }

  // A fragment of `frames` frames was handed to the file: push it to disk.
  bool fragmentDone(uint64_t frames) {
    avio_flush(fmt->pb);
    if (fmt->pb->error < 0) {
      fail(failure(files.back(), "write failed", fmt->pb->error));
      return false;
    }
    ++c.fragments;
    c.frames_flushed += frames;
    c.bytes = closed_bytes + static_cast<uint64_t>(avio_tell(fmt->pb));
    return true;
  }

  // Writes the held access unit with its duration; ends the fragment when it
  // reached the longest allowed.
  bool putHeld(int64_t duration) {
    pkt->data = held.data();
    pkt->size = static_cast<int>(held.size());
    pkt->pts = pkt->dts = held_dts;
    pkt->duration = duration;
    pkt->flags = held_key ? AV_PKT_FLAG_KEY : 0;
    pkt->stream_index = 0;
    const bool cuts = held_key && frag_frames > 0;  // frag_keyframe: the muxer ends the fragment before it
    const int err = av_write_frame(fmt, pkt);
    pkt->data = nullptr;
    pkt->size = 0;
    have_held = false;
    if (err < 0) {
      fail(failure(files.back(), "cannot write a frame", err));
      return false;
    }
    if (cuts && !fragmentDone(frag_frames)) return false;
    if (cuts || frag_frames == 0) {
      frag_start = held_dts;
      frag_frames = 0;
    }
    ++frag_frames;
    last_duration = duration;
    if (held_dts + duration - frag_start < max_fragment) return true;
    const int ret = av_write_frame(fmt, nullptr);  // ends the fragment (mp4 muxer: AVFMT_ALLOW_FLUSH)
    if (ret < 0) {
      fail(failure(files.back(), "cannot write a fragment", ret));
      return false;
    }
    const uint64_t frames = frag_frames;
    frag_frames = 0;
    return fragmentDone(frames);
  }

  // Writes the held frame, the last fragment and the trailer; closes the file.
  void finishFile() {
    if (fmt == nullptr) return;
    if (have_held && !putHeld(last_duration)) return;
    const std::string& path = files.back();
    const int err = av_write_trailer(fmt);
    if (err < 0) {
      fail(failure(path, "cannot write the trailer", err));
      return;
    }
    if (frag_frames > 0) {
      ++c.fragments;
      c.frames_flushed += frag_frames;
      frag_frames = 0;
    }
    avio_flush(fmt->pb);
    if (fmt->pb->error < 0) {
      fail(failure(path, "write failed", fmt->pb->error));
      return;
    }
    closed_bytes += static_cast<uint64_t>(avio_tell(fmt->pb));
    c.bytes = closed_bytes;
    const int close_err = avio_closep(&fmt->pb);
    if (close_err < 0) {
      fail(failure(path, "close failed", close_err));
      return;
    }
    avformat_free_context(fmt);
    fmt = nullptr;
  }

  bool write(const uint8_t* data, std::size_t size, bool keyframe, uint64_t capture_us) {
    if (closed || !error.empty()) {
      ++c.frames_dropped;
      return false;
    }
    if (data == nullptr || size == 0 || size > INT_MAX / 2 || splitAnnexB({data, size}).empty()) {
      ++(fmt == nullptr ? c.frames_skipped : c.frames_dropped);
      return false;
    }
    const auto ps = keyframe ? parameterSets(data, size) : std::nullopt;
    if (fmt == nullptr) {
      if (!ps) {
        ++c.frames_skipped;
        return false;
      }
      open(*ps, capture_us);  // throws: the first file
    } else if (ps && (ps->width != width || ps->height != height)) {
      log::warn(log::tag::kVideo, files.back(), ": picture size ", width, "x", height, " -> ", ps->width, "x", ps->height,
                ", continuing in a new file");
      finishFile();
      if (!error.empty()) {
        ++c.frames_dropped;
        return false;
      }
      try {
        open(*ps, capture_us);
      } catch (const VideoError& e) {
        fail(e.what());
        ++c.frames_dropped;
        return false;
      }
    }
    // The file's first frame (just opened, nothing held) is at 0.
    int64_t dts = av_rescale_q(static_cast<int64_t>(capture_us - first_us), kMicros, timeBase());
    if (have_held) {
      if (dts <= held_dts) {
        dts = held_dts + 1;
        ++c.timestamps_fixed;
      }
      if (!putHeld(dts - held_dts)) {
        ++c.frames_dropped;
        return false;
      }
    }
    held.assign(data, data + size);
    held_key = keyframe;
    held_dts = dts;
    have_held = true;
    ++c.frames_written;
    return true;
  }
};

Mp4Writer::Mp4Writer(std::string path, Mp4Settings s) : impl_(std::make_unique<Impl>()) {
  if (const std::string bad = validate(s); !bad.empty()) throw VideoError(bad);
  if (path.empty()) throw VideoError("video.mp4: empty path");
  impl_->base_path = std::move(path);
  impl_->settings = s;
}

Mp4Writer::~Mp4Writer() { close(); }

bool Mp4Writer::write(const uint8_t* annexb, std::size_t size, bool keyframe, uint64_t capture_us) {
  return impl_->write(annexb, size, keyframe, capture_us);
}

void Mp4Writer::close() {
  if (impl_->closed) return;
  impl_->finishFile();
  impl_->release();
  impl_->closed = true;
}

const Mp4Counters& Mp4Writer::counters() const { return impl_->c; }
const std::vector<std::string>& Mp4Writer::files() const { return impl_->files; }
const std::string& Mp4Writer::error() const { return impl_->error; }

}  // namespace inspect::video
