#include "pc_server/sparkplug/sparkplug_metric.hpp"

#include <cmath>

namespace inspect::server::sparkplug {

Metric Metric::ofDouble(std::string n, double v, double deadband) {
  Metric m{std::move(n), DataType::kDouble, {}};
  m.deadband = deadband;
  if (std::isfinite(v)) m.value = v;
  return m;
}

void encodeMetric(const Metric& m, spb::Payload::Metric& out) {
  out.set_name(m.name);
  out.set_datatype(static_cast<uint32_t>(m.type));
  if (m.timestamp_ms) out.set_timestamp(m.timestamp_ms);
  if (m.historical) out.set_is_historical(true);
  if (m.isNull()) {
    out.set_is_null(true);
    return;
  }
  switch (m.type) {
    case DataType::kBoolean: out.set_boolean_value(std::get<bool>(m.value)); break;
    case DataType::kDouble: out.set_double_value(std::get<double>(m.value)); break;
    case DataType::kString: out.set_string_value(std::get<std::string>(m.value)); break;
    case DataType::kUInt64: out.set_long_value(std::get<uint64_t>(m.value)); break;
    case DataType::kUInt32: out.set_int_value(static_cast<uint32_t>(std::get<uint64_t>(m.value))); break;
    // Signed 32-bit values travel as their two's complement in int_value (section 6.4.16).
    case DataType::kInt32: out.set_int_value(static_cast<uint32_t>(static_cast<int32_t>(std::get<int64_t>(m.value)))); break;
  }
}

std::string encodePayload(const std::vector<Metric>& metrics, uint64_t timestamp_ms, int seq) {
  spb::Payload p;
  p.set_timestamp(timestamp_ms);
  if (seq >= 0) p.set_seq(static_cast<uint64_t>(seq));
  for (const auto& m : metrics) encodeMetric(m, *p.add_metrics());
  return p.SerializeAsString();
}

std::string topic(const std::string& group, const std::string& type, const std::string& node,
                  const std::string& device) {
  std::string t = "spBv1.0/" + group + "/" + type + "/" + node;
  if (!device.empty()) t += "/" + device;
  return t;
}

bool validId(const std::string& s) { return !s.empty() && s.find_first_of("/+#") == std::string::npos; }

}  // namespace inspect::server::sparkplug
