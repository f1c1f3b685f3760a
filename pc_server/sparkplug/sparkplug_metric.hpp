#pragma once
// One Sparkplug B metric as pc_server publishes it (docs/sparkplug.md):
// its name, its DataType and its value, and the payload's encoding of a list
// of them (Eclipse Sparkplug 3.0.0, section 6.4; proto/sparkplug_b).
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "sparkplug_b/sparkplug_b.pb.h"

namespace inspect::server::sparkplug {

namespace spb = inspect_robot::sparkplug_b;

/// The specification's DataType numbers that pc_server uses.
enum class DataType : uint32_t {
  kInt32 = 3,
  kUInt32 = 7,
  kUInt64 = 8,
  kDouble = 10,
  kBoolean = 11,
  kString = 12,
};

struct Metric {
  std::string name;
  DataType type = DataType::kDouble;
  std::variant<std::monostate, bool, int64_t, uint64_t, double, std::string> value;  // monostate = null
  uint64_t timestamp_ms = 0;   // 0 = the payload's
  bool historical = false;     // a value from the past (a stored event delivered late)
  double deadband = 0.0;       // Double: a change smaller than this is not published (not on the wire)
  bool event_driven = false;   // changed by events only (alarm levels): births carry it, updates do not

  static Metric ofDouble(std::string n, double v, double deadband = 0.0);  // NaN = null
  static Metric ofBool(std::string n, bool v) { return {std::move(n), DataType::kBoolean, v}; }
  static Metric ofUInt32(std::string n, uint32_t v) { return {std::move(n), DataType::kUInt32, uint64_t{v}}; }
  static Metric ofUInt64(std::string n, uint64_t v) { return {std::move(n), DataType::kUInt64, v}; }
  static Metric ofInt32(std::string n, int32_t v) { return {std::move(n), DataType::kInt32, int64_t{v}}; }
  static Metric ofString(std::string n, std::string v) { return {std::move(n), DataType::kString, std::move(v)}; }
  bool isNull() const { return std::holds_alternative<std::monostate>(value); }
};

/// The metric into `out` (name, datatype, value or is_null, timestamp, is_historical).
void encodeMetric(const Metric& m, spb::Payload::Metric& out);

/// A payload of `metrics` made at `timestamp_ms`; `seq` < 0 = none (NDEATH).
std::string encodePayload(const std::vector<Metric>& metrics, uint64_t timestamp_ms, int seq);

/// The topic spBv1.0/<group>/<type>/<edge node>[/<device>] (section 4.1).
std::string topic(const std::string& group, const std::string& type, const std::string& node,
                  const std::string& device = "");

/// Whether `s` can be a group, edge node or device id: not empty, none of '/', '+', '#' (section 4.1.1).
bool validId(const std::string& s);

}  // namespace inspect::server::sparkplug
