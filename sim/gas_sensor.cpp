#include "sim/gas_sensor.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace inspect::sim {

GasSensors::GasSensors(const config::GasConfig& cfg, std::vector<GasSensorFault> faults, uint64_t seed)
    : faults_(std::move(faults)), rng_(seed) {
  for (const auto& c : cfg.channels)
    if (channels_.size() < static_cast<std::size_t>(serial::kGasChannels)) channels_.push_back(c);
  response_.assign(channels_.size(), 0.0);
  stuck_raw_.assign(channels_.size(), -1);
  for (std::size_t i = 0; i < channels_.size(); ++i) response_[i] = channels_[i].background;
}

void GasSensors::settle(std::span<const double> true_values) {
  for (std::size_t i = 0; i < channels_.size() && i < true_values.size(); ++i) response_[i] = true_values[i];
}

GasSensors::Raw GasSensors::sample(double t_s, double dt_s, std::span<const double> true_values) {
  Raw out{};
  for (std::size_t i = 0; i < channels_.size(); ++i) {
    const auto& ch = channels_[i];
    const double target = i < true_values.size() && std::isfinite(true_values[i]) ? true_values[i] : response_[i];
    // Exact solution of tau y' = x - y over dt with x held: y += (x - y)(1 - e^(-dt/tau)).
    const double tau = ch.tau_s();
    const double alpha = dt_s > 0.0 ? -std::expm1(-dt_s / tau) : 0.0;
    response_[i] += (target - response_[i]) * alpha;
    // Drawn for every channel every sample, so that a fault does not shift the others' noise.
    const double value = response_[i] + ch.noise * unit_noise_(rng_);
    const double counts = std::round(value / ch.scale);
    const auto healthy = static_cast<uint16_t>(std::clamp(counts, 0.0, static_cast<double>(config::kGasRawMax)));

    bool stuck = false, dropout = false;
    for (const auto& f : faults_) {
      if (f.channel != i || t_s < f.start_s || t_s >= f.end_s) continue;
      (f.kind == GasFaultKind::Stuck ? stuck : dropout) = true;
    }
    if (!stuck) {
      stuck_raw_[i] = -1;
    } else if (stuck_raw_[i] < 0) {
      // Frozen at what the channel showed when the fault began (the last reading before it, if any).
      stuck_raw_[i] = sampled_ && raw_[i] != config::kGasNoData ? raw_[i] : healthy;
    }
    out[i] = dropout ? config::kGasNoData : stuck ? static_cast<uint16_t>(stuck_raw_[i]) : healthy;
  }
  raw_ = out;
  sampled_ = true;
  return out;
}

double GasSensors::reading(std::size_t i) const {
  if (i >= channels_.size() || raw_[i] == config::kGasNoData) return std::numeric_limits<double>::quiet_NaN();
  return raw_[i] * channels_[i].scale;
}

}  // namespace inspect::sim
