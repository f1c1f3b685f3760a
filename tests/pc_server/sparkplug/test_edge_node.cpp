// The Sparkplug B edge node's messages (pc_server/sparkplug/edge_node;
// docs/sparkplug.md), decoded with the project's sparkplug_b.proto: births,
// seq, bdSeq across sessions, deadbands, alarm events at their time,
// deaths and the rebirth request; the broker's credentials file.
#include <gtest/gtest.h>

#include <cmath>

#include "pc_server/sparkplug/device_metrics.hpp"
#include "pc_server/sparkplug/edge_node.hpp"
#include "pc_server/sparkplug/sparkplug_credentials.hpp"
#include "pc_server/sparkplug/transition_spool.hpp"
#include "shared/config/config_node.hpp"
#include "tests/support/process.hpp"

using namespace inspect;
using namespace inspect::server::sparkplug;

namespace {

spb::Payload decode(const Message& m) {
  spb::Payload p;
  EXPECT_TRUE(p.ParseFromString(m.payload)) << m.topic;
  return p;
}

const spb::Payload::Metric* metric(const spb::Payload& p, const std::string& name) {
  for (const auto& m : p.metrics())
    if (m.name() == name) return &m;
  return nullptr;
}

std::vector<Metric> robotAt(double x, double ch4 = 0.0) {
  return {Metric::ofString("Mode", "IDLE"), Metric::ofDouble("Pose/x_m", x, 0.05),
          Metric::ofDouble("Gas/CH4/Value", ch4, 0.2), [] {
            Metric a = Metric::ofBool("Gas/CH4/A1", false);
            a.event_driven = true;
            return a;
          }()};
}

}  // namespace

TEST(SparkplugEdgeNode, BirthsThenDataBeyondTheDeadbandWithTheNextSeq) {
  EdgeNode n("inspection", "pc1");
  EXPECT_FALSE(n.update("robot1", robotAt(0.0), 1000)) << "not born: nothing goes out";
  const auto births = n.birth(2000);
  ASSERT_EQ(births.size(), 2u);
  EXPECT_EQ(births[0].topic, "spBv1.0/inspection/NBIRTH/pc1");
  const auto nb = decode(births[0]);
  EXPECT_EQ(nb.seq(), 0u);
  EXPECT_EQ(nb.timestamp(), 2000u);
  ASSERT_NE(metric(nb, "bdSeq"), nullptr);
  EXPECT_EQ(metric(nb, "bdSeq")->long_value(), 0u);
  EXPECT_EQ(metric(nb, "bdSeq")->datatype(), 8u) << "UInt64";
  ASSERT_NE(metric(nb, EdgeNode::kRebirth), nullptr);
  EXPECT_EQ(births[1].topic, "spBv1.0/inspection/DBIRTH/pc1/robot1");
  const auto db = decode(births[1]);
  EXPECT_EQ(db.seq(), 1u);
  ASSERT_EQ(db.metrics_size(), 4);
  EXPECT_EQ(metric(db, "Mode")->string_value(), "IDLE");
  EXPECT_EQ(metric(db, "Mode")->datatype(), 12u) << "String";
  EXPECT_EQ(metric(db, "Pose/x_m")->datatype(), 10u) << "Double";

  EXPECT_FALSE(n.update("robot1", robotAt(0.04), 2100)) << "within the deadband";
  const auto d = n.update("robot1", robotAt(0.06, 0.1), 2200);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->topic, "spBv1.0/inspection/DDATA/pc1/robot1");
  const auto dd = decode(*d);
  EXPECT_EQ(dd.seq(), 2u);
  ASSERT_EQ(dd.metrics_size(), 1) << "only the pose moved beyond its deadband (0.06 from 0)";
  EXPECT_DOUBLE_EQ(dd.metrics(0).double_value(), 0.06);
  // The deadband is from the value the hosts have: 0.06 -> 0.10 is within it, 0.12 is not.
  EXPECT_FALSE(n.update("robot1", robotAt(0.10), 2300));
  EXPECT_TRUE(n.update("robot1", robotAt(0.12), 2400));
}

