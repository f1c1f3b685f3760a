#pragma once
// robot_client settings (config/client.yaml) and their loader.
#include <string>

#include "shared/config/config_node.hpp"
#include "shared/robot/safety_params.hpp"

namespace inspect::client {

/// Camera stream (docs/video.md); becomes video::SenderSettings.
struct VideoParams {
  bool enabled = true;
  std::string source = "synthetic";  // "synthetic", "v4l2:/dev/videoN", "file:PATH", "sim:PATH"
  int width = 640;
  int height = 480;
  double fps = 30.0;
  std::string pixel_format;          // V4L2 FOURCC asked of a camera ("MJPG", "YUYV"); "" = driver's
  std::string encoder = "libx264";   // "libx264", "h264_v4l2m2m" (Pi) or "auto"
  std::string preset = "ultrafast";
  int bitrate_kbps = 2000;
  int gop = 30;
  bool intra_refresh = false;
  std::string host;                  // "" = the server's host
  int port = 5600;
  int mtu = 1200;
  bool retransmission = true;        // answer the server's NACKs with RTX, send RTCP sender reports
  int history_packets = 1024;
  double history_s = 1.0;
  bool adapt = true;                 // rate adaptation from the receiver reports (docs/video.md)
  int adapt_min_kbps = 500;          // floor; below it the frame rate halves, then the size
  int adapt_max_kbps = 0;            // ceiling; 0 = bitrate_kbps
};

/// How one head's pictures are detected (perception: the PTZ head;
/// wide_head: the wide one); becomes client::WatcherSettings.
struct DetectionParams {
  std::string detector = "hog";      // hog | hog-daimler | haar-fullbody | haar-upperbody
  int width = 640;                   // the picture is resized to this before detection
  int height = 480;
  double rate_hz = 5.0;              // detections per second at most
  double max_core_share = 0.5;       // ...and never more than this share of one core
  double hit_threshold = 0.0;        // HOG's SVM margin
  int group_threshold = 2;           // windows that must agree
  bool floor_band = true;            // HOG: only windows whose person stands on the floor (people_detector.hpp)
};

/// People detection on the camera's pictures (docs/human-awareness.md,
/// "Detection on the robot").
struct PerceptionParams : DetectionParams {
  bool enabled = true;               // runs when the video source can show people (not "synthetic"); both heads
  double stale_s = 1.0;              // detections older than this are not reported (sonar only)
  double ahead_deg = 15.0;           // the camera counts as looking ahead within this pan
  bool look_ahead = true;            // turn the camera ahead while people are near and the robot moves
  double look_ahead_within_m = 4.0;  // ...a tracked person this near
  double look_ahead_hold_s = 3.0;    // ...and give the PTZ back this long after nobody is near or it stops
};

/// The wide, fixed head (robot.yaml's wide_camera; docs/human-awareness.md
/// "The wide head"): its own source, captured and detected on the robot,
/// streamed beside the PTZ head's when `stream` is on (docs/video.md "The
/// wide head's stream"). The bench's choice: HOG at 480x360, one window agreeing.
struct WideHeadParams : DetectionParams {
  WideHeadParams() {
    width = 480;
    height = 360;
    group_threshold = 1;
  }
  std::string source;                // "" = no wide head; "v4l2:/dev/videoN", "file:PATH", "sim:PATH"
  double fps = 15.0;                 // captured at most this often (detection takes rate_hz of them)
  std::string pixel_format;          // V4L2 FOURCC asked of a camera; "" = driver's
  bool stream = false;               // also stream it (H.264/RTP to video.host:video.port, its own SSRC)
  int bitrate_kbps = 800;            // ...at this bitrate (the rest of the encoder's settings: video:)
};

/// Mutual TLS on the link (docs/security.md); relative paths are from the working directory.
struct TlsParams {
  bool plaintext = false;            // only from --plaintext, never from a file
  std::string ca = "certs/ca.pem";   // the CA that signed the server's certificate
  std::string cert;                  // "" = certs/<robot_id>.pem
  std::string key;                   // "" = certs/<robot_id>.key
  std::string server_name;           // name the server's certificate must carry; "" = server.host
};

/// Store-and-forward of events and late acks (docs/store-and-forward.md).
struct EventsParams {
  std::string journal;               // append-only journal file; "" = memory only (lost with the process)
  int max_pending = 10000;           // queue bound; when full the oldest non-alarm entry is dropped
  double sync_period_s = 1.0;        // fdatasync at most this often: a power cut loses at most this long
};

struct ClientConfig {
  std::string robot_id = "robot1";
  std::string server_host = "127.0.0.1";
  int server_port = 7600;
  double reconnect_min_s = 0.1;
  double reconnect_max_s = 0.4;
  double handshake_timeout_s = 3.0;
  double server_heartbeat_period_s = 0.1;
  double telemetry_hz = 50.0;
  std::string serial_device = "/dev/serial0";
  int baud = 115200;
  double serial_reopen_period_s = 1.0;
  double mcu_heartbeat_period_s = 0.1;
  /// SCHED_FIFO priority of the control loop (the main thread) once started; 0: normal scheduling.
  int realtime_priority = 10;
  robot::SafetyParams safety;
  VideoParams video;
  PerceptionParams perception;
  WideHeadParams wide_head;
  TlsParams tls;
  EventsParams events;
  std::string map_file;  // world file whose walls people tracking ignores ("" = no map); --map overrides
};

/// Whether a video source can show people: a camera, a file, the simulator's
/// camera; not the synthetic test picture.
bool showsPeople(const std::string& source);
/// Why `source` cannot be the wide head's ("" = it can): the synthetic picture shows nobody.
std::string wideSourceProblem(const std::string& source);

/// True for ids made of [A-Za-z0-9_-], 1 to 64 characters.
bool validRobotId(const std::string& id);

/// Reads and validates a client config. Throws config::ConfigError.
ClientConfig loadClientConfig(const config::ConfigNode& root);
ClientConfig loadClientConfigFile(const std::string& path);

}  // namespace inspect::client
