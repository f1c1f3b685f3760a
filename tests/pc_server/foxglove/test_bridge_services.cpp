// The bridge's services (pc_server/foxglove/bridge_services): JSON requests
// become typed calls of the operator service or console lines; every bad
// argument is named.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "pc_server/foxglove/bridge_services.hpp"

using namespace inspect::server::foxglove;

TEST(BridgeServices, EveryServiceHasValidSchemas) {
  const auto& defs = serviceDefs();
  EXPECT_GE(defs.size(), 10u);
  for (const auto& d : defs) {
    const auto s = nlohmann::json::parse(d.request_schema, nullptr, false);
    EXPECT_FALSE(s.is_discarded()) << d.name << ": " << d.request_schema;
    EXPECT_EQ(s["type"], "object") << d.name;
    EXPECT_TRUE(s["properties"].contains("robot")) << d.name;
    EXPECT_EQ(toService(d).response_schema, responseSchema());
  }
  EXPECT_FALSE(nlohmann::json::parse(responseSchema(), nullptr, false).is_discarded());
}

TEST(BridgeServices, RequestsBecomeTypedCallsOrConsoleLines) {
  using Call = ServiceRequest::Call;
  auto r = parseServiceRequest("/goto", R"({"x": 1.5, "y": -2, "speed": 0.3, "robot": "robot2"})");
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(r.call, Call::kGoto);
  EXPECT_DOUBLE_EQ(r.x_m, 1.5);
  EXPECT_DOUBLE_EQ(r.y_m, -2);
  EXPECT_EQ(r.speed_m_s, 0.3);
  EXPECT_EQ(r.robot, "robot2");
  EXPECT_FALSE(r.urgent());
  EXPECT_FALSE(parseServiceRequest("/goto", R"({"x": 1, "y": 2})").speed_m_s);
  r = parseServiceRequest("/stop", "");
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.call, Call::kStop);
  EXPECT_TRUE(r.urgent());
  EXPECT_TRUE(parseServiceRequest("/estop", "{}").urgent());
  EXPECT_EQ(parseServiceRequest("/resume", "{}").call, Call::kResume);
  const auto inspect = parseServiceRequest("/inspect", R"({"route": "gas_lab_inspection", "speed": 0.4})");
  EXPECT_EQ(inspect.call, Call::kInspect);
  EXPECT_EQ(inspect.route, "gas_lab_inspection");
  EXPECT_EQ(inspect.speed_m_s, 0.4);
  EXPECT_EQ(parseServiceRequest("/route", R"({"route": "lab_loop"})").call, Call::kRoute);
  EXPECT_EQ(parseServiceRequest("/route", R"({"route": "lab_loop"})").route, "lab_loop");
  const auto take = parseServiceRequest("/control_take", R"({"force": true})");
  EXPECT_EQ(take.call, Call::kControlTake);
  EXPECT_TRUE(take.force);
  EXPECT_EQ(parseServiceRequest("/control_release", "{}").call, Call::kControlRelease);
  const auto start = parseServiceRequest("/record_start", R"({"name": "night round B"})");
  EXPECT_EQ(start.call, Call::kRecordStart);
  EXPECT_EQ(start.name, "night round B");
  EXPECT_EQ(parseServiceRequest("/record_start", "{}").name, "");
  EXPECT_EQ(parseServiceRequest("/record_stop", "{}").call, Call::kRecordStop);
  EXPECT_EQ(parseServiceRequest("/alarm_ack", R"({"number": 3})").alarm, 3);
  EXPECT_EQ(parseServiceRequest("/alarm_ack", "{}").call, Call::kAlarmAck);
  EXPECT_FALSE(parseServiceRequest("/alarm_ack", "{}").alarm);
  EXPECT_EQ(parseServiceRequest("/console", R"({"command": "status"})").call, Call::kConsoleLine);
  EXPECT_EQ(parseServiceRequest("/console", R"({"command": "status"})").line, "status");
  // The urgent flag travels with the advertised service (the server's rate limit skips them).
  for (const auto& d : serviceDefs()) EXPECT_EQ(toService(d).urgent, d.name == "/stop" || d.name == "/estop") << d.name;
}

TEST(BridgeServices, NamesWhatIsWrong) {
  EXPECT_EQ(parseServiceRequest("/goto", "{").error, "/goto: the request is not valid JSON");
  EXPECT_EQ(parseServiceRequest("/goto", "[]").error, "/goto: the request must be a JSON object");
  EXPECT_EQ(parseServiceRequest("/goto", R"({"y": 1})").error, "/goto: missing \"x\" (a number)");
  EXPECT_EQ(parseServiceRequest("/goto", R"({"x": "1", "y": 1})").error, "/goto: \"x\" must be a number");
  EXPECT_EQ(parseServiceRequest("/route", R"({"route": "a b"})").error,
            "/route: \"route\" must be one word (1-200 printable characters, no spaces or #)");
  EXPECT_EQ(parseServiceRequest("/stop", R"({"robot": 3})").error, "/stop: \"robot\" must be a string");
  EXPECT_EQ(parseServiceRequest("/control_take", R"({"force": "yes"})").error,
            "/control_take: \"force\" must be true or false");
  EXPECT_EQ(parseServiceRequest("/console", R"({"command": "status\nestop"})").error,
            "/console: \"command\" must be one line without control characters");
  EXPECT_EQ(parseServiceRequest("/alarm_ack", R"({"number": 1.5})").error,
            "/alarm_ack: \"number\" must be an alarm number (1, 2, ...)");
  EXPECT_EQ(parseServiceRequest("/record_start", R"({"name": "a # b"})").error,
            "/record_start: \"name\" must be text of 1-200 printable characters without #");
}
