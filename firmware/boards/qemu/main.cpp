// The QEMU board (docs/firmware.md): the firmware on QEMU's netduinoplus2, an
// STM32F405 whose USARTs and timers QEMU emulates but not its GPIO, encoder
// timers, input capture or ADC inputs. USART1 is the Pi's line (robot_client);
// USART2 is the hardware-in-the-loop link (shared/hil): `mcu_sim --hil` sends
// what those peripherals would read and takes what the firmware drives. Until
// the simulator's first message the world is held still: wheels at rest, no
// echo in range, gas at its transmitters' 4 mA, the battery full.
#include <array>
#include <cstdint>

#include "firmware/boards/stm32f4/control_loop.hpp"
#include "firmware/boards/stm32f4/registers.hpp"
#include "firmware/boards/stm32f4/uart.hpp"
#include "firmware/core/analog_inputs.hpp"
#include "firmware/mcu/firmware_instance.hpp"
#include "shared/hil/encoder_model.hpp"
#include "shared/hil/hil_link.hpp"

namespace fw = inspect::firmware;
namespace f4 = inspect::firmware::stm32f4;
namespace hil = inspect::hil;

namespace {

// QEMU runs the core at 168 MHz from reset (RCC is not emulated) and clocks
// TIM2-5 at 1 GHz (the timer's clock-frequency property); the baud rate is ignored.
constexpr uint32_t kCoreClockHz = 168000000;
constexpr uint32_t kTimerClockHz = 1000000000;
constexpr uint32_t kBrr115200 = 0x2D9;  // 84 MHz APB2 / 115200, for the record

f4::Uart g_link(f4::usart::kUsart1);

int16_t rounded(float v) { return static_cast<int16_t>(v + (v < 0 ? -0.5f : 0.5f)); }
f4::Uart g_hil(f4::usart::kUsart2);

class HilPeripherals final : public f4::Peripherals {
 public:
  explicit HilPeripherals(const fw::McuSettings& s) : encoders_(s.speed_ff, s.response_tau_s, s.encoder_counts_per_rev) {
    // The world held still until the simulator speaks.
    for (std::size_t i = 0; i < inspect::serial::kGasChannels; ++i)
      sensors_.gas_adc[i] = fw::gasAdcCounts(s, s.gas[i], s.gas[i].range_min);
    sensors_.battery_adc = fw::batteryAdcCounts(s, 25200);
    sensors_.echo_flags = hil::HilSensors::kEchoRose;  // still high at the slot's end: nothing in range
  }

  void poll() override {
    std::array<uint8_t, 64> buf{};
    for (std::size_t n; (n = g_hil.read(buf)) > 0;) {
      decoder_.feed({buf.data(), n}, [this](const hil::HilMessage& m, uint8_t seq) {
        out_.input_seq = seq;
        if (const auto* e = std::get_if<hil::HilEncoders>(&m)) {
          encoders_.take(*e);
        } else if (const auto* in = std::get_if<hil::HilSensors>(&m)) {
          sensors_ = *in;
          heard_ = true;
        }
      });
    }
  }

  fw::PeripheralInputs read(uint32_t now_ms) override {
    fw::PeripheralInputs in;
    // The encoder timers as read at this tick's due time (shared/hil: from the
    // latest sample, carried on by the motor model), however late its bytes came.
    const std::array<uint16_t, 2> counters = encoders_.countersAt(now_ms);
    in.encoder = {counters[0], counters[1]};
    // The echo of this slot's ping, if the simulator has answered that ping.
    if (!heard_ || sensors_.echo_count == out_.trigger_count) {
      in.echo.rose = (sensors_.echo_flags & hil::HilSensors::kEchoRose) != 0;
      in.echo.fell = (sensors_.echo_flags & hil::HilSensors::kEchoFell) != 0;
      in.echo.width_us = sensors_.echo_width_us;
    }
    in.gas_adc = sensors_.gas_adc;
    in.battery_adc = sensors_.battery_adc;
    in.grayscale = sensors_.grayscale;
    in.estop_pressed = (sensors_.switches & hil::HilSensors::kEStopPressed) != 0;
    in.motor_driver_fault = (sensors_.switches & hil::HilSensors::kDriverFault) != 0;
    return in;
  }

  void drive(const fw::PeripheralOutputs& o, uint32_t now_ms, uint32_t late_us) override {
    out_.mcu_time_ms = now_ms;
    for (std::size_t i = 0; i < 2; ++i) {
      out_.duty_1e4[i] = static_cast<int16_t>(o.brake ? 0.0f : o.duty[i] * 10000.0f);
      out_.servo_us[i] = o.servo_us[i];
    }
    out_.flags = o.brake ? hil::HilOutputs::kBrake : 0;
    encoders_.drive({o.brake ? 0.0f : o.duty[0], o.brake ? 0.0f : o.duty[1]});
    const std::array<float, 2> sp = fw::firmwareCore().setpoints();  // in force, before the slew
    const std::array<float, 2> ptz = fw::firmwareCore().ptz().targetRad();
    for (std::size_t i = 0; i < 2; ++i) {
      out_.setpoint_mrad_s[i] = rounded(sp[i] * 1000.0f);
      out_.ptz_target_0p1mrad[i] = rounded(ptz[i] * 10000.0f);
    }
    out_.tick_late_us = static_cast<uint16_t>(late_us > 0xFFFF ? 0xFFFF : late_us);
    const bool ping = o.trigger >= 0;
    if (ping) {
      out_.trigger_sensor = static_cast<uint8_t>(o.trigger);
      ++out_.trigger_count;
    }
    if (ping || now_ms % 2 == 0) {  // 500 Hz, and each ping at once
      const auto frame = hil::encodeHil(out_, seq_++);
      g_hil.write(frame.span());
    }
  }

 private:
  hil::HilDecoder decoder_;
  hil::HilEncoderModel encoders_;
  hil::HilSensors sensors_;
  bool heard_ = false;
  hil::HilOutputs out_;
  uint8_t seq_ = 0;
};

}  // namespace

extern "C" void USART1_IRQHandler() { g_link.onInterrupt(); }
extern "C" void USART2_IRQHandler() { g_hil.onInterrupt(); }
extern "C" void SysTick_Handler() {}

int main() {
  fw::FirmwareCore& core = fw::firmwareCore();
  static HilPeripherals board(core.settings());
  f4::startMicrosecondClock(kTimerClockHz);
  g_link.start(kBrr115200, f4::kIrqUsart1);
  g_hil.start(kBrr115200, f4::kIrqUsart2);
  f4::startWakeups(kCoreClockHz);
  f4::runControlLoop(core, g_link, board);
}
