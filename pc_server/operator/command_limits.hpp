#pragma once
// What an operator may ask of a robot, whatever the front end: the one home
// of the limits the operator service and route files check.

namespace inspect::server {

/// Fastest cruise speed of a go-to, a track or a route, m/s.
inline constexpr double kMaxCommandSpeed_m_s = 1.0;
/// A cruise speed an operator may ask for: (0, kMaxCommandSpeed_m_s] (NaN is not).
inline bool commandSpeedOk(double v_m_s) { return v_m_s > 0.0 && v_m_s <= kMaxCommandSpeed_m_s; }

/// The camera stream's settings an operator may ask for (the service checks
/// them; the console's help and argument errors say them).
inline constexpr int kVideoMinSide = 64, kVideoMaxSide = 4096;
inline constexpr double kVideoMinFps = 1.0, kVideoMaxFps = 120.0;
inline constexpr int kVideoMinBitrate_kbps = 50, kVideoMaxBitrate_kbps = 50000;
inline constexpr const char* kVideoSizeWant = "<W>x<H>, even, 64 to 4096 (e.g. 1280x720)";
inline constexpr const char* kVideoFpsWant = "1 to 120";
inline constexpr const char* kVideoBitrateWant = "50 to 50000 kbit/s";

}  // namespace inspect::server
