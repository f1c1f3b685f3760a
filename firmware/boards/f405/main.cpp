// The real board (docs/firmware.md): the firmware on an STM32F405VG/F407VG
// at 168 MHz from an 8 MHz crystal. Every 1 ms the control loop
// (stm32f4/control_loop.hpp) reads the encoder timers, the echo captures, the
// ADC, the line sensor and the switches, ticks the core and drives the motor
// PWM, direction and brake, the triggers and the servos. The independent
// watchdog resets the MCU if the loop stops for 50 ms (its pins then fall back
// to inputs: the drivers' PWM inputs float low and the motors coast to a stop).
#include <array>
#include <cstdint>

#include "firmware/boards/f405/clock.hpp"
#include "firmware/boards/f405/pins.hpp"
#include "firmware/boards/stm32f4/control_loop.hpp"
#include "firmware/boards/stm32f4/registers.hpp"
#include "firmware/boards/stm32f4/uart.hpp"
#include "firmware/mcu/firmware_instance.hpp"

namespace fw = inspect::firmware;
namespace f4 = inspect::firmware::stm32f4;
namespace f405 = inspect::firmware::f405;
using f405::Pin;

namespace {

constexpr uint32_t kPwmTop = f405::kApb2TimerClockHz / 20000u;  // 20 kHz: 8400 steps
constexpr uint32_t kUsartBrr = (f405::kApb2ClockHz + 57600u) / 115200u;  // 115200 baud, 16x oversampling

f4::Uart g_link(f4::usart::kUsart1);

enum Mode : uint32_t { kInput = 0, kOutput = 1, kAlternate = 2, kAnalog = 3 };

void pinMode(Pin p, Mode m, uint32_t af = 0) {
  const auto shift = static_cast<uint32_t>(2 * p.pin);
  f4::gpio::moder(p.port) = (f4::gpio::moder(p.port) & ~(3u << shift)) | (static_cast<uint32_t>(m) << shift);
  if (m == kAlternate) {
    const auto a = static_cast<uint32_t>(4 * (p.pin % 8));
    auto& afr = f4::gpio::afr(p.port, p.pin / 8);
    afr = (afr & ~(0xFu << a)) | (af << a);
  }
}
void pullUp(Pin p) {
  const auto shift = static_cast<uint32_t>(2 * p.pin);
  f4::gpio::pupdr(p.port) = (f4::gpio::pupdr(p.port) & ~(3u << shift)) | (1u << shift);
}
void write(Pin p, bool high) { f4::gpio::bsrr(p.port) = 1u << (p.pin + (high ? 0 : 16)); }
bool readPin(Pin p) { return ((f4::gpio::idr(p.port) >> p.pin) & 1u) != 0; }

// The echo captures: TIM1 at 1 MHz, each channel on both edges; the interrupt
// keeps the rise and the fall of the sensor pinged last.
struct EchoState {
  volatile int sensor = -1;
  volatile bool rose = false;
  volatile bool fell = false;
  volatile uint16_t rise_us = 0;
  volatile uint16_t width_us = 0;
};
EchoState g_echo;

void startEncoder(uint32_t timer) {
  f4::tim::smcr(timer) = 0b011;                    // encoder mode 3: both inputs, both edges (x4)
  f4::tim::ccmr1(timer) = 0x01 | (0x01 << 8) | (0x3 << 4) | (0x3 << 12);  // CC1S = TI1, CC2S = TI2, filter 8 samples
  f4::tim::arr(timer) = 0xFFFF;
  f4::tim::cr1(timer) = f4::tim::kCr1Cen;
}

void startPeripherals() {
  namespace rcc = f4::rcc;
  rcc::ahb1enr() |= 0x1F;                             // GPIOA-E
  rcc::apb1enr() |= (1u << 0) | (1u << 1) | (1u << 2) | (1u << 3);  // TIM2-5
  rcc::apb2enr() |= (1u << 0) | (1u << 1) | (1u << 4) | (1u << 8);  // TIM1, TIM8, USART1, ADC1
  pinMode(f405::kPiTx, kAlternate, 7);
  pinMode(f405::kPiRx, kAlternate, 7);
  pullUp(f405::kPiRx);
  for (Pin p : {f405::kEncLeftA, f405::kEncLeftB, f405::kEncRightA, f405::kEncRightB}) pinMode(p, kAlternate, 2);
  startEncoder(f4::tim::kTim3);
  startEncoder(f4::tim::kTim4);
  // Motors: braked before the PWM starts.
  for (Pin p : {f405::kDirLeft, f405::kDirRight, f405::kBrake}) pinMode(p, kOutput);
  write(f405::kBrake, true);
  pinMode(f405::kPwmLeft, kAlternate, 3);
  pinMode(f405::kPwmRight, kAlternate, 3);
  f4::tim::arr(f4::tim::kTim8) = kPwmTop - 1;
  f4::tim::ccmr1(f4::tim::kTim8) = (0b110u << 4) | (1u << 3) | (0b110u << 12) | (1u << 11);  // PWM mode 1, preload
  f4::tim::ccer(f4::tim::kTim8) = (1u << 0) | (1u << 4);
  f4::tim::bdtr(f4::tim::kTim8) = 1u << 15;  // MOE: an advanced timer's outputs on
  f4::tim::egr(f4::tim::kTim8) = f4::tim::kEgrUg;
  f4::tim::cr1(f4::tim::kTim8) = f4::tim::kCr1Cen | (1u << 7);
  pinMode(f405::kDriverFault, kInput);
  pullUp(f405::kDriverFault);
  pinMode(f405::kEStop, kInput);
  pullUp(f405::kEStop);
  // Servos: TIM5 at 1 MHz, 20 ms period, centred.
  pinMode(f405::kServoPan, kAlternate, 2);
  pinMode(f405::kServoTilt, kAlternate, 2);
  f4::tim::psc(f4::tim::kTim5) = f405::kApb1TimerClockHz / 1000000u - 1u;
  f4::tim::arr(f4::tim::kTim5) = 20000 - 1;
  f4::tim::ccmr1(f4::tim::kTim5) = (0b110u << 4) | (1u << 3) | (0b110u << 12) | (1u << 11);
  f4::tim::ccr(f4::tim::kTim5, 1) = fw::PtzServo::kCentreUs;
  f4::tim::ccr(f4::tim::kTim5, 2) = fw::PtzServo::kCentreUs;
  f4::tim::ccer(f4::tim::kTim5) = (1u << 0) | (1u << 4);
  f4::tim::egr(f4::tim::kTim5) = f4::tim::kEgrUg;
  f4::tim::cr1(f4::tim::kTim5) = f4::tim::kCr1Cen | (1u << 7);
  // Ultrasonic: triggers low; echoes captured by TIM1 CH1-4 at 1 MHz on both edges.
  for (Pin p : f405::kTrigger) {
    pinMode(p, kOutput);
    write(p, false);
  }
  for (Pin p : f405::kEcho) pinMode(p, kAlternate, 1);
  f4::tim::psc(f4::tim::kTim1) = f405::kApb2TimerClockHz / 1000000u - 1u;
  f4::tim::arr(f4::tim::kTim1) = 0xFFFF;
  f4::tim::ccmr1(f4::tim::kTim1) = 0x01 | (0x01 << 8);  // CC1 on TI1, CC2 on TI2
  f4::tim::ccmr2(f4::tim::kTim1) = 0x01 | (0x01 << 8);  // CC3 on TI3, CC4 on TI4
  f4::tim::ccer(f4::tim::kTim1) = 0xBBBB;                // each channel enabled, both edges (CCxP | CCxNP)
  f4::tim::dier(f4::tim::kTim1) = 0x1E;                  // CC1IE-CC4IE
  f4::tim::egr(f4::tim::kTim1) = f4::tim::kEgrUg;
  f4::tim::cr1(f4::tim::kTim1) = f4::tim::kCr1Cen;
  f4::core::enableIrq(f4::kIrqTim1Cc);
  // Line sensor: inputs.
  for (int i = 0; i < 8; ++i) pinMode({f405::kD, f405::kLineFirst.pin + i}, kInput);
  // ADC1: 12 bits, ADC clock 84 / 4 = 21 MHz, 84 cycles a sample (4 us each).
  for (Pin p : f405::kAdcPins) pinMode(p, kAnalog);
  f4::adc::ccr() = 1u << 16;  // ADCPRE = /4
  f4::adc::smpr2() = 0;
  f4::adc::smpr1() = (0b100u << 0) | (0b100u << 3) | (0b100u << 6) | (0b100u << 9) | (0b100u << 12);  // SMPR1: IN10-14, 84 cycles
  f4::adc::cr2() = f4::adc::kCr2Adon;
}

uint16_t adcRead(uint32_t channel) {
  f4::adc::sqr1() = 0;  // one conversion
  f4::adc::sqr3() = channel;
  f4::adc::cr2() = f4::adc::kCr2Adon | f4::adc::kCr2Swstart;
  for (uint32_t i = 0; i < 10000 && (f4::adc::sr() & f4::adc::kSrEoc) == 0; ++i) {
  }
  return static_cast<uint16_t>(f4::adc::dr() & 0xFFF);
}

void startIndependentWatchdog() {
  f4::iwdg::kr() = 0x5555;  // unlock
  f4::iwdg::pr() = 3;       // LSI 32 kHz / 32 = 1 kHz
  f4::iwdg::rlr() = 50;     // 50 ms
  f4::iwdg::kr() = 0xCCCC;  // start
}

class BoardPeripherals final : public f4::Peripherals {
 public:
  fw::PeripheralInputs read(uint32_t) override {
    fw::PeripheralInputs in;
    in.encoder = {static_cast<uint16_t>(f4::tim::cnt(f4::tim::kTim3)), static_cast<uint16_t>(f4::tim::cnt(f4::tim::kTim4))};
    in.echo.rose = g_echo.rose;
    in.echo.fell = g_echo.fell;
    in.echo.width_us = g_echo.width_us;
    for (std::size_t i = 0; i < 4; ++i) in.gas_adc[i] = adcRead(f405::kAdcGas[i]);
    in.battery_adc = adcRead(f405::kAdcBattery);
    in.grayscale = static_cast<uint8_t>(f4::gpio::idr(f405::kD) >> f405::kLineFirst.pin);
    in.estop_pressed = readPin(f405::kEStop);
    in.motor_driver_fault = !readPin(f405::kDriverFault);
    return in;
  }

