#pragma once
// Ground-truth CSV log (--truth FILE): T (state per frame), C (accepted wheel
// commands), E (events), P (pedestrians, 10 Hz), G (gas at the inlet, 10 Hz) lines,
// '#' comments. Tests read the file while the simulator runs: a thread of its
// own writes the lines out every 20 ms (BackgroundFile), so the real-time loop
// never waits on the disk. Format: docs/simulator.md.
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "sim/mcu_sim/background_file.hpp"
#include "sim/sim_observer.hpp"

namespace inspect::sim {

/// Writes the truth log; throws std::runtime_error when the file cannot be opened.
class TruthLog : public SimObserver {
 public:
  explicit TruthLog(const std::string& path);
  ~TruthLog() override;
  TruthLog(const TruthLog&) = delete;
  TruthLog& operator=(const TruthLog&) = delete;

  void onSample(const TruthSample& s) override;
  void onCommand(double sim_t_s, uint8_t seq, const serial::WheelCommand& cmd) override;
  void onEvent(double sim_t_s, std::string_view event, std::string_view detail) override;
  void onPedestrian(const PedestrianSample& s) override;
  void onGas(const GasSample& s) override;
  void onFrameSent(double sim_t_s, std::span<const uint8_t> wire, uint32_t mcu_time_ms) override;
  /// Also writes every sensor frame sent to `path` (F rows, docs/failsafes.md); throws like the constructor.
  void openFrameLog(const std::string& path);
  /// Writes "# <text>".
  void comment(std::string_view text);
  /// "truth log: longest write-out N ms, dropped N bytes" (dropped only when the disk stalled for minutes).
  std::string writerSummary() const;

 private:
  void line(const char* text, int n);
  std::unique_ptr<BackgroundFile> file_;
  std::unique_ptr<BackgroundFile> frames_;
};

}  // namespace inspect::sim
