// The robot's event journal and outbox (store-and-forward): real files in a
// temporary folder; torn and corrupt records; a full disk (RLIMIT_FSIZE in a
// child process stands in for it: a small tmpfs needs root).
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "robot_client/event_journal.hpp"
#include "robot_client/event_outbox.hpp"
#include "tests/support/process.hpp"

using namespace inspect;
using client::EventJournal;
using client::EventOutbox;

namespace {

v1::Envelope eventEnv(const std::string& text, v1::Event::Kind kind = v1::Event::INFO) {
  v1::Envelope env;
  env.mutable_event()->set_kind(kind);
  env.mutable_event()->set_text(text);
  if (kind == v1::Event::ALARM_RAISED) env.mutable_event()->mutable_gas_alarm()->set_id(7);
  return env;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void spit(const std::string& path, const std::string& data) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << data;
}

std::vector<std::string> texts(const EventOutbox& o) {
  std::vector<std::string> v;
  o.forEachPending([&](const v1::Envelope& e) { v.push_back(e.event().text()); });
  return v;
}

}  // namespace

TEST(EventJournal, PendingEntriesSurviveAReopenAndDeliveredOnesDoNot) {
  test::TempDir dir("journal");
  const std::string path = dir / "events.journal";
  uint64_t stream = 0;
  {
    EventOutbox o(path, 100, 0);
    stream = o.stream();
    EXPECT_NE(stream, 0u);
    for (int i = 0; i < 5; ++i) {
      auto env = eventEnv("e" + std::to_string(i));
      o.store(env, 1000 + i);
      EXPECT_EQ(env.event().stored().seq(), static_cast<uint64_t>(i + 1));
      EXPECT_EQ(env.event().stored().wall_time_us(), static_cast<uint64_t>(1000 + i));
    }
    o.delivered(stream, 2);
    o.delivered(stream + 1, 5);  // another stream's confirmation changes nothing
    EXPECT_EQ(o.pending(), 3u);
  }
  EventOutbox again(path, 100, 0);
  EXPECT_EQ(again.stream(), stream);
  EXPECT_EQ(again.counters().loaded, 3u);
  EXPECT_EQ(texts(again), (std::vector<std::string>{"e2", "e3", "e4"}));
  // Numbering goes on after the highest number the file has seen.
  auto env = eventEnv("e5");
  again.store(env, 2000);
  EXPECT_EQ(env.event().stored().seq(), 6u);
  // Sent after the next Hello: the three from before the restart marked
  // replayed, the live one not; in order; then nothing more on this connection.
  again.linkUp();
  std::vector<std::pair<uint64_t, bool>> sent;
  auto send = [&](const v1::Envelope& e) { sent.emplace_back(e.event().stored().seq(), e.event().stored().replayed()); };
  EXPECT_EQ(again.sendNext(send, 2), 2u);  // a budget per call
  EXPECT_EQ(again.sendNext(send, 100), 2u);
  EXPECT_EQ(again.sendNext(send, 100), 0u);
  auto live = eventEnv("e6");
  again.store(live, 2001);
  EXPECT_EQ(again.sendNext(send, 100), 1u);
  EXPECT_EQ(sent, (std::vector<std::pair<uint64_t, bool>>{{3, true}, {4, true}, {5, true}, {6, true}, {7, false}}));
  // A reconnect sends what is still pending again, all replayed.
  again.delivered(stream, 4);
  again.linkDown();
  again.linkUp();
  sent.clear();
  again.sendNext(send, 100);
  EXPECT_EQ(sent, (std::vector<std::pair<uint64_t, bool>>{{5, true}, {6, true}, {7, true}}));
  // Nothing goes while the link is down.
  again.linkDown();
  EXPECT_EQ(again.sendNext(send, 100), 0u);
}

TEST(EventJournal, ATornTailAndACorruptRecordAreSkippedWithTheirReason) {
  test::TempDir dir("journal");
  const std::string path = dir / "events.journal";
  {
    EventOutbox o(path, 100, 0);
    for (int i = 0; i < 4; ++i) {
      auto env = eventEnv("entry-" + std::to_string(i));
      o.store(env, 1);
    }
  }
  std::string data = slurp(path);
  // Flip one byte inside the second entry's payload (a bad sector), and cut
  // the last entry short (power lost mid-write).
  const auto second = data.find("entry-1");
  ASSERT_NE(second, std::string::npos);
  data[second + 2] ^= 0x20;
  data.resize(data.size() - 3);
  spit(path, data);

  const auto read = EventJournal::read(path);
  ASSERT_EQ(read.skipped.size(), 2u);
  EXPECT_NE(read.skipped[0].find("checksum mismatch (seq 2)"), std::string::npos) << read.skipped[0];
  EXPECT_NE(read.skipped[1].find("torn record at the end"), std::string::npos) << read.skipped[1];
  EventOutbox o(path, 100, 0);
  EXPECT_EQ(o.counters().skipped, 2u);
  EXPECT_EQ(texts(o), (std::vector<std::string>{"entry-0", "entry-2"}));
  // Opening rewrote the file: read again, nothing is skipped.
  EXPECT_TRUE(EventJournal::read(path).skipped.empty());
}

