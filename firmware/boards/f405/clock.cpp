#include "firmware/boards/f405/clock.hpp"

#include "firmware/boards/stm32f4/registers.hpp"

namespace inspect::firmware::f405 {
namespace {

namespace rcc = stm32f4::rcc;

constexpr uint32_t kHseOn = 1u << 16, kHseRdy = 1u << 17, kPllOn = 1u << 24, kPllRdy = 1u << 25;
constexpr uint32_t kPllSrcHse = 1u << 22;
constexpr uint32_t kTimeoutLoops = 500000;  // about 50 ms at the 16 MHz HSI the MCU starts on

bool waitFor(uint32_t mask) {
  for (uint32_t i = 0; i < kTimeoutLoops; ++i) {
    if ((rcc::cr() & mask) != 0) return true;
  }
  return false;
}

}  // namespace

bool startClocks() {
  rcc::cr() |= kHseOn;
  const bool crystal = waitFor(kHseRdy);
  if (!crystal) rcc::cr() &= ~kHseOn;
  // PLL: VCO in = 1 MHz (M = 8 from HSE, 16 from HSI), VCO = 336 MHz, P = 2, Q = 7.
  const uint32_t m = crystal ? 8 : 16;
  rcc::pllcfgr() = m | (336u << 6) | (0u << 16) | (crystal ? kPllSrcHse : 0u) | (7u << 24);
  rcc::cr() |= kPllOn;
  if (!waitFor(kPllRdy)) return false;  // stays on the HSI at 16 MHz
  // 5 wait states at 168 MHz and 3.3 V, prefetch, instruction and data caches (RM0090 3.5.1).
  stm32f4::flash::acr() = 5u | (1u << 8) | (1u << 9) | (1u << 10);
  // AHB / 1, APB1 / 4, APB2 / 2, then SYSCLK = PLL.
  rcc::cfgr() = (0u << 4) | (0b101u << 10) | (0b100u << 13) | 0b10u;
  while (((rcc::cfgr() >> 2) & 0b11u) != 0b10u) {
  }
  return crystal;
}

}  // namespace inspect::firmware::f405
