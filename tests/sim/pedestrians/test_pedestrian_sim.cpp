// Pedestrians in the simulation: route following (start time, pauses, loop),
// seen by the ultrasonic sensors in the crossing world, P rows at 10 Hz in the
// truth log, determinism, and robot-person contact events.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "shared/config/robot_config.hpp"
#include "shared/serial/frame_codec.hpp"
#include "sim/pedestrian_crowd.hpp"
#include "sim/simulation.hpp"
#include "sim/mcu_sim/truth_log.hpp"
#include "tests/support/paths.hpp"
#include "tests/sim/world_text.hpp"

using namespace inspect;
using namespace inspect::sim;

namespace {

using inspect::test::worldOf;
constexpr double kPiOver2 = 1.57079632679489661923;


struct Recorder : SimObserver {
  struct Event {
    double t_s;
    std::string name, detail;
  };
  struct Ped {
    double t_s;
    std::string id;
    double x, y, vx, vy, dist;
    bool operator==(const Ped&) const = default;
  };
  std::vector<Event> events;
  std::vector<Ped> peds;
  std::vector<TruthSample> samples;
  void onSample(const TruthSample& s) override { samples.push_back(s); }
  void onEvent(double t, std::string_view e, std::string_view d) override {
    events.push_back({t, std::string(e), std::string(d)});
  }
  void onPedestrian(const PedestrianSample& s) override {
    peds.push_back({s.sim_t_s, std::string(s.id), s.x_m, s.y_m, s.vx_m_s, s.vy_m_s, s.robot_distance_m});
  }
  std::vector<Event> named(const std::string& name) const {
    std::vector<Event> out;
    for (const auto& e : events)
      if (e.name == name) out.push_back(e);
    return out;
  }
};

std::vector<serial::SensorFrame> decodeFrames(const std::vector<uint8_t>& bytes) {
  serial::FrameDecoder dec;
  std::vector<serial::SensorFrame> out;
  dec.feed(bytes, [&](const serial::Message& m, uint8_t) {
    if (auto* s = std::get_if<serial::SensorFrame>(&m)) out.push_back(*s);
  });
  EXPECT_EQ(dec.counters().errors(), 0u);
  return out;
}

// Runs the crowd alone (robot parked far away) and returns pedestrian 0's
// position every 100 ms.
std::vector<Eigen::Vector2d> walk(double duration_s, PedestrianCrowd& crowd) {
  behavior::Agent robot;
  robot.position_m = {100, 100};
  robot.radius_m = 0.35;
  std::vector<Eigen::Vector2d> out;
  const int steps = static_cast<int>(std::lround(duration_s / 0.001));
  for (int k = 0; k < steps; ++k) {
    if (k % 100 == 0) out.push_back(crowd.present(0) ? crowd.agent(0).position_m : Eigen::Vector2d::Constant(std::nan("")));
    crowd.step(k * 0.001, 0.001, robot);
  }
  return out;
}

}  // namespace

// --- route following ---

TEST(PedestrianCrowd, AbsentBeforeStartThenWalksTheRouteAndStops) {
  const World w = worldOf("pedestrians:\n  - {id: a, start_s: 1.5, route_m: [0, 0, 2, 0]}\n", "peds.yaml");
  Recorder rec;
  PedestrianCrowd crowd(w, &rec);
  EXPECT_FALSE(crowd.present(0));
  EXPECT_TRUE(crowd.circles().empty());
  const auto pos = walk(10.0, crowd);
  for (int i = 0; i < 15; ++i) EXPECT_TRUE(std::isnan(pos[static_cast<std::size_t>(i)].x())) << i;  // t < 1.5 s
  EXPECT_EQ(pos[15], Eigen::Vector2d(0, 0));
  ASSERT_EQ(rec.named("pedestrian_start").size(), 1u);
  EXPECT_NEAR(rec.named("pedestrian_start")[0].t_s, 1.5, 1e-9);
  EXPECT_EQ(rec.named("pedestrian_start")[0].detail, "id=a x=0.000 y=0.000");
  // 2 m at 0.5 m/s: ~4 s plus the relaxation lag; stops within arrive_m (0.3) + overshoot of the end.
  EXPECT_TRUE(crowd.finished(0));
  ASSERT_EQ(rec.named("pedestrian_end").size(), 1u);
  EXPECT_GT(rec.named("pedestrian_end")[0].t_s, 1.5 + (2.0 - 0.3) / 0.5);
  EXPECT_LT(rec.named("pedestrian_end")[0].t_s, 1.5 + 2.0 / 0.5 + 1.0);
  EXPECT_NEAR(crowd.agent(0).position_m.x(), 2.0, 0.3);
  EXPECT_LT(crowd.agent(0).velocity_m_s.norm(), 1e-3) << "stands at the end";
  ASSERT_EQ(crowd.circles().size(), 1u);
  EXPECT_DOUBLE_EQ(crowd.circles()[0].radius_m, 0.25);
  EXPECT_DOUBLE_EQ(crowd.circles()[0].centre.x, crowd.agent(0).position_m.x());
}

