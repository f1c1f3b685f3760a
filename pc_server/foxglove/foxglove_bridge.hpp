#pragma once
// pc_server's Foxglove bridge (docs/foxglove.md): every robot's telemetry,
// events, acks, alarms, camera and 3-D scene live on the Foxglove WebSocket
// protocol, and from the clients teleop set-points and service calls, each
// client an operator session of its own (it observes until it takes control;
// stop and e-stop always work; teleop lapses when the client stops sending).
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include "pc_server/console/console.hpp"
#include "pc_server/foxglove/bridge_services.hpp"
#include "pc_server/foxglove/client_operator.hpp"
#include "pc_server/foxglove/ws_server.hpp"
#include "pc_server/scene/camera_people.hpp"
#include "pc_server/scene/robot_scene.hpp"
#include "pc_server/scene/scene_feed.hpp"
#include "pc_server/scene/site_maps.hpp"
#include "pc_server/scene/topics.hpp"
#include "shared/video/rtp_h264.hpp"

namespace inspect::server::foxglove {

class FoxgloveBridge : public WsServer::Handler {
 public:
  /// At most this many /console lines run at once, whatever the number of clients.
  static constexpr std::size_t kConsoleThreads = 2;
  struct Options {
    WsServer::Options server;
    double scene_hz = 10;          // SceneUpdate per robot
    double grid_hz = 1;            // gas grids per robot and channel
    double teleop_timeout_s = 0.3; // a set-point not renewed this long lapses to zero (the session's lease)
    double max_v_m_s = 1.0;        // teleop limits (the console's)
    double max_w_rad_s = 2.0;
    /// Where /record_start, /record_stop and /inspect record (null: the server records nothing).
    Recorder* recorder = nullptr;
    /// The server's receive figures of a robot's stream (VideoHub), for
    /// /<robot>/video_stats once a second; unset or nullopt = none.
    std::function<std::optional<v1::VideoReceiveStats>(const std::string& robot)> video_stats;
  };

  FoxgloveBridge(boost::asio::io_context& ioc, Options options, RobotRegistry& registry, CommandSink& sink,
                 ControlArbiter& control, scene::SiteMaps& maps, scene::Geometry geometry,
                 Console::Options console_options, ClientOperator::Configure configure);
  ~FoxgloveBridge() override;

  /// Listens and starts the timers. Throws util::StartupError.
  boost::asio::ip::tcp::endpoint start();
  /// Closes the clients (their sessions end, robots they drove are stopped); idempotent.
  void stop();

  /// Every envelope to or from a robot (LinkServer's observer; any thread).
  void onEnvelope(const std::string& robot, const v1::Envelope& env, bool inbound, uint64_t time_us);
  /// Every intact access unit of a robot's camera head (VideoHub's hook):
  /// /<robot>/camera, or /<robot>/camera_wide for the wide head.
  void onAccessUnit(const std::string& robot, v1::CameraHead head, const video::Frame& frame, uint64_t capture_us);

  /// The `foxglove` console command's text: clients, subscriptions, queues, drops.
  std::string report() const;
  /// Figures for tests and benchmarks.
  std::vector<WsServer::ClientInfo> clients() const { return server_.clients(); }
  const WsServer& server() const { return server_; }

  // WsServer::Handler
  void onClientOpen(uint64_t client, const std::string& peer) override;
  void onClientClose(uint64_t client) override;
  void onSubscribe(uint64_t client, uint32_t channel) override;
  void onClientMessage(uint64_t client, const ClientChannel& channel, std::string_view payload) override;
  void onServiceCall(uint64_t client, const Service& service, uint32_t call_id, std::string_view payload) override;

