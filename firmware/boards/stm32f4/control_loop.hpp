#pragma once
// The boards' one main loop: the core ticked every 1 ms by a 1 MHz count of
// TIM2 (32 bits), not by counting interrupts: SysTick (and the UART's receive
// interrupt) only wake the core from WFI, so that a lost or late interrupt
// (QEMU loses SysTick interrupts when its host is busy) delays a tick but never
// drops one from the clock. A board supplies its peripherals (read before each
// tick, driven after it) and the link to the Pi.
#include <array>
#include <cstdint>

#include "firmware/boards/stm32f4/registers.hpp"
#include "firmware/boards/stm32f4/uart.hpp"
#include "firmware/core/firmware_core.hpp"

namespace inspect::firmware::stm32f4 {

/// A board's peripherals as the loop sees them.
class Peripherals {
 public:
  /// Between ticks: anything the board polls (the HIL link's bytes).
  virtual void poll() {}
  /// Before the tick of `now_ms`: what the peripherals read.
  virtual PeripheralInputs read(uint32_t now_ms) = 0;
  /// After it: drive the outputs; `late_us` is how late the tick started.
  virtual void drive(const PeripheralOutputs& out, uint32_t now_ms, uint32_t late_us) = 0;

 protected:
  // Not virtual: a board's peripherals live for ever (a static), and a trivial
  // destructor registers no exit handler (none exists on bare metal).
  ~Peripherals() = default;
};

/// TIM2 as a free-running 1 MHz counter, from its input clock in Hz.
inline void startMicrosecondClock(uint32_t timer_clock_hz) {
  tim::psc(tim::kTim2) = timer_clock_hz / 1000000u - 1u;
  tim::arr(tim::kTim2) = 0xFFFFFFFFu;
  tim::egr(tim::kTim2) = tim::kEgrUg;  // load the prescaler now, count from 0
  tim::cr1(tim::kTim2) = tim::kCr1Cen;
}
inline uint32_t micros() { return tim::cnt(tim::kTim2); }

/// SysTick interrupting 4 times a period (every 250 us) of a `core_clock_hz`
/// core: the loop's wake-up. A wake-up that comes late or not at all (QEMU on a
/// busy host) then delays a tick by 0.25 ms, not by a whole period: at one a
/// millisecond the ticks' lateness had p99 1.15 ms over 10 minutes in QEMU.
inline constexpr uint32_t kWakeupsPerSecond = 4000;
inline void startWakeups(uint32_t core_clock_hz) {
  core::systickLoad() = core_clock_hz / kWakeupsPerSecond - 1u;
  core::systickVal() = 0;
  core::systickCtrl() = 0x7;  // processor clock, interrupt, enable
}

/// Runs the core for ever. A stall longer than kMaxCatchUpUs (a debugger, a
/// host that stopped QEMU) restarts the schedule instead of replaying it.
[[noreturn]] inline void runControlLoop(FirmwareCore& core, Uart& link, Peripherals& board) {
  constexpr uint32_t kPeriodUs = 1000;
  constexpr uint32_t kMaxCatchUpUs = 100000;
  std::array<uint8_t, 64> buf{};
  uint32_t now_ms = 0;
  uint32_t next_us = micros();
  for (;;) {
    core::waitForInterrupt();
    for (std::size_t n; (n = link.read(buf)) > 0;) core.receive({buf.data(), n}, now_ms);
    board.poll();
    for (;;) {
      const uint32_t late_us = micros() - next_us;
      if (late_us >= 0x80000000u) break;  // the next tick is not due yet
      if (late_us > kMaxCatchUpUs) next_us += late_us;
      ++now_ms;
      next_us += kPeriodUs;
      const PeripheralOutputs out = core.tick(now_ms, board.read(now_ms));
      board.drive(out, now_ms, late_us > kMaxCatchUpUs ? 0 : late_us);
      for (std::size_t n; (n = core.takeTx(buf)) > 0;) link.write({buf.data(), n});
    }
  }
}

}  // namespace inspect::firmware::stm32f4
