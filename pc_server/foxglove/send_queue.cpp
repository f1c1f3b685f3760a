#include "pc_server/foxglove/send_queue.hpp"

#include <algorithm>

namespace inspect::server::foxglove {

bool SendQueue::pushControl(OutMessage m) {
  if (control_bytes_ + m.bytes() > limits_.control_bytes) return false;
  control_bytes_ += m.bytes();
  control_.push_back(std::move(m));
  ++counters_.queued;
  return true;
}

void SendQueue::pushData(OutMessage m) {
  while (!data_.empty() && data_bytes_ + m.bytes() > limits_.data_bytes) {
    data_bytes_ -= data_.front().bytes();
    data_.pop_front();
    ++counters_.dropped_data;
  }
  if (m.bytes() > limits_.data_bytes) {  // larger than the whole lane: never fits
    ++counters_.dropped_data;
    return;
  }
  data_bytes_ += m.bytes();
  data_.push_back(std::move(m));
  ++counters_.queued;
}

void SendQueue::pushVideo(uint32_t stream, bool keyframe, OutMessage m) {
  auto [it, fresh] = need_keyframe_.try_emplace(stream, true);
  bool& waiting = it->second;
  if (!keyframe && waiting) {
    ++counters_.skipped_video;
    return;
  }
  if (video_bytes_ + m.bytes() > limits_.video_bytes) {
    if (!keyframe) {
      ++counters_.dropped_video;
      waiting = true;
      return;
    }
    // A keyframe makes this subscription's queued frames obsolete (all older,
    // and a delta without the frames before it is garbage): drop them all.
    for (auto q = video_.begin(); q != video_.end();) {
      if (q->stream != stream) {
        ++q;
        continue;
      }
      video_bytes_ -= q->m.bytes();
      q = video_.erase(q);
      ++counters_.dropped_video;
    }
    if (video_bytes_ + m.bytes() > limits_.video_bytes) {
      ++counters_.dropped_video;
      waiting = true;
      return;
    }
  }
  waiting = false;
  video_bytes_ += m.bytes();
  video_.push_back({stream, std::move(m)});
  ++counters_.queued;
}

void SendQueue::forgetStream(uint32_t stream) {
  need_keyframe_.erase(stream);
  if (stream == 0) return;
  std::erase_if(data_, [&](const OutMessage& m) {
    if (m.subscription != stream) return false;
    data_bytes_ -= m.bytes();
    return true;
  });
  std::erase_if(video_, [&](const VideoItem& v) {
    if (v.stream != stream) return false;
    video_bytes_ -= v.m.bytes();
    return true;
  });
}

std::optional<OutMessage> SendQueue::pop() {
  std::optional<OutMessage> out;
  if (!control_.empty()) {
    out = std::move(control_.front());
    control_.pop_front();
    control_bytes_ -= out->bytes();
  } else if (!data_.empty()) {
    out = std::move(data_.front());
    data_.pop_front();
    data_bytes_ -= out->bytes();
  } else if (!video_.empty()) {
    out = std::move(video_.front().m);
    video_.pop_front();
    video_bytes_ -= out->bytes();
  } else {
    return out;
  }
  ++counters_.sent;
  return out;
}

}  // namespace inspect::server::foxglove
