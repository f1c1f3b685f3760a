// Recording of a run through the real programs: the server writes run.mcap,
// video.mp4 and the catalog; independent readers (@mcap/core from npm,
// ffprobe, sqlite3) open them; a SIGKILLed server loses at most about a second
// and repairs the run at its next start.
#include <gtest/gtest.h>

#include <signal.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <string>
#include <thread>

#include "shared/catalog/catalog.hpp"
#include "tests/support/stack.hpp"
#include "tests/support/test_certs.hpp"

using namespace inspect::test;

namespace {



int ffprobeFrames(const std::string& mp4) {
  const auto out = captureOutput("ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames "
                           "-of csv=p=0 " + mp4);
  return std::atoi(out.c_str());
}

std::string runDir(const std::string& runs, const std::string& id) { return runs + "/" + id; }

}  // namespace

TEST(RecordingStack, RunsAreRecordedReadAndSurviveAServerKill) {
  const char* reader = std::getenv("INSPECT_MCAP_READER");
  ASSERT_NE(reader, nullptr) << "INSPECT_MCAP_READER: the @mcap/core reader (ctest fixture mcap_reader)";
  Stack s("record");
  s.enableVideo();
  const std::string runs = s.dir() / "runs";
  ASSERT_TRUE(s.startServer("expect robots >= 1 within 15\n"
                            "record start first run\n"
                            "drive 0.3 0.3\n"
                            "wait 4\n"
                            "stop\n"
                            "wait 1\n"
                            "record stop\n"
                            "runs\n"
                            "run show 1\n"
                            "record start second run\n"
                            "drive 0.2 0\n"
                            "wait 60\n",
                            {"--runs-dir", runs}))
      << s.logs();
  auto& robot = s.startRobot("robot1");

  // Kill the server 4 s into the second run.
  // (The server's stdout is block-buffered into its file: watch the run directories.)
  const auto runDirs = [&] {
    int n = 0;
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(runs, ec))
      n += e.is_directory() && e.path().filename().string().find("-robot1") != std::string::npos;
    return n;
  };
  ASSERT_TRUE(waitUntil([&] { return runDirs() == 2; }, 40.0)) << s.logs();
  std::this_thread::sleep_for(std::chrono::seconds(4));
  const auto kill_time = std::chrono::system_clock::now();
  s.server().signal(SIGKILL);
  ASSERT_TRUE(s.server().wait(5.0).has_value());
  robot.client.terminate();
  const std::string out = s.serverOutput();

  std::smatch m;
  std::vector<std::string> ids;
  const std::regex re_id("recording run ([0-9]{8}-[0-9]{6}-robot1(-[0-9]+)?)");
  for (std::sregex_iterator it(out.begin(), out.end(), re_id), end; it != end; ++it) ids.push_back((*it)[1]);
  ASSERT_EQ(ids.size(), 2u) << out;

  // 1. The first run, ended normally: every reader opens it.
  const std::string first = runDir(runs, ids[0]);
  const auto counts = captureOutput(std::string("node ") + reader + " " + first + "/run.mcap");
  EXPECT_GT(mcapTopicCount(counts, "/robot1/telemetry"), 150) << counts;  // 50 Hz for ~5 s
  EXPECT_GT(mcapTopicCount(counts, "/robot1/camera"), 90) << counts;      // 30 fps (~150, less the stream's start)
  EXPECT_GT(mcapTopicCount(counts, "/robot1/commands"), 20) << counts;     // teleop re-sent at 20 Hz
  EXPECT_GT(mcapTopicCount(counts, "/robot1/acks"), 20) << counts;
  EXPECT_GE(mcapTopicCount(counts, "/robot1/server_events"), 2) << counts;
  EXPECT_EQ(mcapTopicCount(counts, "/robot1/robot_info"), 1) << counts;  // the robot's Hello at the start
  EXPECT_GT(ffprobeFrames(first + "/video.mp4"), 90);
  // ...and finds exactly the messages the server wrote ("run <id> ended (stopped): N messages" in its log).
  {
    const std::string err = readFile(s.dir() / "server.err");
    const std::regex re_end("run " + ids[0] + " ended \\(stopped\\): ([0-9]+) messages");
    std::smatch me;
    ASSERT_TRUE(std::regex_search(err, me, re_end)) << err;
    int read_total = 0;
    // The live view's names (pc_server/scene/topics), prefixed with the robot.
    for (const char* t : {"telemetry", "camera", "commands", "acks", "events", "server_events", "robot_info", "tf",
                          "scene", "log", "gas/CH4", "gas/H2S", "gas/CO", "gas/O2"})
      read_total += std::max(mcapTopicCount(counts, std::string("/robot1/") + t), 0);
    EXPECT_EQ(read_total, std::stoi(me[1])) << counts;
  }
  EXPECT_NE(out.find("distance "), std::string::npos) << out;  // run show
  EXPECT_NE(out.find("stopped"), std::string::npos) << out;

  // 2. After the kill: the catalog is intact, the next start marks the run
  // incomplete and repairs its MCAP file; the MP4 plays to its last fragment.
  {
    auto cat = inspect::catalog::Catalog::open(runs + "/catalog.sqlite");
    EXPECT_EQ(cat.integrityCheck(), "ok");
    EXPECT_TRUE(cat.activeRun("robot1").has_value());
  }
  const std::string second = runDir(runs, ids[1]);
  writeFile(s.dir() / "restart.txt", "runs\nrun show 2\nreport 1\nexport 1 csv\nreplay 1 20\n");
  auto restarted = Process::spawn({binPath("pc_server"), "--config", srcPath("config/server.yaml"), "--bind",
                                   "127.0.0.1", "--port", "0", "--no-video", "--no-foxglove", "--certs", testCertsDir(), "--runs-dir",
                                   runs, "--script",
                                   s.dir() / "restart.txt"},
                                  s.dir() / "restart.out", s.dir() / "restart.err");
  ASSERT_TRUE(restarted.wait(20.0).has_value());
  const std::string rout = readFile(s.dir() / "restart.out");
  EXPECT_NE(rout.find(ids[1] + ": marked incomplete, MCAP repaired"), std::string::npos) << rout;
  EXPECT_NE(rout.find("incomplete"), std::string::npos) << rout;
  // report, export and replay read the first run back.
  EXPECT_NE(rout.find(ids[0] + ": report "), std::string::npos) << rout;
  for (const char* png : {"trajectory.png", "speed_people.png"})
    EXPECT_TRUE(exists(first + "/report/" + png)) << png << "\n" << rout;
  EXPECT_TRUE(exists(first + "/report/summary.md"));
  // + /robot_info and /log; the 3-D scene's channels (/tf, /scene, /gas/*) are drawings, not tables.
  EXPECT_NE(rout.find(ids[0] + ": exported 8 CSV files"), std::string::npos) << rout;
  EXPECT_NE(readFile(first + "/csv/telemetry.csv").find("pose.x_m"), std::string::npos);
  EXPECT_NE(rout.find("replay of " + ids[0] + " done"), std::string::npos) << rout;
  EXPECT_NE(rout.find("| TELEOP |"), std::string::npos) << rout;
  EXPECT_NE(rout.find("| gas CH4 "), std::string::npos) << "the replay names the gas channels as live: " << rout;
  {
    auto cat = inspect::catalog::Catalog::open(runs + "/catalog.sqlite");
    EXPECT_EQ(cat.integrityCheck(), "ok");
    const auto d = cat.run(ids[1]);
    ASSERT_TRUE(d.has_value());
    EXPECT_EQ(d->info.outcome, "incomplete");
    // Seconds of telemetry lost: from the last message kept to the kill.
    const auto counts2 = captureOutput(std::string("node ") + reader + " " + second + "/run.mcap");
    const int telemetry = mcapTopicCount(counts2, "/robot1/telemetry");
    const double recorded_s = std::chrono::duration<double>(kill_time - d->info.start).count();
    const double lost_s = recorded_s - telemetry / 50.0;
    std::printf("second run: %.2f s recorded before the kill, %d telemetry messages kept (%.2f s at 50 Hz): "
                "about %.2f s lost; %d camera frames kept; mp4 %d frames\n",
                recorded_s, telemetry, telemetry / 50.0, lost_s, mcapTopicCount(counts2, "/robot1/camera"),
                ffprobeFrames(second + "/video.mp4"));
    EXPECT_GT(telemetry, 100) << counts2;
    EXPECT_LT(lost_s, 1.5) << counts2;  // 1 s of chunk + telemetry jitter
    EXPECT_GT(ffprobeFrames(second + "/video.mp4"), 60);
  }
}