TEST(PedestrianCrowd, KeepsHowFarEachHasWalkedAndWhereTheyFaceForTheCamera) {
  // Up the y axis, then back: the camera draws the gait from the distance walked and the
  // front or back from the facing.
  const World w = worldOf("pedestrians:\n  - {id: a, route_m: [0, 0, 0, 3, 0, 0]}\n", "peds.yaml");
  PedestrianCrowd crowd(w);
  EXPECT_NEAR(crowd.facingRad(0), kPiOver2, 1e-9) << "facing the route's second point before walking";
  EXPECT_EQ(crowd.walkedM(0), 0.0);
  behavior::Agent robot;
  robot.position_m = {100, 100};
  double walked_out = 0, facing_out = 0, y_out = 0;
  for (int k = 0; k < 16000; ++k) {
    crowd.step(k * 0.001, 0.001, robot);
    if (k == 4000) {
      walked_out = crowd.walkedM(0);
      facing_out = crowd.facingRad(0);
      y_out = crowd.agent(0).position_m.y();
    }
  }
  EXPECT_NEAR(walked_out, y_out, 0.02) << "a straight walk: the distance walked is the distance from the start";
  EXPECT_GT(walked_out, 1.5);
  EXPECT_NEAR(facing_out, kPiOver2, 0.1) << "walking up: facing +y";
  EXPECT_TRUE(crowd.finished(0));
  EXPECT_NEAR(crowd.walkedM(0), 6.0, 0.6) << "there and back";
  EXPECT_NEAR(std::abs(crowd.facingRad(0)), kPiOver2, 0.3) << "came back facing -y and kept it standing";
  EXPECT_LT(crowd.facingRad(0), 0.0);
}

TEST(PedestrianCrowd, PausesAtAWaypoint) {
  const auto endTime = [](const std::string& yaml, double& slowest_near_wp1) {
    const World w = worldOf(yaml, "peds.yaml");
    Recorder rec;
    PedestrianCrowd crowd(w, &rec);
    const auto pos = walk(14.0, crowd);
    slowest_near_wp1 = 1e9;
    for (std::size_t i = 1; i < pos.size(); ++i)
      if (std::abs(pos[i].x() - 2.0) < 0.3) slowest_near_wp1 = std::min(slowest_near_wp1, (pos[i] - pos[i - 1]).norm() / 0.1);
    EXPECT_TRUE(crowd.finished(0));
    EXPECT_NEAR(crowd.agent(0).position_m.x(), 4.0, 0.3);
    const auto ends = rec.named("pedestrian_end");
    return ends.empty() ? -1.0 : ends[0].t_s;
  };
  double slowest_pause = 0, slowest_walk = 0;
  const double with = endTime("pedestrians:\n  - {route_m: [0, 0, 2, 0, 4, 0], pauses: [{at: 1, s: 3.0}]}\n", slowest_pause);
  const double without = endTime("pedestrians:\n  - {route_m: [0, 0, 2, 0, 4, 0]}\n", slowest_walk);
  // The pause starts on arriving within arrive_m and includes slowing down and starting again.
  EXPECT_NEAR(with - without, 3.0 + 2 * 0.5, 1.0);
  EXPECT_LT(slowest_pause, 0.01) << "stood still at waypoint 1";
  EXPECT_GT(slowest_walk, 0.45) << "without a pause: walked through waypoint 1";
}

