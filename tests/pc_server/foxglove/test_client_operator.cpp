// A Foxglove client's console lines on the bridge's bounded pool: in order
// and one at a time per client, at most kMaxQueued waiting, other clients
// going on while one waits, and a client that leaves interrupted at once.
#include <gtest/gtest.h>

#include "tests/support/null_command_sink.hpp"

#include <chrono>
#include <condition_variable>
#include <future>
#include <mutex>
#include <vector>

#include <boost/asio/post.hpp>

#include "pc_server/foxglove/client_operator.hpp"

using namespace inspect;
using namespace inspect::server;
using namespace inspect::server::foxglove;
using namespace std::chrono_literals;

namespace {

using NullSink = inspect::test::NullCommandSink;

/// The answers a client got, in the order they came.
struct Answers {
  std::mutex mu;
  std::condition_variable cv;
  std::vector<std::pair<bool, std::string>> got;
  ClientOperator::Done done() {
    return [this](bool ok, const std::string& text) {
      std::lock_guard lk(mu);
      got.emplace_back(ok, text);
      cv.notify_all();
    };
  }
  /// True once n answers are in (waits at most 10 s).
  bool waitFor(std::size_t n) {
    std::unique_lock lk(mu);
    return cv.wait_for(lk, 10s, [&] { return got.size() >= n; });
  }
};

class ClientOperatorTest : public ::testing::Test {
 protected:
  std::shared_ptr<ClientOperator> client(ConsolePool& pool, const std::string& who) {
    return std::make_shared<ClientOperator>(who, registry_, sink_, control_, Console::Options{}, nullptr, pool);
  }
  RobotRegistry registry_;
  NullSink sink_;
  ControlArbiter control_;
};

}  // namespace

TEST_F(ClientOperatorTest, LinesOfAClientRunInOrderAndAnswerWithTheirOutput) {
  ConsolePool pool(2);
  auto op = client(pool, "foxglove a");
  Answers a;
  for (const char* line : {"echo one", "echo two", "frobnicate", "echo three"}) ASSERT_TRUE(op->post("", line, a.done()));
  ASSERT_TRUE(a.waitFor(4));
  EXPECT_EQ(a.got[0], std::make_pair(true, std::string("one")));
  EXPECT_EQ(a.got[1], std::make_pair(true, std::string("two")));
  EXPECT_FALSE(a.got[2].first);
  EXPECT_NE(a.got[2].second.find("frobnicate"), std::string::npos) << a.got[2].second;
  EXPECT_EQ(a.got[3], std::make_pair(true, std::string("three")));
}

TEST_F(ClientOperatorTest, AtMostKMaxQueuedLinesWaitPerClient) {
  ConsolePool pool(1);
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  boost::asio::post(pool.executor(), [released] { released.wait_for(10s); });  // the only thread, busy
  auto op = client(pool, "foxglove a");
  Answers a;
  for (std::size_t i = 0; i < ClientOperator::kMaxQueued; ++i) EXPECT_TRUE(op->post("", "echo " + std::to_string(i), a.done()));
  EXPECT_FALSE(op->post("", "echo too many", a.done())) << "a ninth line waiting is refused";
  release.set_value();
  ASSERT_TRUE(a.waitFor(ClientOperator::kMaxQueued));
  EXPECT_EQ(a.got.back().second, std::to_string(ClientOperator::kMaxQueued - 1));
  EXPECT_TRUE(op->post("", "echo again", a.done())) << "room again once they ran";
  ASSERT_TRUE(a.waitFor(ClientOperator::kMaxQueued + 1));
}

TEST_F(ClientOperatorTest, OneClientWaitingHoldsNoOtherAndLeavingInterruptsIt) {
  ConsolePool pool(2);
  auto slow = client(pool, "foxglove slow");
  auto quick = client(pool, "foxglove quick");
  const uint64_t slow_session = slow->session();
  Answers s, q;
  ASSERT_TRUE(slow->post("", "wait 30", s.done()));
  ASSERT_TRUE(quick->post("", "echo here", q.done()));
  ASSERT_TRUE(q.waitFor(1)) << "the other client's line ran while the first waited";
  EXPECT_EQ(q.got[0].second, "here");
  {
    std::lock_guard lk(s.mu);
    EXPECT_TRUE(s.got.empty()) << "wait 30 is still waiting";
  }
  const auto t0 = std::chrono::steady_clock::now();
  slow->end();
  EXPECT_FALSE(slow->post("", "echo after", s.done())) << "a client that left takes no more lines";
  slow.reset();
  ASSERT_TRUE(s.waitFor(1));
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 5s) << "leaving interrupted the wait";
  EXPECT_FALSE(s.got[0].first);
  EXPECT_NE(s.got[0].second.find("interrupted"), std::string::npos) << s.got[0].second;
  pool.join();
  EXPECT_EQ(control_.sessionName(slow_session).find("foxglove slow"), std::string::npos)
      << "the session closed with its last line: " << control_.sessionName(slow_session);
}
