#include "shared/video/h264_codec.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <deque>
#include <map>
#include <mutex>
#include <sstream>

#include <opencv2/imgproc.hpp>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/buffer.h>
#include <libavutil/error.h>
#include <libavutil/opt.h>
#include <libavutil/pixdesc.h>
#include <libswscale/swscale.h>
}

#include "shared/util/log.hpp"
#include "shared/video/rtp_h264.hpp"

namespace inspect::video {

namespace {

std::string avError(int err) {
  char buf[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(err, buf, sizeof buf);
  return buf;
}

// FFmpeg's messages from the codec contexts opened here go to the project log
// at debug level (decoder errors are counted, not printed), and the first
// error-level one is kept for our error text. Other contexts print as usual.
std::mutex g_log_mutex;
std::map<const void*, std::string*> g_log_sinks;  // context -> first error message

void routeAvLog(void* avcl, int level, const char* fmt, va_list vl) {
  std::unique_lock lock(g_log_mutex);
  const auto it = avcl != nullptr ? g_log_sinks.find(avcl) : g_log_sinks.end();
  if (it == g_log_sinks.end()) {
    lock.unlock();
    av_log_default_callback(avcl, level, fmt, vl);
    return;
  }
  if (level > AV_LOG_INFO) return;
  char text[512];
  std::vsnprintf(text, sizeof text, fmt, vl);
  std::string line(text);
  while (!line.empty() && (line.back() == '\n' || line.back() == ' ')) line.pop_back();
  if (level <= AV_LOG_ERROR && it->second->empty()) *it->second = line;
  lock.unlock();
  log::debug("ffmpeg", line);
}

// Routes one codec context's messages while it lives.
class LogSink {
 public:
  LogSink() = default;
  LogSink(const LogSink&) = delete;
  LogSink& operator=(const LogSink&) = delete;
  ~LogSink() { attach(nullptr); }

  void attach(const AVCodecContext* ctx) {
    static std::once_flag once;
    std::call_once(once, [] { av_log_set_callback(routeAvLog); });
    const std::lock_guard lock(g_log_mutex);
    if (ctx_ != nullptr) g_log_sinks.erase(ctx_);
    ctx_ = ctx;
    first_error_.clear();
    if (ctx_ != nullptr) g_log_sinks[ctx_] = &first_error_;
  }
  /// " (message)" for the first error logged since the last call, or "".
  std::string take() {
    const std::lock_guard lock(g_log_mutex);
    std::string detail = first_error_.empty() ? "" : " (" + first_error_ + ")";
    first_error_.clear();
    return detail;
  }

 private:
  const AVCodecContext* ctx_ = nullptr;
  std::string first_error_;
};

template <class T>
std::string outOfRange(const char* field, T value, const char* range) {
  std::ostringstream os;
  os << "video." << field << ": " << value << " out of range " << range;
  return os.str();
}

// Frames an asynchronous encoder (h264_v4l2m2m) may hold before its packets come out.
constexpr std::size_t kMaxInFlight = 64;

bool isVcl(uint8_t type) { return type >= kNalSlice && type <= kNalIdr; }

void appendNal(std::vector<uint8_t>& out, std::span<const uint8_t> nal) {
  out.insert(out.end(), {0, 0, 0, 1});
  out.insert(out.end(), nal.begin(), nal.end());
}

// Encoder names to try for a `codec` setting, in order.
std::vector<std::string> candidates(const std::string& codec) {
  if (codec == "auto") return {"h264_v4l2m2m", "libx264"};
  return {codec};
}

}  // namespace

std::string validate(const EncoderSettings& s) {
  if (s.width < 64 || s.width > 4096) return outOfRange("width", s.width, "[64, 4096]");
  if (s.height < 64 || s.height > 4096) return outOfRange("height", s.height, "[64, 4096]");
  if (s.width % 2 != 0) return "video.width: " + std::to_string(s.width) + " is odd (must be even)";
  if (s.height % 2 != 0) return "video.height: " + std::to_string(s.height) + " is odd (must be even)";
  if (!(s.fps > 0.0 && s.fps <= 120.0)) return outOfRange("fps", s.fps, "(0, 120]");
  if (s.bitrate_kbps < 50 || s.bitrate_kbps > 50000) return outOfRange("bitrate_kbps", s.bitrate_kbps, "[50, 50000]");
  if (s.gop < 1 || s.gop > 600) return outOfRange("gop", s.gop, "[1, 600]");
  if (s.threads < 0 || s.threads > 16) return outOfRange("threads", s.threads, "[0, 16]");
  if (s.codec != "libx264" && s.codec != "h264_v4l2m2m" && s.codec != "auto")
    return "video.codec: '" + s.codec + "' is not one of libx264, h264_v4l2m2m, auto";
  if (s.preset != "ultrafast" && s.preset != "superfast" && s.preset != "veryfast")
    return "video.preset: '" + s.preset + "' is not one of ultrafast, superfast, veryfast";
  return {};
}

// ---------------------------------------------------------------- encoder

struct H264Encoder::Impl {
  EncoderSettings s;
  std::string name;
  AVCodecContext* ctx = nullptr;
  AVFrame* frame = nullptr;
  AVPacket* pkt = nullptr;
  AVBufferPool* pool = nullptr;  // I420 pictures, planes back to back
  int64_t next_pts = 0;
  struct Meta {
    int64_t pts;
    uint64_t capture_us;
    uint32_t frame_index;
  };
  std::deque<Meta> in_flight;       // frames given, packet not yet out
  std::deque<EncodedFrame> ready;   // packets out, not yet returned
  std::vector<uint8_t> param_sets;  // the latest SPS and PPS (Annex B)
  std::vector<uint8_t> carry;       // a header-only packet, put before the next one
  LogSink log_sink;  // outlives ctx (members go after the destructor's body)