  void drive(const fw::PeripheralOutputs& o, uint32_t, uint32_t) override {
    f4::iwdg::kr() = 0xAAAA;  // the loop is alive
    write(f405::kBrake, o.brake);
    const Pin dir[2] = {f405::kDirLeft, f405::kDirRight};
    for (int i = 0; i < 2; ++i) {
      const float d = o.brake ? 0.0f : o.duty[static_cast<std::size_t>(i)];
      write(dir[i], d >= 0.0f);
      const float mag = d < 0.0f ? -d : d;
      f4::tim::ccr(f4::tim::kTim8, i + 1) = static_cast<uint32_t>((mag > 1.0f ? 1.0f : mag) * static_cast<float>(kPwmTop));
    }
    f4::tim::ccr(f4::tim::kTim5, 1) = o.servo_us[0];
    f4::tim::ccr(f4::tim::kTim5, 2) = o.servo_us[1];
    if (o.trigger >= 0 && o.trigger < 4) {
      g_echo.rose = false;
      g_echo.fell = false;
      g_echo.sensor = o.trigger;
      const Pin p = f405::kTrigger[o.trigger];
      write(p, true);  // a 10 us trigger pulse
      const uint32_t t0 = f4::micros();
      while (f4::micros() - t0 < 12) {
      }
      write(p, false);
    }
  }
};

}  // namespace