TEST(SparkplugEdgeNode, SeqWrapsAt256AndARebirthStartsAgainAtZero) {
  EdgeNode n("g", "e");
  n.birth(0);
  for (int i = 1; i <= 300; ++i) {
    const auto m = n.update("r", robotAt(i * 1.0), static_cast<uint64_t>(i));
    ASSERT_TRUE(m);
    EXPECT_EQ(decode(*m).seq(), static_cast<uint64_t>(i % 256)) << i;
  }
  const auto again = n.birth(400);
  EXPECT_EQ(decode(again[0]).seq(), 0u);
  EXPECT_EQ(decode(again[1]).seq(), 1u) << "the device born again";
}

TEST(SparkplugEdgeNode, ALostSessionMakesTheNextBdSeqAndTheWillCarriesIt) {
  EdgeNode n("g", "e", 254);
  const auto w0 = decode(n.will(5));
  EXPECT_FALSE(w0.has_seq()) << "NDEATH has no seq";
  EXPECT_EQ(metric(w0, "bdSeq")->long_value(), 254u);
  n.birth(10);
  n.sessionEnded();
  EXPECT_EQ(metric(decode(n.will(20)), "bdSeq")->long_value(), 255u);
  n.sessionEnded();  // not born since: the same bdSeq again
  EXPECT_EQ(n.bdSeq(), 255);
  n.birth(30);
  n.sessionEnded();
  EXPECT_EQ(n.bdSeq(), 0) << "wraps at 256";
  EXPECT_EQ(n.will(1).topic, "spBv1.0/g/NDEATH/e");
}

TEST(SparkplugEdgeNode, AlarmEventsGoOutAtTheirTimeAndTelemetryDoesNotRepeatThem) {
  EdgeNode n("g", "e");
  n.birth(0);
  ASSERT_TRUE(n.update("r", robotAt(0), 10));
  v1::GasAlarm a;
  a.set_id(7);
  a.set_channel_name("CH4");
  a.set_level(v1::GasAlarm::LOW);
  a.set_active(true);
  a.set_value(12.5);
  const auto ev = n.events("r", alarmEventMetrics(a, 123456, false), 200);
  ASSERT_TRUE(ev);
  EXPECT_TRUE(ev->event);
  const auto p = decode(*ev);
  const auto* m = metric(p, "Gas/CH4/A1");
  ASSERT_NE(m, nullptr);
  EXPECT_TRUE(m->boolean_value());
  EXPECT_EQ(m->timestamp(), 123456u) << "the robot's time of the transition";
  EXPECT_FALSE(m->is_historical());
  EXPECT_EQ(metric(p, "Gas/CH4/A1/Alarm Id")->long_value(), 7u);
  // The telemetry's alarm state is not sent again as data.
  auto now = robotAt(0);
  now[3].value = true;
  EXPECT_FALSE(n.update("r", now, 300));
  // A late (stored) transition is historical.
  a.set_active(false);
  const auto late = decode(*n.events("r", alarmEventMetrics(a, 99, true), 400));
  EXPECT_TRUE(metric(late, "Gas/CH4/A1")->is_historical());
  EXPECT_FALSE(n.events("other", alarmEventMetrics(a, 99, false), 500)) << "a device not born: kept by the caller";
}

TEST(SparkplugEdgeNode, ADeviceGoneIsDeadAndBornAgainWhenBack) {
  EdgeNode n("g", "e");
  n.birth(0);
  n.update("r", robotAt(0), 1);
  const auto death = n.deviceOffline("r", 2);
  ASSERT_TRUE(death);
  EXPECT_EQ(death->topic, "spBv1.0/g/DDEATH/e/r");
  EXPECT_EQ(decode(*death).seq(), 2u);
  EXPECT_FALSE(n.deviceOffline("r", 3)) << "once";
  const auto back = n.update("r", robotAt(0), 4);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->topic, "spBv1.0/g/DBIRTH/e/r");
}