  ~Impl() {
    avcodec_free_context(&ctx);
    av_frame_free(&frame);
    av_packet_free(&pkt);
    av_buffer_pool_uninit(&pool);
  }

  // Opens encoder `codec_name`; "" on success, else why not.
  std::string open(const std::string& codec_name) {
    const AVCodec* codec = avcodec_find_encoder_by_name(codec_name.c_str());
    if (codec == nullptr) return "not in this libavcodec";
    ctx = avcodec_alloc_context3(codec);
    if (ctx == nullptr) return "out of memory";
    log_sink.attach(ctx);
    ctx->width = s.width;
    ctx->height = s.height;
    ctx->pix_fmt = AV_PIX_FMT_YUV420P;
    ctx->framerate = av_d2q(s.fps, 1001000);
    ctx->time_base = av_inv_q(ctx->framerate);
    ctx->gop_size = s.gop;
    ctx->max_b_frames = 0;
    ctx->bit_rate = int64_t{s.bitrate_kbps} * 1000;
    // cv::cvtColor's BGR -> I420 is BT.601, limited range.
    ctx->color_range = AVCOL_RANGE_MPEG;
    ctx->colorspace = AVCOL_SPC_SMPTE170M;
    AVDictionary* opts = nullptr;
    if (codec_name == "libx264") {
      ctx->keyint_min = s.gop;
      setRateControl();
      ctx->thread_count = s.threads;
      ctx->thread_type = FF_THREAD_SLICE;  // frame threads would add a frame of latency each
      std::string params = "scenecut=0";    // IDRs exactly every gop frames
      if (s.threads != 1) params += ":sliced-threads=1";
      if (s.intra_refresh) params += ":intra-refresh=1";
      av_dict_set(&opts, "preset", s.preset.c_str(), 0);
      av_dict_set(&opts, "tune", "zerolatency", 0);
      av_dict_set(&opts, "forced-idr", "1", 0);
      av_dict_set(&opts, "x264-params", params.c_str(), 0);
    }
    const int ret = avcodec_open2(ctx, codec, &opts);
    av_dict_free(&opts);
    if (ret < 0) {
      const std::string why = avError(ret) + log_sink.take();
      log_sink.attach(nullptr);
      avcodec_free_context(&ctx);
      return why;
    }
    name = codec_name;
    keepParamSets(std::span<const uint8_t>(ctx->extradata, ctx->extradata_size));
    return {};
  }

  // Capped VBR at s.bitrate_kbps with a one-frame VBV buffer (libx264 takes
  // it in whole kbit). libx264.c compares these with its parameters before
  // every frame and calls x264_encoder_reconfig when they differ.
  void setRateControl() {
    ctx->bit_rate = int64_t{s.bitrate_kbps} * 1000;
    ctx->rc_max_rate = ctx->bit_rate;
    ctx->rc_buffer_size = std::max(1000, static_cast<int>(std::ceil(static_cast<double>(ctx->bit_rate) / s.fps)));
  }