TEST(PedestrianCrowd, LoopsForever) {
  const World w = worldOf("pedestrians:\n  - {route_m: [0, 0, 2, 0], loop: true}\n", "peds.yaml");
  Recorder rec;
  PedestrianCrowd crowd(w, &rec);
  const auto pos = walk(20.0, crowd);
  int turns = 0;  // changes of walking direction
  for (std::size_t i = 2; i < pos.size(); ++i)
    turns += ((pos[i].x() - pos[i - 1].x()) > 0) != ((pos[i - 1].x() - pos[i - 2].x()) > 0);
  EXPECT_GE(turns, 3);
  EXPECT_FALSE(crowd.finished(0));
  EXPECT_TRUE(rec.named("pedestrian_end").empty());
}

// --- in the simulation ---

TEST(PedestrianSim, CrossingPersonIsSeenByTheFrontSensorsWhileInTheBeam) {
  const config::RobotConfig robot;
  Simulation sim(robot, loadWorldFile(inspect::test::srcPath("config/worlds/crossing.yaml")), 1);
  // The robot stays at rest (no wheel commands). Record the person at every frame.
  std::vector<Eigen::Vector2d> person;
  for (int t = 0; t < 18000; ++t) {
    if (t % Simulation::kFramePeriod_ms == 0) person.push_back(sim.pedestrians().agent(0).position_m);
    sim.step();
  }
  std::vector<uint8_t> tx;
  sim.takeTx(tx);
  const auto frames = decodeFrames(tx);
  ASSERT_EQ(frames.size(), person.size());

  const auto& us = robot.ultrasonic;
  const double half = us.beam_width_rad / 2;
  int seen = 0, crossed_axis_frames = 0;
  double min_range = 1e9;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const Eigen::Vector2d p = person[i];
    for (int s : {serial::kFrontLeft, serial::kFrontRight}) {
      const auto& m = us.mounts[static_cast<std::size_t>(s)];
      const double ahead = p.x() - m.x_m;       // sensors face +x
      const double lateral = p.y() - m.y_m;
      const uint16_t mm = frames[i].ultrasonic_mm[static_cast<std::size_t>(s)];
      // Clearly outside the cone (body included): nothing in range (the walls are beyond 4.5 m).
      if (std::abs(lateral) > std::tan(half) * ahead + 0.25 / std::cos(half) + 0.05) {
        EXPECT_EQ(mm, serial::kNoEcho) << "sensor " << s << " frame " << i << " person " << p.transpose();
      }
      // On the sensor's axis: the near side of the body, within the noise.
      if (std::abs(lateral) < 0.05) {
        ++crossed_axis_frames;
        ASSERT_NE(mm, serial::kNoEcho) << "sensor " << s << " frame " << i;
        EXPECT_NEAR(mm / 1000.0, ahead - 0.25, us.noise_m + 0.01) << "sensor " << s << " frame " << i;
      }
      if (mm != serial::kNoEcho) {
        ++seen;
        min_range = std::min(min_range, mm / 1000.0);
      }
    }
  }
  EXPECT_GT(crossed_axis_frames, 10) << "the person never crossed the sensor axes";
  EXPECT_GT(seen, 100);
  // The person walks along x ~ 4.0: the body's near side is ~3.45 m from the sensors.
  EXPECT_NEAR(min_range, 4.0 - 0.30 - 0.25, 0.1);
}

