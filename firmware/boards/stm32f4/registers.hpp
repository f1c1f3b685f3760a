#pragma once
// The STM32F405/F407 registers the boards use (RM0090), as addresses: the few
// the firmware needs, written here rather than a vendor header (Debian ships
// no CMSIS device header for the STM32F4; docs/firmware.md).
#include <cstdint>

namespace inspect::firmware::stm32f4 {

inline volatile uint32_t& reg(uint32_t address) { return *reinterpret_cast<volatile uint32_t*>(address); }

// Reset and clock control (RM0090 7.3).
namespace rcc {
inline constexpr uint32_t kBase = 0x40023800;
inline volatile uint32_t& cr() { return reg(kBase + 0x00); }
inline volatile uint32_t& pllcfgr() { return reg(kBase + 0x04); }
inline volatile uint32_t& cfgr() { return reg(kBase + 0x08); }
inline volatile uint32_t& ahb1enr() { return reg(kBase + 0x30); }
inline volatile uint32_t& apb1enr() { return reg(kBase + 0x40); }
inline volatile uint32_t& apb2enr() { return reg(kBase + 0x44); }
inline volatile uint32_t& csr() { return reg(kBase + 0x74); }
}  // namespace rcc

namespace flash {
inline volatile uint32_t& acr() { return reg(0x40023C00); }
}

// General-purpose I/O (RM0090 8.4): port 0 = A, 1 = B ...
namespace gpio {
inline constexpr uint32_t base(int port) { return 0x40020000u + 0x400u * static_cast<uint32_t>(port); }
inline volatile uint32_t& moder(int p) { return reg(base(p) + 0x00); }
inline volatile uint32_t& pupdr(int p) { return reg(base(p) + 0x0C); }
inline volatile uint32_t& idr(int p) { return reg(base(p) + 0x10); }
inline volatile uint32_t& bsrr(int p) { return reg(base(p) + 0x18); }
inline volatile uint32_t& afr(int p, int half) { return reg(base(p) + 0x20 + 4u * static_cast<uint32_t>(half)); }
}  // namespace gpio

// USART (RM0090 30.6).
namespace usart {
inline constexpr uint32_t kUsart1 = 0x40011000;
inline constexpr uint32_t kUsart2 = 0x40004400;
inline constexpr uint32_t kUsart3 = 0x40004800;
inline volatile uint32_t& sr(uint32_t b) { return reg(b + 0x00); }
inline volatile uint32_t& dr(uint32_t b) { return reg(b + 0x04); }
inline volatile uint32_t& brr(uint32_t b) { return reg(b + 0x08); }
inline volatile uint32_t& cr1(uint32_t b) { return reg(b + 0x0C); }
inline constexpr uint32_t kSrRxne = 1u << 5;
inline constexpr uint32_t kSrTxe = 1u << 7;
inline constexpr uint32_t kSrOre = 1u << 3;
inline constexpr uint32_t kCr1Re = 1u << 2;
inline constexpr uint32_t kCr1Te = 1u << 3;
inline constexpr uint32_t kCr1Rxneie = 1u << 5;
inline constexpr uint32_t kCr1Ue = 1u << 13;
}  // namespace usart

// Timers (RM0090 14.4 / 18.4): the registers of TIM1-TIM14 that exist.
namespace tim {
inline constexpr uint32_t kTim1 = 0x40010000;
inline constexpr uint32_t kTim2 = 0x40000000;
inline constexpr uint32_t kTim3 = 0x40000400;
inline constexpr uint32_t kTim4 = 0x40000800;
inline constexpr uint32_t kTim5 = 0x40000C00;
inline constexpr uint32_t kTim8 = 0x40010400;
inline volatile uint32_t& cr1(uint32_t b) { return reg(b + 0x00); }
inline volatile uint32_t& smcr(uint32_t b) { return reg(b + 0x08); }
inline volatile uint32_t& dier(uint32_t b) { return reg(b + 0x0C); }
inline volatile uint32_t& sr(uint32_t b) { return reg(b + 0x10); }
inline volatile uint32_t& egr(uint32_t b) { return reg(b + 0x14); }
inline volatile uint32_t& ccmr1(uint32_t b) { return reg(b + 0x18); }
inline volatile uint32_t& ccmr2(uint32_t b) { return reg(b + 0x1C); }
inline volatile uint32_t& ccer(uint32_t b) { return reg(b + 0x20); }
inline volatile uint32_t& cnt(uint32_t b) { return reg(b + 0x24); }
inline volatile uint32_t& psc(uint32_t b) { return reg(b + 0x28); }
inline volatile uint32_t& arr(uint32_t b) { return reg(b + 0x2C); }
inline volatile uint32_t& ccr(uint32_t b, int ch) { return reg(b + 0x34 + 4u * static_cast<uint32_t>(ch - 1)); }
inline volatile uint32_t& bdtr(uint32_t b) { return reg(b + 0x44); }
inline constexpr uint32_t kCr1Cen = 1u << 0;
inline constexpr uint32_t kEgrUg = 1u << 0;
}  // namespace tim

// ADC1 (RM0090 13.13).
namespace adc {
inline constexpr uint32_t kAdc1 = 0x40012000;
inline volatile uint32_t& sr() { return reg(kAdc1 + 0x00); }
inline volatile uint32_t& cr1() { return reg(kAdc1 + 0x04); }
inline volatile uint32_t& cr2() { return reg(kAdc1 + 0x08); }
inline volatile uint32_t& smpr1() { return reg(kAdc1 + 0x0C); }
inline volatile uint32_t& smpr2() { return reg(kAdc1 + 0x10); }
inline volatile uint32_t& sqr1() { return reg(kAdc1 + 0x2C); }
inline volatile uint32_t& sqr3() { return reg(kAdc1 + 0x34); }
inline volatile uint32_t& dr() { return reg(kAdc1 + 0x4C); }
inline volatile uint32_t& ccr() { return reg(0x40012304); }
inline constexpr uint32_t kSrEoc = 1u << 1;
inline constexpr uint32_t kCr2Adon = 1u << 0;
inline constexpr uint32_t kCr2Swstart = 1u << 30;
}  // namespace adc

// The independent watchdog (RM0090 21.4).
namespace iwdg {
inline volatile uint32_t& kr() { return reg(0x40003000); }
inline volatile uint32_t& pr() { return reg(0x40003004); }
inline volatile uint32_t& rlr() { return reg(0x40003008); }
}  // namespace iwdg

// Cortex-M4 core peripherals (PM0214).
namespace core {
inline volatile uint32_t& systickCtrl() { return reg(0xE000E010); }
inline volatile uint32_t& systickLoad() { return reg(0xE000E014); }
inline volatile uint32_t& systickVal() { return reg(0xE000E018); }
inline volatile uint32_t& nvicIser(int n) { return reg(0xE000E100 + 4u * static_cast<uint32_t>(n)); }
inline void enableIrq(int irq) { nvicIser(irq / 32) = 1u << (irq % 32); }
inline void waitForInterrupt() { __asm volatile("wfi"); }
inline void disableIrqs() { __asm volatile("cpsid i" ::: "memory"); }
inline void enableIrqs() { __asm volatile("cpsie i" ::: "memory"); }
}  // namespace core

// Interrupt numbers (RM0090 table 61).
inline constexpr int kIrqTim1Cc = 27;
inline constexpr int kIrqUsart1 = 37;
inline constexpr int kIrqUsart2 = 38;
inline constexpr int kIrqUsart3 = 39;

}  // namespace inspect::firmware::stm32f4