  // Remembers the SPS and PPS in `annexb`, if it has both.
  void keepParamSets(std::span<const uint8_t> annexb) {
    std::vector<uint8_t> sets;
    bool sps = false, pps = false;
    for (const auto& nal : splitAnnexB(annexb)) {
      const uint8_t t = nalType(nal[0]);
      if (t != kNalSps && t != kNalPps) continue;
      (t == kNalSps ? sps : pps) = true;
      appendNal(sets, nal);
    }
    if (sps && pps) param_sets = std::move(sets);
  }

  // Points `frame` at a pooled I420 buffer and converts `bgr` into it
  // (cv::cvtColor: 0.3-0.45 ms at 640x480, sws_scale 1.0 ms).
  void fillFrame(const cv::Mat& bgr) {
    const int w = s.width, h = s.height;
    AVBufferRef* buf = av_buffer_pool_get(pool);
    if (buf == nullptr) throw VideoError("H.264 encoder " + name + ": out of memory");
    frame->buf[0] = buf;
    frame->data[0] = buf->data;
    frame->data[1] = buf->data + w * h;
    frame->data[2] = frame->data[1] + (w / 2) * (h / 2);
    frame->linesize[0] = w;
    frame->linesize[1] = frame->linesize[2] = w / 2;
    frame->width = w;
    frame->height = h;
    frame->format = AV_PIX_FMT_YUV420P;
    cv::Mat i420(h * 3 / 2, w, CV_8UC1, buf->data);
    cv::cvtColor(bgr, i420, cv::COLOR_BGR2YUV_I420);
  }

  // Turns one packet into an access unit on `ready` (headers-only packets wait for the next one).
  void takePacket() {
    const std::span<const uint8_t> data(pkt->data, pkt->size);
    std::vector<uint8_t> au = std::move(carry);
    carry.clear();
    au.insert(au.end(), data.begin(), data.end());
    bool vcl = false, idr = false, sps = false;
    for (const auto& nal : splitAnnexB(au)) {
      const uint8_t t = nalType(nal[0]);
      vcl = vcl || isVcl(t);
      idr = idr || t == kNalIdr;
      sps = sps || t == kNalSps;
    }
    if (sps) keepParamSets(au);
    if (!vcl) {
      carry = std::move(au);
      return;
    }
    EncodedFrame f;
    if (idr && !sps) f.annexb = param_sets;
    f.annexb.insert(f.annexb.end(), au.begin(), au.end());
    f.keyframe = idr;
    while (!in_flight.empty() && in_flight.front().pts < pkt->pts) in_flight.pop_front();
    if (!in_flight.empty()) {
      f.capture_us = in_flight.front().capture_us;
      f.frame_index = in_flight.front().frame_index;
      in_flight.pop_front();
    }
    ready.push_back(std::move(f));
  }
};

H264Encoder::H264Encoder(const EncoderSettings& s) : impl_(std::make_unique<Impl>()) {
  if (const std::string bad = validate(s); !bad.empty()) throw VideoError("H.264 encoder: " + bad);
  impl_->s = s;
  std::string failures;
  for (const auto& name : candidates(s.codec)) {
    const std::string why = impl_->open(name);
    if (why.empty()) break;
    failures += (failures.empty() ? "" : "; ") + name + ": " + why;
  }
  if (impl_->ctx == nullptr) throw VideoError("H.264 encoder " + s.codec + ": cannot open (" + failures + ")");
  if (!failures.empty()) log::info("video", "H.264 encoder ", impl_->name, " (", failures, ")");
  impl_->frame = av_frame_alloc();
  impl_->pkt = av_packet_alloc();
  const int w = s.width, h = s.height;
  impl_->pool = av_buffer_pool_init(w * h + 2 * (w / 2) * (h / 2) + AV_INPUT_BUFFER_PADDING_SIZE, av_buffer_alloc);
  if (impl_->frame == nullptr || impl_->pkt == nullptr || impl_->pool == nullptr)
    throw VideoError("H.264 encoder " + impl_->name + ": out of memory");
}

H264Encoder::~H264Encoder() = default;

bool H264Encoder::encode(const cv::Mat& bgr, uint64_t capture_us, uint32_t frame_index, bool force_keyframe,
                         EncodedFrame& out) {
  Impl& m = *impl_;
  if (bgr.type() != CV_8UC3 || bgr.cols != m.s.width || bgr.rows != m.s.height)
    throw VideoError("H.264 encoder " + m.name + ": picture " + std::to_string(bgr.cols) + "x" +
                     std::to_string(bgr.rows) + " type " + std::to_string(bgr.type()) + ", expected " +
                     std::to_string(m.s.width) + "x" + std::to_string(m.s.height) + " CV_8UC3");
  m.fillFrame(bgr);
  m.frame->pts = m.next_pts++;
  m.frame->pict_type = force_keyframe ? AV_PICTURE_TYPE_I : AV_PICTURE_TYPE_NONE;
  m.in_flight.push_back({m.frame->pts, capture_us, frame_index});
  if (m.in_flight.size() > kMaxInFlight) m.in_flight.pop_front();  // an encoder that drops frames
  int ret = avcodec_send_frame(m.ctx, m.frame);
  av_frame_unref(m.frame);  // the encoder holds its own reference if it needs one
  if (ret < 0) throw VideoError("H.264 encoder " + m.name + ": send_frame: " + avError(ret) + m.log_sink.take());
  while ((ret = avcodec_receive_packet(m.ctx, m.pkt)) >= 0) {
    m.takePacket();
    av_packet_unref(m.pkt);
  }
  if (ret != AVERROR(EAGAIN) && ret != AVERROR_EOF)
    throw VideoError("H.264 encoder " + m.name + ": receive_packet: " + avError(ret) + m.log_sink.take());
  if (m.ready.empty()) return false;
  out = std::move(m.ready.front());
  m.ready.pop_front();
  return true;
}

bool H264Encoder::setBitrate(int kbps) {
  EncoderSettings n = impl_->s;
  n.bitrate_kbps = kbps;
  if (const std::string bad = validate(n); !bad.empty()) throw VideoError("H.264 encoder: " + bad);
  if (impl_->name != "libx264") return false;
  impl_->s = n;
  impl_->setRateControl();
  return true;
}

const std::string& H264Encoder::codecName() const { return impl_->name; }
const EncoderSettings& H264Encoder::settings() const { return impl_->s; }

// ---------------------------------------------------------------- decoder

struct H264Decoder::Impl {
  AVCodecContext* ctx = nullptr;
  AVPacket* pkt = nullptr;
  AVFrame* frame = nullptr;  // the latest picture
  AVFrame* next = nullptr;
  SwsContext* sws = nullptr;  // to BGR
  int sws_matrix = -1;        // colour details set on sws
  bool sws_full_range = false;
  DecoderCounters c;
  std::string last_error;
  LogSink log_sink;

