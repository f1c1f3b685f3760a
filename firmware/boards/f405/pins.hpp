#pragma once
// The real board's pin map (STM32F405VG/F407VG, LQFP100; docs/firmware.md
// has the wiring). Port 0 = A, 1 = B, 2 = C, 3 = D, 4 = E.
#include <cstdint>

namespace inspect::firmware::f405 {

struct Pin {
  int port;
  int pin;
};
inline constexpr int kA = 0, kB = 1, kC = 2, kD = 3, kE = 4;

// The Pi's serial line: USART1, AF7, 3.3 V TTL, 115200 8N1.
inline constexpr Pin kPiTx{kA, 9}, kPiRx{kA, 10};
// Hub-motor encoders, quadrature: TIM3 (left) and TIM4 (right), AF2.
inline constexpr Pin kEncLeftA{kA, 6}, kEncLeftB{kA, 7}, kEncRightA{kD, 12}, kEncRightB{kD, 13};
// Motor drivers: PWM on TIM8 CH1 (left) and CH2 (right), AF3, 20 kHz; direction
// (high = forward), brake (high = both shorted) and the drivers' fault line
// (open drain, low = fault; pulled up).
inline constexpr Pin kPwmLeft{kC, 6}, kPwmRight{kC, 7};
inline constexpr Pin kDirLeft{kE, 0}, kDirRight{kE, 1}, kBrake{kE, 2}, kDriverFault{kE, 3};
// The e-stop button: a normally closed contact to ground, pulled up (pressed or
// a cut wire both read high = pressed).
inline constexpr Pin kEStop{kE, 4};
// Camera mount servos: TIM5 CH1 (pan) and CH2 (tilt), AF2, 50 Hz.
inline constexpr Pin kServoPan{kA, 0}, kServoTilt{kA, 1};
// Ultrasonic sensors (HC-SR04 type, in serial::UltrasonicIndex order): the
// triggers, and the echoes on TIM1 CH1-CH4 (AF1), captured on both edges
// (through 5 V -> 3.3 V dividers).
inline constexpr Pin kTrigger[4] = {{kD, 0}, {kD, 1}, {kD, 2}, {kD, 3}};
inline constexpr Pin kEcho[4] = {{kE, 9}, {kE, 11}, {kE, 13}, {kE, 14}};
// The grayscale line sensor's 8 digital outputs, bit i on PD(4 + i).
inline constexpr Pin kLineFirst{kD, 4};
// ADC1: gas channels 0-3 on IN10-IN13 (PC0-PC3, across their 150 ohm shunts),
// the battery's divider on IN14 (PC4).
inline constexpr uint32_t kAdcGas[4] = {10, 11, 12, 13};
inline constexpr uint32_t kAdcBattery = 14;
inline constexpr Pin kAdcPins[5] = {{kC, 0}, {kC, 1}, {kC, 2}, {kC, 3}, {kC, 4}};

}  // namespace inspect::firmware::f405
