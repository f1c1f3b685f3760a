// TuneReference and the default search ranges of pc_server/tuning/tuner.hpp.
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "pc_server/tuning/tuner.hpp"

namespace inspect::tuning {

std::string TuneReference::describe() const {
  std::ostringstream os;
  switch (kind) {
    case Kind::kCircle: os << "circle r=" << radius_m << " m v=" << speed_m_s << " m/s laps=" << laps; break;
    case Kind::kLine: os << "line " << length_m << " m v=" << speed_m_s << " m/s"; break;
    case Kind::kWaypoints:
      os << "waypoints " << length_m << " x " << length_m / 2.0 << " m rectangle v=" << speed_m_s << " m/s";
      break;
  }
  return os.str();
}

std::unique_ptr<control::ReferencePath> TuneReference::makePath() const {
  const control::Pose2 start{0.0, 0.0, 0.0};
  switch (kind) {
    case Kind::kCircle: return control::makeCircle(start, radius_m, speed_m_s, laps);
    case Kind::kLine: return control::makeLine(start, length_m, speed_m_s);
    case Kind::kWaypoints: return control::makeRectangleWaypoints(length_m, speed_m_s);
  }
  throw std::invalid_argument("unknown reference kind");
}

std::pair<double, double> defaultTuneBounds(const std::string& name) {
  // Ranges a robot engineer would search around the paper's values
  // (kp' 9, ki' 2, kd' 3, ke 0.9, kec 0.1, k1 3, k2 1, k3 1, a1 -1, a2 -1.2, a3 -0.5).
  if (name == "kp") return {0.5, 30.0};
  if (name == "ki") return {0.0, 50.0};
  if (name == "kd") return {0.0, 10.0};
  if (name == "ke") return {0.01, 10.0};
  if (name == "kec") return {0.005, 1.0};
  if (name == "k1") return {0.0, 10.0};
  if (name == "k2") return {0.0, 5.0};
  if (name == "k3") return {0.0, 5.0};
  if (name == "a1") return {-5.0, -0.1};
  if (name == "a2") return {-5.0, -0.1};
  if (name == "a3") return {-3.0, -0.05};
  throw std::invalid_argument("unknown gain '" + name + "'");
}

}  // namespace inspect::tuning