  ~Impl() {
    sws_freeContext(sws);
    av_frame_free(&next);
    av_frame_free(&frame);
    av_packet_free(&pkt);
    avcodec_free_context(&ctx);
  }

  // Counts one refused access unit; the message names why.
  bool fail(const std::string& what) {
    ++c.errors;
    last_error = what + log_sink.take();
    return false;
  }

  // Decodes one access unit; true when `frame` holds a new, undamaged picture.
  bool decode(const uint8_t* data, std::size_t size) {
    ++c.frames_in;
    log_sink.take();
    if (data == nullptr || size == 0 || size > INT32_MAX - AV_INPUT_BUFFER_PADDING_SIZE)
      return fail("empty or oversized access unit (" + std::to_string(size) + " bytes)");
    if (av_new_packet(pkt, static_cast<int>(size)) < 0)
      return fail("out of memory for a packet of " + std::to_string(size) + " bytes");
    std::memcpy(pkt->data, data, size);
    int ret = avcodec_send_packet(ctx, pkt);
    av_packet_unref(pkt);
    std::string error;
    if (ret < 0 && ret != AVERROR(EAGAIN)) error = "send_packet: " + avError(ret);
    bool got = false;
    while ((ret = avcodec_receive_frame(ctx, next)) >= 0) {
      av_frame_unref(frame);
      av_frame_move_ref(frame, next);
      got = true;
    }
    if (ret != AVERROR(EAGAIN) && ret != AVERROR_EOF && error.empty()) error = "receive_frame: " + avError(ret);
    if (!error.empty()) return fail(error);
    if (got && (frame->decode_error_flags != 0 || (frame->flags & AV_FRAME_FLAG_CORRUPT)))
      return fail("picture damaged and concealed, decode_error_flags " + std::to_string(frame->decode_error_flags));
    return got;
  }