TEST(EventJournal, GarbageAndAnEmptyFileGiveANewStream) {
  test::TempDir dir("journal");
  const std::string path = dir / "events.journal";
  spit(path, std::string(1000, '\x5a'));
  EventOutbox o(path, 100, 0);
  EXPECT_NE(o.stream(), 0u);
  EXPECT_EQ(o.pending(), 0u);
  EXPECT_EQ(o.counters().skipped, 1u);
  EXPECT_NE(o.skippedRecords().at(0).find("bad magic"), std::string::npos);
  spit(dir / "empty.journal", "");
  EventOutbox e(dir / "empty.journal", 100, 0);
  EXPECT_NE(e.stream(), o.stream());
}

TEST(EventJournal, AFullQueueDropsTheOldestNonAlarmAndNeverAnAlarm) {
  test::TempDir dir("journal");
  const std::string path = dir / "events.journal";
  {
    EventOutbox o(path, 3, 0);
    auto a = eventEnv("alarm", v1::Event::ALARM_RAISED);
    o.store(a, 1);
    for (int i = 0; i < 4; ++i) {
      auto env = eventEnv("info-" + std::to_string(i));
      o.store(env, 1);
    }
    EXPECT_EQ(o.counters().dropped, 2u);
    EXPECT_EQ(texts(o), (std::vector<std::string>{"alarm", "info-2", "info-3"}));
    // Alarms only: the bound yields.
    for (int i = 0; i < 4; ++i) {
      auto env = eventEnv("alarm-" + std::to_string(i), v1::Event::ALARM_RAISED);
      o.store(env, 1);
    }
    EXPECT_EQ(o.pending(), 5u);
    EXPECT_EQ(o.counters().dropped, 4u);
  }
  // The journal knows what was dropped.
  EventOutbox again(path, 3, 0);
  EXPECT_EQ(texts(again), (std::vector<std::string>{"alarm", "alarm-0", "alarm-1", "alarm-2", "alarm-3"}));
}

TEST(EventJournal, ADiskThatCannotBeWrittenIsReportedNotFatal) {
  // A full disk, in a child process: RLIMIT_FSIZE at the journal's size makes
  // every further write fail (EFBIG, as ENOSPC would), SIGXFSZ ignored.
  test::TempDir dir("journal");
  const std::string path = dir / "events.journal";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    int bad = 0;
    {
      EventOutbox o(path, 100, 0);
      std::signal(SIGXFSZ, SIG_IGN);
      const rlimit lim{static_cast<rlim_t>(std::filesystem::file_size(path)), RLIM_INFINITY};
      ::setrlimit(RLIMIT_FSIZE, &lim);
      auto env = eventEnv("kept in memory");
      o.store(env, 1);
      if (o.pending() != 1) bad |= 1;
      if (o.counters().journal_errors < 1) bad |= 2;
      if (o.journalError().find("cannot append") == std::string::npos) bad |= 4;
      std::printf("journal error: %s\n", o.journalError().c_str());
      o.delivered(o.stream(), 1);  // the delivered mark fails too: still no crash
      if (o.pending() != 0) bad |= 8;
    }
    std::_Exit(bad);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "bits: 1 lost, 2 not counted, 4 not said, 8 delivery";
  // A folder that cannot exist: memory only, said so.
  EventOutbox none("/proc/no/such/dir/events.journal", 100, 0);
  auto e2 = eventEnv("x");
  none.store(e2, 1);
  EXPECT_EQ(none.pending(), 1u);
  EXPECT_FALSE(none.hasJournal());
  EXPECT_FALSE(none.journalError().empty());
}

TEST(EventJournal, DeliveryCompactsTheFile) {
  test::TempDir dir("journal");
  const std::string path = dir / "events.journal";
  EventOutbox o(path, 100000, 0);
  std::string text(200, 'x');
  for (int i = 0; i < 600; ++i) {
    auto env = eventEnv(text);
    o.store(env, 1);
  }
  const auto before = std::filesystem::file_size(path);
  EXPECT_GT(before, 64u * 1024);
  o.delivered(o.stream(), 600);
  EXPECT_LT(std::filesystem::file_size(path), 100u);
  EXPECT_EQ(o.pending(), 0u);
  // And the next entry is numbered on.
  auto env = eventEnv("next");
  o.store(env, 1);
  EXPECT_EQ(env.event().stored().seq(), 601u);
}
