// Mutual TLS on the robot link: the server and robot_client's ServerLink with
// certificates made by scripts/make_certs.sh, real sockets on 127.0.0.1.
#include <gtest/gtest.h>

#include <filesystem>
#include <thread>

#include <boost/asio/io_context.hpp>

#include "pc_server/app/cli_options.hpp"
#include "pc_server/app/server_config.hpp"
#include "robot_client/client_config.hpp"
#include "robot_client/server_link.hpp"
#include "tests/pc_server/server_fixture.hpp"

namespace inspect::test {
namespace {

using Body = v1::Envelope::BodyCase;

class LinkTlsTest : public ServerFixture {
 protected:
  /// robot_client's link (the real one) against our server, run for up to `for_s`
  /// or until up; returns whether the handshake was accepted.
  bool clientLinkComesUp(client::ClientConfig cfg, double for_s = 2.0) {
    boost::asio::io_context io;
    cfg.server_host = "127.0.0.1";
    cfg.server_port = port_;
    cfg.video.enabled = false;
    client::ServerLink link(io, cfg);
    bool up = false;
    link.start({[&] { up = true; }, nullptr, nullptr});
    const auto deadline = Clock::now() + std::chrono::duration<double>(for_s);
    while (!up && Clock::now() < deadline) io.run_for(20ms);
    link.stop();
    io.run_for(20ms);
    return up;
  }