 private:
  struct RobotChannels {
    uint32_t telemetry = 0, events = 0, acks = 0, alarms = 0, camera = 0, camera_people = 0, tf = 0, scene = 0, log = 0,
             video_stats = 0;
    // The wide head's, advertised once the robot's telemetry shows its stream (Telemetry.wide_video).
    uint32_t camera_wide = 0, camera_wide_people = 0;
    std::map<std::string, uint32_t> grids;  // gas channel -> channel id
    std::vector<uint32_t> all() const;
  };
  struct RobotState {
    std::unique_ptr<scene::SceneFeed> feed;  // the scene, its map, the camera's people
    RobotChannels ch;
    bool connected = false;
    std::chrono::steady_clock::time_point last_grid{};
    std::chrono::steady_clock::time_point last_video_stats{};
    // For a new video subscriber, at most once a second per head.
    std::chrono::steady_clock::time_point keyframe_asked{}, wide_keyframe_asked{};
  };
  struct Client {
    std::shared_ptr<ClientOperator> op;
    std::string peer;
    std::string teleop_robot;  // "" = not driving
    std::string selected;      // the robot its last call named ("" = none yet: the console session's)
    std::chrono::steady_clock::time_point last_teleop{};
    std::chrono::steady_clock::time_point last_refusal{};
  };

  void tick();         // every 1 / scene_hz: robots appear and go, scenes and grids
  v1::VideoStats videoStats(const std::string& robot) const;
  void deadman();      // every 50 ms: teleop set-points that lapsed
  void advertiseRobot(const std::string& robot, RobotState& r);
  void unadvertiseRobot(RobotState& r);
  void advertiseWideHead(const std::string& robot, RobotState& r);
  uint32_t addTopic(const std::string& robot, scene::TopicKind kind);
  uint32_t addChannel(const std::string& topic, const google::protobuf::Descriptor* d, WsServer::Kind kind);
  void publishMessage(uint32_t channel, uint64_t ns, const google::protobuf::Message& m);
  void teleop(uint64_t client, const std::string& robot, std::string_view payload);
  void refuse(uint64_t client, const std::string& why);
  std::string robotOfTopic(const std::string& topic) const;
  /// The client's operator session (null once it has gone).
  std::shared_ptr<ClientOperator> operatorOf(uint64_t client) const;
  void stopRobot(const std::string& robot, uint64_t session);
  /// A typed service call through the operator service; the answer is sent when it settles.
  void callService(uint64_t client, const ClientOperator& op, uint32_t service_id, uint32_t call_id,
                   const ServiceRequest& req);
  /// The operator service's call for a typed request; `preface` gets a line
  /// to print before its result (a route's summary).
  Issued issue(const ServiceRequest& req, uint64_t session, const std::string& robot, std::string& preface);
  /// Polls a pending call every kCallPollPeriod until the robot's Ack or the
  /// deadline; then answers with preface, the control note and the result.
  void awaitCall(uint64_t client, uint32_t service_id, uint32_t call_id, PendingCall pending, std::string preface);
  /// Stops `robot` if `session` still holds its control; false (nothing sent) otherwise.
  bool stopIfHeld(const std::string& robot, uint64_t session);

  boost::asio::io_context& ioc_;
  Options options_;
  RobotRegistry& registry_;
  CommandSink& sink_;
  ControlArbiter& control_;
  scene::SiteMaps& maps_;
  scene::Geometry geometry_;
  Console::Options console_options_;
  ClientOperator::Configure configure_;
  WsServer server_;
  boost::asio::steady_timer tick_timer_, deadman_timer_;
  OperatorService service_;
  /// Timers of calls waiting for an Ack (cancelled by stop()).
  std::vector<std::weak_ptr<boost::asio::steady_timer>> call_timers_;
  std::map<std::string, uint32_t> service_ids_;  // name -> id

  mutable std::mutex mu_;
  bool stopped_ = false;
  std::map<std::string, RobotState> robots_;
  std::map<uint64_t, Client> clients_;
  std::map<std::string, std::string> schemas_;  // message type -> base64 FileDescriptorSet
  /// The threads of the clients' /console lines (bounded; one line at a time per client).
  ConsolePool console_pool_{kConsoleThreads};
};

}  // namespace inspect::server::foxglove
