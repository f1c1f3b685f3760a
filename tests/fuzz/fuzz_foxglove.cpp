// Fuzzes what a Foxglove client sends the bridge, without a socket: the
// protocol's text and binary client messages (pc_server/foxglove/ws_protocol),
// the service requests (bridge_services) and a client's send queue
// (send_queue) under arbitrary pushes and pops.
//
// Input: records (fuzz_records.hpp). tag % 4: 0 = a text message, 1 = a
// binary message, 2 = a service request to service (tag / 4) % n, 3 = send
// queue operations (each body byte one push or pop).
// Invariants: a parse either succeeds or names what was wrong; payload views
// point inside the input; the queue's byte count matches what it holds, the
// control lane loses nothing, and no subscription gets a delta frame between
// a drop and its next keyframe.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <string>
#include <string_view>
#include <variant>

#include "pc_server/foxglove/bridge_services.hpp"
#include "pc_server/foxglove/send_queue.hpp"
#include "pc_server/foxglove/ws_protocol.hpp"
#include "tests/fuzz/fuzz_records.hpp"

using namespace inspect::server::foxglove;

namespace {

void require(bool ok) {
  if (!ok) std::abort();
}

bool inside(std::string_view part, std::string_view whole) {
  return part.empty() || (part.data() >= whole.data() && part.data() + part.size() <= whole.data() + whole.size());
}

void queueOps(std::span<const uint8_t> body) {
  SendQueue::Limits lim;
  lim.control_bytes = 4096;
  lim.data_bytes = 2048;
  lim.video_bytes = 4096;
  SendQueue q(lim);
  uint64_t control_in = 0, control_out = 0;
  std::map<uint32_t, bool> broken;  // a frame of the stream was dropped since its last accepted keyframe
  const auto isControl = [](const OutMessage& m) { return (static_cast<uint8_t>(m.head[0]) & 7) == 0; };
  for (const uint8_t b : body) {
    const std::size_t size = 1 + (b >> 3) * 37;
    OutMessage m{std::string(size, static_cast<char>(b)), nullptr, (b & 1) != 0};
    switch (b & 7) {
      case 0:
        if (q.pushControl(std::move(m))) ++control_in;
        break;
      case 1: q.pushData(std::move(m)); break;
      case 2:
      case 3: {
        const uint32_t stream = b & 1;
        const bool key = (b & 0x40) != 0;
        const uint64_t before = q.counters().queued;
        m.head[0] = key ? 'K' : 'D';
        q.pushVideo(stream, key, std::move(m));
        const bool accepted = q.counters().queued > before;
        if (!accepted) broken[stream] = true;
        else if (key) broken[stream] = false;
        else require(!broken[stream]);  // never a delta after a lost frame before its keyframe
        break;
      }
      default:
        if (const auto out = q.pop(); out && isControl(*out)) ++control_out;
        break;
    }
    require(q.queuedBytes() <= lim.control_bytes + lim.data_bytes + lim.video_bytes);
  }
  while (const auto out = q.pop())
    if (isControl(*out)) ++control_out;
  require(q.queuedBytes() == 0 && q.empty());
  require(control_out == control_in);  // the control lane loses nothing it accepted
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  inspect::fuzz::RecordReader rr(data, size);
  inspect::fuzz::Record r;
  const auto& services = serviceDefs();
  while (rr.next(r)) {
    const std::string_view body(reinterpret_cast<const char*>(r.body.data()), r.body.size());
    switch (r.tag % 4) {
      case 0: {
        const Parsed p = parseClientText(body);
        if (!p.ok()) require(!p.error.empty());
        // Whatever the client sent, a status naming it is valid JSON.
        (void)statusJson(StatusLevel::kError, p.error);
        break;
      }
      case 1: {
        const Parsed p = parseClientBinary(body);
        if (!p.ok()) {
          require(!p.error.empty());
          break;
        }
        if (const auto* d = std::get_if<ClientMessageData>(&p.message)) require(inside(d->payload, body));
        if (const auto* c = std::get_if<ServiceCallRequest>(&p.message)) {
          require(inside(c->payload, body));
          require(c->encoding.size() + c->payload.size() + 13 == body.size());
        }
        break;
      }
      case 2: {
        const auto& def = services[(r.tag / 4) % services.size()];
        const ServiceRequest q = parseServiceRequest(def.name, body);
        if (q.ok() && q.call == ServiceRequest::Call::kConsoleLine) {
          require(!q.line.empty());
          // A line from JSON arguments never smuggles a second line or a comment.
          if (def.name != "/console") require(q.line.find_first_of("\n\r#") == std::string::npos);
        }
        // The response text is always valid JSON whatever the message.
        if (q.ok() && q.call == ServiceRequest::Call::kGoto)  // a typed call's numbers are finite (ranges: the service)
          require(std::isfinite(q.x_m) && std::isfinite(q.y_m) && (!q.speed_m_s || std::isfinite(*q.speed_m_s)));
        // A route is one printable word; a run's name printable text without '#'.
        if (q.ok() && (q.call == ServiceRequest::Call::kRoute || q.call == ServiceRequest::Call::kInspect))
          require(!q.route.empty() && std::none_of(q.route.begin(), q.route.end(), [](unsigned char c) {
            return c <= ' ' || c == 0x7f || c == '#';
          }));
        if (q.ok() && q.call == ServiceRequest::Call::kRecordStart)
          require(std::none_of(q.name.begin(), q.name.end(), [](unsigned char c) { return c < ' ' || c == '#'; }));
        (void)serviceResponse(q.ok(), q.error + q.line);
        break;
      }
      default: queueOps(r.body); break;
    }
  }
  return 0;
}
