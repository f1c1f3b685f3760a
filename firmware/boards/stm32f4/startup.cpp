// Reset and the vector table of the STM32F405/F407 (both boards): the FPU
// on, .data copied from flash, .bss zeroed, the static constructors run,
// then main(). The linker script is stm32f405.ld.
#include <cstdint>

extern "C" {
extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack;
extern void (*__init_array_start[])();
extern void (*__init_array_end[])();
int main();

// An interrupt nobody handles: stop here (the independent watchdog, where it runs, resets).
void Default_Handler() noexcept {
  for (;;) {
  }
}
void NMI_Handler() noexcept __attribute__((weak, alias("Default_Handler")));
void HardFault_Handler() noexcept __attribute__((weak, alias("Default_Handler")));
void MemManage_Handler() noexcept __attribute__((weak, alias("Default_Handler")));
void BusFault_Handler() noexcept __attribute__((weak, alias("Default_Handler")));
void UsageFault_Handler() noexcept __attribute__((weak, alias("Default_Handler")));
void SVC_Handler() noexcept __attribute__((weak, alias("Default_Handler")));
void PendSV_Handler() noexcept __attribute__((weak, alias("Default_Handler")));
void SysTick_Handler() noexcept __attribute__((weak, alias("Default_Handler")));
void TIM1_CC_IRQHandler() noexcept __attribute__((weak, alias("Default_Handler")));
void USART1_IRQHandler() noexcept __attribute__((weak, alias("Default_Handler")));
void USART2_IRQHandler() noexcept __attribute__((weak, alias("Default_Handler")));
void USART3_IRQHandler() noexcept __attribute__((weak, alias("Default_Handler")));

[[noreturn]] void Reset_Handler() {
  // CP10 and CP11 (the FPU) full access before any floating-point instruction (PM0214 4.6.6).
  *reinterpret_cast<volatile uint32_t*>(0xE000ED88) |= 0xFu << 20;
  __asm volatile("dsb\n isb" ::: "memory");
  const uint32_t* src = &_sidata;
  for (uint32_t* dst = &_sdata; dst < &_edata;) *dst++ = *src++;
  for (uint32_t* dst = &_sbss; dst < &_ebss;) *dst++ = 0;
  for (auto fn = __init_array_start; fn < __init_array_end; ++fn) (*fn)();
  main();
  for (;;) {
  }
}
}

namespace {

using Handler = void (*)();
constexpr int kIrqCount = 82;  // STM32F405/F407: IRQ 0-81 (RM0090 table 61)

struct VectorTable {
  uint32_t* initial_sp;
  Handler core[15];
  Handler irq[kIrqCount];
};

constexpr VectorTable makeTable() {
  VectorTable t{&_estack, {}, {}};
  t.core[0] = Reset_Handler;
  t.core[1] = NMI_Handler;
  t.core[2] = HardFault_Handler;
  t.core[3] = MemManage_Handler;
  t.core[4] = BusFault_Handler;
  t.core[5] = UsageFault_Handler;
  t.core[10] = SVC_Handler;
  t.core[13] = PendSV_Handler;
  t.core[14] = SysTick_Handler;
  for (auto& h : t.irq) h = Default_Handler;
  t.irq[27] = TIM1_CC_IRQHandler;
  t.irq[37] = USART1_IRQHandler;
  t.irq[38] = USART2_IRQHandler;
  t.irq[39] = USART3_IRQHandler;
  return t;
}

}  // namespace

__attribute__((section(".isr_vector"), used)) const VectorTable g_vectors = makeTable();
