#include "firmware/boards/stm32f4/uart.hpp"

namespace inspect::firmware::stm32f4 {

void Uart::start(uint32_t brr, int irq) {
  usart::brr(base_) = brr;
  usart::cr1(base_) = usart::kCr1Ue | usart::kCr1Te | usart::kCr1Re | usart::kCr1Rxneie;
  core::enableIrq(irq);
}

void Uart::onInterrupt() {
  const uint32_t sr = usart::sr(base_);
  if ((sr & (usart::kSrRxne | usart::kSrOre)) == 0) return;
  const auto byte = static_cast<uint8_t>(usart::dr(base_));  // reading DR clears RXNE and ORE
  const uint32_t head = head_;
  if (head - tail_ >= kRxRing) {
    rx_dropped_ = rx_dropped_ + 1;
    return;
  }
  ring_[head % kRxRing] = byte;
  head_ = head + 1;
}

std::size_t Uart::read(std::span<uint8_t> out) {
  std::size_t n = 0;
  uint32_t tail = tail_;
  const uint32_t head = head_;
  while (tail != head && n < out.size()) out[n++] = ring_[tail++ % kRxRing];
  tail_ = tail;
  return n;
}

void Uart::write(std::span<const uint8_t> bytes) {
  for (uint8_t b : bytes) {
    while ((usart::sr(base_) & usart::kSrTxe) == 0) {
    }
    usart::dr(base_) = b;
  }
}

}  // namespace inspect::firmware::stm32f4
