#pragma once
// control::GainSet <-> the link's v1::Gains (proto/inspect_robot/v1/link.proto).
#include "inspect_robot/v1/link.pb.h"
#include "shared/control/gain_set.hpp"

namespace inspect::net {

inline void toProto(const control::GainSet& g, v1::Gains& p) {
  p.set_kp(g.fuzzy.base.kp);
  p.set_ki(g.fuzzy.base.ki);
  p.set_kd(g.fuzzy.base.kd);
  p.set_ke(g.fuzzy.ke);
  p.set_kec(g.fuzzy.kec);
  p.set_k1(g.fuzzy.k1);
  p.set_k2(g.fuzzy.k2);
  p.set_k3(g.fuzzy.k3);
  p.set_a1(g.aux.a1);
  p.set_a2(g.aux.a2);
  p.set_a3(g.aux.a3);
}

inline control::GainSet fromProto(const v1::Gains& p) {
  control::GainSet g;
  g.fuzzy.base = {p.kp(), p.ki(), p.kd()};
  g.fuzzy.ke = p.ke();
  g.fuzzy.kec = p.kec();
  g.fuzzy.k1 = p.k1();
  g.fuzzy.k2 = p.k2();
  g.fuzzy.k3 = p.k3();
  g.aux = {p.a1(), p.a2(), p.a3()};
  return g;
}

}  // namespace inspect::net
