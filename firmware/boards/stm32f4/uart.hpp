#pragma once
// A USART of the STM32F4 for the firmware's links: receiving by interrupt into
// a ring (the ISR calls onInterrupt()), sending by polling TXE (QEMU 7.2 never
// raises the transmit-empty interrupt, and at 115200 baud a 46-byte sensor
// frame takes 4 ms of a 10 ms period: the board sends between its ticks).
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "firmware/boards/stm32f4/registers.hpp"

namespace inspect::firmware::stm32f4 {

class Uart {
 public:
  static constexpr std::size_t kRxRing = 512;  // a power of two

  explicit Uart(uint32_t base) : base_(base) {}
  /// Enables the USART (8N1 at `brr`'s rate) and its receive interrupt `irq`.
  void start(uint32_t brr, int irq);
  /// From the USART's interrupt: moves the received byte into the ring (a byte
  /// that does not fit is counted, not kept).
  void onInterrupt();
  /// Moves what was received to `out`; how many bytes.
  std::size_t read(std::span<uint8_t> out);
  /// Sends `bytes`, waiting on TXE for each.
  void write(std::span<const uint8_t> bytes);
  uint32_t rxDropped() const { return rx_dropped_; }

 private:
  uint32_t base_;
  std::array<uint8_t, kRxRing> ring_{};
  volatile uint32_t head_ = 0;  // written by the interrupt
  volatile uint32_t tail_ = 0;  // written by the main loop
  volatile uint32_t rx_dropped_ = 0;
};

}  // namespace inspect::firmware::stm32f4