TEST(SparkplugEdgeNode, NullValuesAndTheRebirthRequest) {
  Metric m = Metric::ofDouble("People/Nearest_m", NAN);
  spb::Payload::Metric out;
  encodeMetric(m, out);
  EXPECT_TRUE(out.is_null());
  EXPECT_FALSE(out.has_double_value());
  spb::Payload ncmd;
  auto* r = ncmd.add_metrics();
  r->set_name(EdgeNode::kRebirth);
  r->set_datatype(11);
  r->set_boolean_value(true);
  EXPECT_EQ(EdgeNode::rebirthAsked(ncmd.SerializeAsString()), std::optional<bool>(true));
  r->set_boolean_value(false);
  EXPECT_EQ(EdgeNode::rebirthAsked(ncmd.SerializeAsString()), std::optional<bool>(false));
  EXPECT_EQ(EdgeNode::rebirthAsked("\xff\xff\xff"), std::nullopt) << "not a payload";
  EXPECT_TRUE(validId("plant-1"));
  EXPECT_FALSE(validId("a/b"));
  EXPECT_FALSE(validId("#"));
  EXPECT_FALSE(validId(""));
}

TEST(SparkplugCredentials, ReadFromTheirFileWithErrorsNamed) {
  inspect::test::TempDir d("spcred");
  inspect::test::writeFile(d / "ok.yaml", "username: edge\npassword: \"p:w#1\"\n");
  const auto c = loadCredentials(d / "ok.yaml");
  EXPECT_EQ(c.username, "edge");
  EXPECT_EQ(c.password, "p:w#1");
  inspect::test::writeFile(d / "none.yaml", "password: x\n");
  try {
    loadCredentials(d / "none.yaml");
    ADD_FAILURE() << "no username accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("none.yaml: username: must not be empty"), std::string::npos) << e.what();
  }
  inspect::test::writeFile(d / "typo.yaml", "user: edge\n");
  EXPECT_THROW(loadCredentials(d / "typo.yaml"), config::ConfigError);
  EXPECT_THROW(loadCredentials(d / "missing.yaml"), config::ConfigError);
}

TEST(SparkplugSpool, TransitionsStayInOrderUntilConfirmedAndOutliveTheProcess) {
  inspect::test::TempDir d("spspool");
  const std::string path = d / "sparkplug-spool.sqlite";
  v1::GasAlarm a;
  a.set_id(3);
  a.set_channel(1);
  a.set_channel_name("H2S");
  a.set_level(v1::GasAlarm::HIGH);
  a.set_active(true);
  a.set_value(21.5);
  a.set_robot_time_us(123);
  int64_t first = 0;
  {
    TransitionSpool s(path);
    first = s.append("robot1", a, 1000, false);
    a.set_active(false);
    a.set_value(NAN);
    s.append("robot1", a, 2000, true);
    a.set_id(4);
    const int64_t third = s.append("robot2", a, 3000, false);
    s.remove(third);
  }
  TransitionSpool again(path);  // a new process
  const auto all = again.all();
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[0].seq, first);
  EXPECT_EQ(all[0].device, "robot1");
  EXPECT_EQ(all[0].alarm.id(), 3u);
  EXPECT_EQ(all[0].alarm.channel_name(), "H2S");
  EXPECT_EQ(all[0].alarm.level(), v1::GasAlarm::HIGH);
  EXPECT_TRUE(all[0].alarm.active());
  EXPECT_DOUBLE_EQ(all[0].alarm.value(), 21.5);
  EXPECT_EQ(all[0].time_ms, 1000u);
  EXPECT_FALSE(all[0].late);
  EXPECT_FALSE(all[1].alarm.active());
  EXPECT_TRUE(std::isnan(all[1].alarm.value())) << "no reading stays no reading";
  EXPECT_TRUE(all[1].late);
  inspect::test::writeFile(d / "not-a-db", "garbage garbage garbage garbage");
  EXPECT_THROW(TransitionSpool(d / "not-a-db"), std::exception);
}
