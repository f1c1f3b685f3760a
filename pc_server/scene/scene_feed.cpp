#include "pc_server/scene/scene_feed.hpp"

#include "shared/util/clock.hpp"

namespace inspect::server::scene {

void SceneFeed::onEnvelope(const v1::Envelope& env, bool inbound) {
  if (!inbound) {
    if (env.has_command()) scene_.onCommand(env.command());
    return;
  }
  switch (env.body_case()) {
    case v1::Envelope::kHello: scene_.onHello(env.hello()); break;
    case v1::Envelope::kTelemetry: scene_.onTelemetry(env.telemetry()); break;
    case v1::Envelope::kEvent: scene_.onEvent(env.event()); break;
    default: break;
  }
}

std::optional<std::pair<uint64_t, ::foxglove::ImageAnnotations>> SceneFeed::cameraPeople(const v1::Telemetry& t,
                                                                                        int64_t link_offset_us,
                                                                                        v1::CameraHead head) {
  const bool wide = head == v1::WIDE_HEAD;
  if (!(wide ? t.has_wide_perception() : t.has_perception())) return std::nullopt;
  const v1::Perception& p = wide ? t.wide_perception() : t.perception();
  const v1::VideoStatus& v = wide ? t.wide_video() : t.video();
  const auto capture_ns = clock(head).fresh(p, link_offset_us, monoUsToWallNs);
  if (!capture_ns) return std::nullopt;
  return std::make_pair(*capture_ns, scene::cameraPeople(p, v.width(), v.height(), *capture_ns));
}

void SceneFeed::followMap(SiteMaps& maps, const std::string& robot) {
  const auto m = maps.get(robot);
  if (m.version == map_version_) return;
  map_version_ = m.version;
  scene_.setMap(m.map ? std::optional<SiteMap>(*m.map) : std::nullopt);
}

}  // namespace inspect::server::scene