extern "C" void USART1_IRQHandler() { g_link.onInterrupt(); }
extern "C" void SysTick_Handler() {}
extern "C" void TIM1_CC_IRQHandler() {
  const uint32_t sr = f4::tim::sr(f4::tim::kTim1);
  f4::tim::sr(f4::tim::kTim1) = ~(sr & 0x1Eu);  // clear the flags taken here
  const int s = g_echo.sensor;
  if (s < 0 || (sr & (1u << (s + 1))) == 0) return;  // another channel's edge: not the sensor pinged
  const auto t = static_cast<uint16_t>(f4::tim::ccr(f4::tim::kTim1, s + 1));
  if (readPin(f405::kEcho[s])) {
    g_echo.rise_us = t;
    g_echo.rose = true;
  } else if (g_echo.rose) {
    g_echo.width_us = static_cast<uint16_t>(t - g_echo.rise_us);
    g_echo.fell = true;
  }
}

int main() {
  f405::startClocks();
  fw::FirmwareCore& core = fw::firmwareCore();
  static BoardPeripherals board;
  startPeripherals();
  f4::startMicrosecondClock(f405::kApb1TimerClockHz);
  g_link.start(kUsartBrr, f4::kIrqUsart1);
  f4::startWakeups(f405::kSysClockHz);
  startIndependentWatchdog();
  f4::runControlLoop(core, g_link, board);
}