  // sws_scale straight from the decoder's planes: faster than the copy to one
  // I420 block that cv::cvtColor needs (0.24 vs 0.41 ms at 640x480).
  bool toBgr(cv::Mat& bgr) {
    const int w = frame->width, h = frame->height;
    const auto format = static_cast<AVPixelFormat>(frame->format);
    SwsContext* const before = sws;
    sws = sws_getCachedContext(sws, w, h, format, w, h, AV_PIX_FMT_BGR24, SWS_BILINEAR, nullptr, nullptr, nullptr);
    if (sws == nullptr) {
      const char* name = av_get_pix_fmt_name(format);
      return fail(std::string("no conversion from ") + (name != nullptr ? name : "unknown") + " to BGR");
    }
    // The stream's matrix and range; BT.601 limited unless it says otherwise.
    const AVColorSpace cs = frame->colorspace;
    const bool known = cs == AVCOL_SPC_BT709 || cs == AVCOL_SPC_FCC || cs == AVCOL_SPC_SMPTE240M ||
                       cs == AVCOL_SPC_BT2020_NCL || cs == AVCOL_SPC_BT2020_CL;
    const int matrix = known ? cs : SWS_CS_DEFAULT;
    const bool full_range = frame->color_range == AVCOL_RANGE_JPEG;
    if (sws != before || matrix != sws_matrix || full_range != sws_full_range) {
      sws_setColorspaceDetails(sws, sws_getCoefficients(matrix), full_range, sws_getCoefficients(SWS_CS_DEFAULT), 1,
                               0, 1 << 16, 1 << 16);
      sws_matrix = matrix;
      sws_full_range = full_range;
    }
    bgr.create(h, w, CV_8UC3);
    uint8_t* dst[4] = {bgr.data, nullptr, nullptr, nullptr};
    const int dst_stride[4] = {static_cast<int>(bgr.step), 0, 0, 0};
    sws_scale(sws, frame->data, frame->linesize, 0, h, dst, dst_stride);
    return true;
  }

  bool toGrey(cv::Mat& grey) {
    const int w = frame->width, h = frame->height;
    grey.create(h, w, CV_8UC1);
    const AVPixFmtDescriptor* d = av_pix_fmt_desc_get(static_cast<AVPixelFormat>(frame->format));
    const bool plain_luma = d != nullptr && !(d->flags & AV_PIX_FMT_FLAG_RGB) && d->comp[0].plane == 0 &&
                            d->comp[0].step == 1 && d->comp[0].depth == 8;
    if (plain_luma) {
      for (int y = 0; y < h; ++y) std::memcpy(grey.ptr(y), frame->data[0] + y * frame->linesize[0], w);
      return true;
    }
    cv::Mat bgr;
    if (!toBgr(bgr)) return false;
    cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
    return true;
  }
};

H264Decoder::H264Decoder() : impl_(std::make_unique<Impl>()) {
  const AVCodec* codec = avcodec_find_decoder(AV_CODEC_ID_H264);
  if (codec == nullptr) throw VideoError("H.264 decoder: libavcodec has no h264 decoder");
  Impl& m = *impl_;
  m.ctx = avcodec_alloc_context3(codec);
  m.pkt = av_packet_alloc();
  m.frame = av_frame_alloc();
  m.next = av_frame_alloc();
  if (m.ctx == nullptr || m.pkt == nullptr || m.frame == nullptr || m.next == nullptr)
    throw VideoError("H.264 decoder: out of memory");
  m.log_sink.attach(m.ctx);
  m.ctx->thread_count = 1;
  m.ctx->flags |= AV_CODEC_FLAG_LOW_DELAY;
  if (const int ret = avcodec_open2(m.ctx, codec, nullptr); ret < 0)
    throw VideoError("H.264 decoder " + std::string(codec->name) + ": cannot open (" + avError(ret) + ")" +
                     m.log_sink.take());
}

H264Decoder::~H264Decoder() = default;

bool H264Decoder::decode(const uint8_t* data, std::size_t size, cv::Mat& bgr) {
  if (!impl_->decode(data, size) || !impl_->toBgr(bgr)) return false;
  ++impl_->c.pictures;
  return true;
}

bool H264Decoder::decodeLuma(const uint8_t* data, std::size_t size, cv::Mat& grey) {
  if (!impl_->decode(data, size) || !impl_->toGrey(grey)) return false;
  ++impl_->c.pictures;
  return true;
}

const DecoderCounters& H264Decoder::counters() const { return impl_->c; }
const std::string& H264Decoder::lastError() const { return impl_->last_error; }

std::vector<std::string> availableH264Encoders() {
  std::vector<std::string> names;
  void* it = nullptr;
  while (const AVCodec* c = av_codec_iterate(&it))
    if (c->id == AV_CODEC_ID_H264 && av_codec_is_encoder(c)) names.emplace_back(c->name);
  return names;
}

}  // namespace inspect::video
