#pragma once
// Small setters for fields of Foxglove's schemas, shared by the scene's builders.
#include <cstdint>

#include <google/protobuf/timestamp.pb.h>

#include "foxglove/Color.pb.h"

namespace inspect::server::scene {

inline void setTime(google::protobuf::Timestamp* t, uint64_t ns) {
  t->set_seconds(static_cast<int64_t>(ns / 1'000'000'000ULL));
  t->set_nanos(static_cast<int32_t>(ns % 1'000'000'000ULL));
}

inline void setColor(::foxglove::Color* c, double r, double g, double b, double a) {
  c->set_r(r);
  c->set_g(g);
  c->set_b(b);
  c->set_a(a);
}

}  // namespace inspect::server::scene
