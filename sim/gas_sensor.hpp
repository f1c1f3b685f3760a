#pragma once
// The robot's gas sensors as the MCU reads them: per channel a first-order
// response to the true value at the inlet (tau = t90 / ln 10), Gaussian noise,
// quantisation to raw counts, and scripted faults (stuck, dropout) from the
// world file (docs/simulator.md "Gas").
#include <array>
#include <cstdint>
#include <random>
#include <span>
#include <vector>

#include "shared/config/gas_config.hpp"
#include "shared/serial/messages.hpp"
#include "sim/world_names.hpp"

namespace inspect::sim {

/// A scripted fault resolved to its channel's slot.
struct GasSensorFault {
  std::size_t channel = 0;
  GasFaultKind kind = GasFaultKind::Stuck;
  double start_s = 0.0;
  double end_s = 0.0;
};

/// Raw gas slots of the sensor frame from true concentrations.
class GasSensors {
 public:
  using Raw = std::array<uint16_t, serial::kGasChannels>;

  /// Channels beyond serial::kGasChannels are ignored (the config loader allows at most 4).
  GasSensors(const config::GasConfig& cfg, std::vector<GasSensorFault> faults, uint64_t seed);

  /// Puts every sensor at rest at the given true values (no start-up transient).
  void settle(std::span<const double> true_values);
  /// One reading at sim time t_s, dt_s after the previous one: the response
  /// moves toward true_values exactly as the first-order lag would over dt_s,
  /// then noise, quantisation (round(value / scale), clamped to [0, kGasRawMax])
  /// and faults apply. Slots beyond the configured channels are 0.
  Raw sample(double t_s, double dt_s, std::span<const double> true_values);

  std::size_t channels() const { return channels_.size(); }
  /// Noise-free sensor response of channel i (unit), before quantisation and faults.
  double response(std::size_t i) const { return response_[i]; }
  /// Last reading of channel i as the host decodes it (raw x scale); NaN for no data.
  double reading(std::size_t i) const;
  /// The scripted faults.
  const std::vector<GasSensorFault>& faults() const { return faults_; }
  /// Raw slots of the last sample.
  const Raw& raw() const { return raw_; }

 private:
  std::vector<config::GasChannel> channels_;
  std::vector<GasSensorFault> faults_;
  std::vector<double> response_;
  std::vector<int> stuck_raw_;  // per channel: raw frozen by an active stuck fault, or -1
  Raw raw_{};
  bool sampled_ = false;
  std::mt19937_64 rng_;
  std::normal_distribution<double> unit_noise_{0.0, 1.0};
};

}  // namespace inspect::sim
