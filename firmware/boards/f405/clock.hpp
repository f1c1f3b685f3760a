#pragma once
// The STM32F405/F407's clock tree from an 8 MHz crystal (RM0090 6.3):
// HSE 8 MHz / M 8 x N 336 / P 2 = 168 MHz SYSCLK (Q 7: 48 MHz USB clock),
// AHB 168 MHz, APB1 42 MHz (its timers 84 MHz), APB2 84 MHz (its timers
// 168 MHz), flash at 5 wait states with prefetch and caches. Without a crystal
// (HSE not ready within its timeout) the same 168 MHz from the 16 MHz HSI.
#include <cstdint>

namespace inspect::firmware::f405 {

inline constexpr uint32_t kSysClockHz = 168000000;
inline constexpr uint32_t kApb1TimerClockHz = 84000000;   // TIM2-5, TIM12-14
inline constexpr uint32_t kApb2TimerClockHz = 168000000;  // TIM1, TIM8-11
inline constexpr uint32_t kApb2ClockHz = 84000000;        // USART1, USART6, ADC

/// Switches SYSCLK to the PLL; true when it runs from the crystal.
bool startClocks();

}  // namespace inspect::firmware::f405