  static client::ClientConfig robotConfig(const std::string& id, const std::string& certs_dir) {
    client::ClientConfig c;
    c.robot_id = id;
    c.tls.ca = certs_dir + "/ca.pem";
    c.tls.cert = certs_dir + "/" + id + ".pem";
    c.tls.key = certs_dir + "/" + id + ".key";
    c.tls.server_name = "127.0.0.1";
    return c;
  }
};

TEST_F(LinkTlsTest, RobotWithItsOwnCertificateIsAccepted) {
  startServer();
  const auto certs = testCertsDir({"robot1"});
  EXPECT_TRUE(clientLinkComesUp(robotConfig("robot1", certs)));
  EXPECT_TRUE(eventually([&] { return snap("robot1").has_value(); }));
}

TEST_F(LinkTlsTest, RobotIdMustMatchItsCertificate) {
  startServer();
  ScriptedRobot r;
  ASSERT_TRUE(r.connect(port_));
  ASSERT_TRUE(r.handshake("robot2")) << r.tlsError();
  const auto reply = r.hello("robot1");  // robot2's certificate, robot1's id
  ASSERT_TRUE(reply.has_value());
  EXPECT_FALSE(reply->accepted());
  EXPECT_NE(reply->reason().find("does not match its certificate (CN 'robot2')"), std::string::npos)
      << reply->reason();
  EXPECT_FALSE(snap("robot1").has_value());
}

TEST_F(LinkTlsTest, PlaintextRobotIsRefusedAndOthersAreServed) {
  startServer();
  ScriptedRobot good;
  ASSERT_TRUE(good.connect(port_));
  ASSERT_TRUE(good.hello("good"));
  good.startPump(50);
  ScriptedRobot plain(ScriptedRobot::Mode::kPlaintext);
  ASSERT_TRUE(plain.connect(port_));
  EXPECT_FALSE(plain.hello("robot1").has_value());
  EXPECT_TRUE(plain.waitClosed(2000ms));
  EXPECT_FALSE(snap("robot1").has_value());
  ASSERT_TRUE(eventually([&] { return snap("good") && snap("good")->telemetry_count > 10; }));
  EXPECT_TRUE(connected("good"));
}

TEST_F(LinkTlsTest, CertificateOfAnotherCaIsRefused) {
  startServer();
  ScriptedRobot r(ScriptedRobot::Mode::kTls, testCertsDir({"robot1"}, "test_certs_other_ca"));
  ASSERT_TRUE(r.connect(port_));
  EXPECT_FALSE(r.hello("robot1").has_value());
  EXPECT_FALSE(r.tlsError().empty());
  EXPECT_FALSE(snap("robot1").has_value());
  // And robot_client's link refuses a server of another CA (its CA file is the other one).
  auto cfg = robotConfig("robot1", testCertsDir({"robot1"}));
  cfg.tls.ca = testCertsDir({}, "test_certs_other_ca") + "/ca.pem";
  EXPECT_FALSE(clientLinkComesUp(cfg, 1.0));
}

TEST_F(LinkTlsTest, RobotWithoutCertificateIsRefused) {
  startServer();
  ScriptedRobot r(ScriptedRobot::Mode::kTlsNoCertificate);
  ASSERT_TRUE(r.connect(port_));
  EXPECT_FALSE(r.hello("robot1").has_value());
  EXPECT_FALSE(snap("robot1").has_value());
}

TEST_F(LinkTlsTest, RobotCertificateCannotPoseAsTheServer) {
  // A stolen robot key must not let anyone impersonate pc_server: the robot
  // requires a certificate made for server authentication.
  const auto certs = testCertsDir({"robot1", "robot2"});
  auto config = testConfig();
  config.tls.cert = certs + "/robot2.pem";
  config.tls.key = certs + "/robot2.key";
  startServer(config);
  EXPECT_FALSE(clientLinkComesUp(robotConfig("robot1", certs), 1.0));
}

TEST_F(LinkTlsTest, ServerCertificateMustNameTheHost) {
  startServer();
  auto cfg = robotConfig("robot1", testCertsDir({"robot1"}));
  cfg.tls.server_name = "pc.elsewhere.example";
  EXPECT_FALSE(clientLinkComesUp(cfg, 1.0));
  cfg.tls.server_name = "localhost";  // in the certificate's names
  EXPECT_TRUE(clientLinkComesUp(cfg));
}

TEST_F(LinkTlsTest, PlaintextOnlyWhenBothSidesAskForIt) {
  auto config = testConfig();
  config.tls.plaintext = true;
  startServer(config);
  ScriptedRobot r(ScriptedRobot::Mode::kPlaintext);
  ASSERT_TRUE(r.connect(port_));
  const auto reply = r.hello("robot1");
  ASSERT_TRUE(reply.has_value());
  EXPECT_TRUE(reply->accepted());
  // A TLS robot does not fall back to plaintext.
  EXPECT_FALSE(clientLinkComesUp(robotConfig("robot2", testCertsDir({"robot2"})), 1.0));
}

TEST(TlsFiles, ClearErrorsNamingTheFile) {
  const auto certs = testCertsDir({"robot1", "robot2"});
  const auto expectError = [](const net::TlsFiles& f, const std::string& needle) {
    try {
      net::makeTlsContext(f, net::TlsRole::kClient);
      ADD_FAILURE() << "no error, expected " << needle;
    } catch (const net::TlsError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  expectError({certs + "/ca.pem", certs + "/nobody.pem", certs + "/robot1.key"}, "nobody.pem': cannot open");
  expectError({certs + "/nothing.pem", certs + "/robot1.pem", certs + "/robot1.key"}, "nothing.pem");
  expectError({certs + "/ca.pem", certs + "/robot1.pem", certs + "/robot2.key"},
              "robot2.key' does not belong to certificate");
  expectError({certs + "/ca.pem", certs + "/robot1.key", certs + "/robot1.key"}, "not a PEM certificate");
  // The description names the subject and expiry, never the key.
  const auto d = net::describeCertificate(certs + "/robot1.pem");
  EXPECT_NE(d.find("CN=robot1"), std::string::npos) << d;
  EXPECT_EQ(d.find("PRIVATE"), std::string::npos) << d;
}

TEST(TlsConfig, FilesAndFlags) {
  const auto root = config::ConfigNode::loadString("tls:\n  ca: \"\"\n", "server.yaml");
  EXPECT_THROW(server::loadServerConfig(root), config::ConfigError);
  const auto ok = server::loadServerConfig(config::ConfigNode::loadString("tls:\n  ca: /etc/inspect/ca.pem\n", "s.yaml"));
  EXPECT_EQ(ok.tls.ca, "/etc/inspect/ca.pem");
  EXPECT_FALSE(ok.tls.plaintext);
  EXPECT_THROW(server::parseCli({"--plaintext", "--certs", "x"}), server::UsageError);
  EXPECT_TRUE(server::parseCli({"--plaintext"}).plaintext);
  const auto c = client::loadClientConfig(config::ConfigNode::loadString("tls:\n  server_name: pc.local\n", "c.yaml"));
  EXPECT_EQ(c.tls.server_name, "pc.local");
  EXPECT_FALSE(c.tls.plaintext);
}

}  // namespace
}  // namespace inspect::test
