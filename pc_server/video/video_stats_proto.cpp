#include "pc_server/video/video_stats_proto.hpp"

namespace inspect::server {

v1::VideoReceiveStats toProto(const video::StreamStats& s) {
  v1::VideoReceiveStats p;
  p.set_active(s.active);
  p.set_width(static_cast<uint32_t>(s.width));
  p.set_height(static_cast<uint32_t>(s.height));
  p.set_fps_received(s.fps_received);
  p.set_fps_decoded(s.fps_decoded);
  p.set_kbps(s.kbps);
  p.set_loss_pct(s.loss_pct);
  p.set_latency_ms(s.latency_ms);
  p.set_latency_p50_ms(s.latency_p50_ms);
  p.set_latency_p99_ms(s.latency_p99_ms);
  p.set_frames(s.frames);
  p.set_decoded(s.decoded);
  p.set_frames_skipped(s.frames_skipped);
  p.set_lost_packets(s.lost_packets);
  p.set_keyframe_requests(s.keyframe_requests);
  p.set_nacks_sent(s.nacks_sent);
  p.set_nacked_packets(s.nacked_packets);
  p.set_retransmissions(s.retransmissions);
  p.set_rtx_unneeded(s.rtx_unneeded);
  p.set_tail_probes(s.tail_probes);
  p.set_plis_sent(s.plis_sent);
  p.set_rtt_ms(s.rtt_ms);
  return p;
}

}  // namespace inspect::server