TEST(PedestrianSim, TruthLogHasPRowsAt10HzAndPersonEvents) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("ped_truth_" + std::to_string(::getpid()) + ".csv")).string();
  {
    TruthLog truth(path);
    Simulation sim(config::RobotConfig{}, loadWorldFile(inspect::test::srcPath("config/worlds/crossing.yaml")), 1, &truth);
    sim.advanceTo(3000);
  }
  std::ifstream in(path);
  std::string line;
  std::vector<std::vector<std::string>> p_rows;
  bool header = false;
  int t_rows = 0;
  while (std::getline(in, line)) {
    if (line == "# P,mono_ns,sim_t_s,id,x_m,y_m,vx_m_s,vy_m_s,robot_dist_m") header = true;
    if (line.rfind("T,", 0) == 0) ++t_rows;
    if (line.rfind("P,", 0) != 0) continue;
    std::vector<std::string> cols;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) cols.push_back(c);
    p_rows.push_back(cols);
  }
  std::filesystem::remove(path);
  EXPECT_TRUE(header);
  EXPECT_EQ(t_rows, 300);        // T rows unchanged: 100 Hz
  ASSERT_EQ(p_rows.size(), 30u);  // 0.0, 0.1, ... 2.9 s
  for (std::size_t i = 0; i < p_rows.size(); ++i) {
    const auto& r = p_rows[i];
    ASSERT_EQ(r.size(), 9u) << i;
    EXPECT_GT(std::stoll(r[1]), 0);
    EXPECT_NEAR(std::stod(r[2]), 0.1 * static_cast<double>(i), 1e-9);
    EXPECT_EQ(r[3], "crosser");
    const double x = std::stod(r[4]), y = std::stod(r[5]), vx = std::stod(r[6]), vy = std::stod(r[7]);
    EXPECT_NEAR(x, 4.0, 0.02);
    if (i > 0) {
      EXPECT_LT(y, std::stod(p_rows[i - 1][5])) << "walks towards -y";
    }
    if (i >= 25) {  // after 5 tau: at v0 along -y
      EXPECT_NEAR(vy, -0.5, 0.01);
      EXPECT_NEAR(vx, 0.0, 0.01);
    }
    EXPECT_NEAR(std::stod(r[8]), std::hypot(x, y), 1e-3);  // robot at the origin
  }
  EXPECT_NEAR(std::stod(p_rows[0][5]), 3.8, 1e-9);
  EXPECT_NEAR(std::stod(p_rows[0][8]), std::hypot(4.0, 3.8), 1e-3);  // ~5.5 m at the start
}

TEST(PedestrianSim, SameSeedSameTruth) {
  const World w = loadWorldFile(inspect::test::srcPath("config/worlds/encountering.yaml"));
  Recorder a, b;
  Simulation sa(config::RobotConfig{}, w, 7, &a);
  Simulation sb(config::RobotConfig{}, w, 7, &b);
  sa.advanceTo(20000);
  sb.advanceTo(20000);
  ASSERT_EQ(a.peds.size(), 200u);
  EXPECT_TRUE(a.peds == b.peds);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  for (std::size_t i = 0; i < a.samples.size(); ++i) {
    EXPECT_EQ(a.samples[i].pose.x_m, b.samples[i].pose.x_m);
    EXPECT_EQ(a.samples[i].pose.y_m, b.samples[i].pose.y_m);
  }
  std::vector<uint8_t> ta, tb;
  sa.takeTx(ta);
  sb.takeTx(tb);
  EXPECT_EQ(ta, tb);
  // The walker went past the standing robot without touching it.
  EXPECT_EQ(sa.personCollisions(), 0u);
  double min_dist = 1e9;
  for (const auto& p : a.peds) min_dist = std::min(min_dist, p.dist);
  EXPECT_GT(min_dist, 0.35 + 0.25 + 0.2);
  EXPECT_LT(a.peds.back().x, -1.5) << "reached the far end behind the robot";
}

TEST(PedestrianSim, DrivingIntoAPersonLogsOneContact) {
  // A dead end just wider than the robot; the person stands at its end and
  // cannot get out of the way.
  const World w = worldOf(R"(
walls:
  - {points_m: [-1, 0.4,  3, 0.4,  3, -0.4,  -1, -0.4]}
pedestrians:
  - {id: cornered, route_m: [2.6, 0]}
)", "peds.yaml");
  Recorder rec;
  const config::RobotConfig robot;
  Simulation sim(robot, w, 1, &rec);
  serial::FrameEncoder enc;
  for (uint64_t t = 0; t < 8000; t += 10) {
    const auto f = enc.encode(serial::WheelCommand{2500, 2500, serial::WheelCommand::kEnable});  // 0.5 m/s
    sim.receive({f.bytes.data(), f.size});
    sim.advanceTo(t + 10);
  }
  EXPECT_EQ(sim.personCollisions(), 1u);
  const auto hits = rec.named("collision_person");
  ASSERT_EQ(hits.size(), 1u);
  EXPECT_EQ(hits[0].detail.rfind("id=cornered x=", 0), 0u) << hits[0].detail;
  // Contact came when the bodies met: robot front (x + 0.35) at the person's back (~2.75 - 0.25).
  EXPECT_GT(hits[0].t_s, 3.0);
  EXPECT_LT(hits[0].t_s, 6.0);
}
