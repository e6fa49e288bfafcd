// Cortex-M7 startup shared by every ARM board: vector table, reset handler
// (FPU on before any floating-point code, .data copied, .bss zeroed, static
// constructors run), and fault handlers that leave a snapshot in no-init RAM
// and reset the board.
#include <cstdint>

#include "firmware/board/fault_snapshot.hpp"
#include "hal/cortex_m.hpp"
#include "hal/wire.hpp"

// Symbols defined by linker/sections.ld.
extern "C" {
extern uint32_t __stack_top, __stack_bottom;
extern uint32_t __data_load, __data_start, __data_end;
extern uint32_t __bss_start, __bss_end;
extern uint32_t __fast_bss_start, __fast_bss_end;
extern void (*__init_array_start[])();
extern void (*__init_array_end[])();
int main();
void Reset_Handler();
void NMI_Handler();
void HardFault_Handler();
void Default_Handler();
void faultWithFrame(const uint32_t* frame, uint32_t cause);
}

namespace {

__attribute__((section(".bss.noinit"))) hyq::board::FaultSnapshot g_fault_snapshot;
__attribute__((section(".bss.noinit"))) hyq::board::LinkMemory g_link_memory;

using Handler = void (*)();
constexpr int kCoreVectors = 16;

}  // namespace

hyq::board::FaultSnapshot& hyq::board::faultSnapshot() { return g_fault_snapshot; }
hyq::board::LinkMemory& hyq::board::linkMemory() { return g_link_memory; }

uint32_t hyq::board::stackPeakBytes() {
  const uint32_t* word = &__stack_bottom;
  while (word < &__stack_top && *word == kStackPaint) ++word;
  return static_cast<uint32_t>(reinterpret_cast<uintptr_t>(&__stack_top) - reinterpret_cast<uintptr_t>(word));
}

// Only the core exceptions: the loop is polled, device interrupts merely wake
// WFI while masked, so they never need a vector.
__attribute__((section(".vectors"), used)) const Handler g_vector_table[kCoreVectors] = {
    reinterpret_cast<Handler>(&__stack_top),
    Reset_Handler,
    NMI_Handler,
    HardFault_Handler,
    HardFault_Handler,  // MemManage
    HardFault_Handler,  // BusFault
    HardFault_Handler,  // UsageFault
    nullptr, nullptr, nullptr, nullptr,
    Default_Handler,    // SVCall
    Default_Handler,    // DebugMonitor
    nullptr,
    Default_Handler,    // PendSV
    Default_Handler,    // SysTick (masked by PRIMASK; only wakes WFI)
};

extern "C" __attribute__((naked, noreturn)) void Reset_Handler() {
  // CP10/CP11 full access before the compiler may touch an FP register.
  __asm volatile(
      "ldr r0, =0xE000ED88\n\t"
      "ldr r1, [r0]\n\t"
      "orr r1, r1, #(0xF << 20)\n\t"
      "str r1, [r0]\n\t"
      "dsb\n\t"
      "isb\n\t"
      "cpsid i\n\t"
      "b resetContinue\n\t");
}

extern "C" __attribute__((noreturn, used)) void resetContinue() {
  hyq::hal::cortex_m::reg(0xE000ED08) = reinterpret_cast<uint32_t>(&g_vector_table[0]);  // VTOR
  const uint32_t* src = &__data_load;
  for (uint32_t* dst = &__data_start; dst < &__data_end;) *dst++ = *src++;
  for (uint32_t* dst = &__bss_start; dst < &__bss_end;) *dst++ = 0;
  for (uint32_t* dst = &__fast_bss_start; dst < &__fast_bss_end;) *dst++ = 0;
  // Paint the stack below this frame, so that stackPeakBytes() can find
  // how deep it has ever been used.
  const uint32_t* frame = static_cast<const uint32_t*>(__builtin_frame_address(0));
  for (uint32_t* word = &__stack_bottom; word + 16 < frame;) *word++ = hyq::board::kStackPaint;
  const int constructors = static_cast<int>(__init_array_end - __init_array_start);
  for (int i = 0; i < constructors; ++i) __init_array_start[i]();
  main();
  hyq::hal::cortex_m::systemReset();
}

extern "C" void faultWithFrame(const uint32_t* frame, uint32_t cause) {
  using hyq::hal::cortex_m::reg;
  hyq::board::FaultSnapshot& s = g_fault_snapshot;
  s.cause = cause;
  s.lr = frame[5];
  s.pc = frame[6];
  s.psr = frame[7];
  s.cfsr = reg(hyq::hal::cortex_m::kCfsr);
  s.hfsr = reg(hyq::hal::cortex_m::kHfsr);
  s.bfar = reg(hyq::hal::cortex_m::kBfar);
  s.magic = hyq::board::FaultSnapshot::kValid;
  hyq::hal::cortex_m::systemReset();
}

// The exception frame is on whichever stack was active when the fault hit.
#define HYQ_FAULT_ENTRY(cause)                 \
  __asm volatile(                              \
      "tst lr, #4\n\t"                         \
      "ite eq\n\t"                             \
      "mrseq r0, msp\n\t"                      \
      "mrsne r0, psp\n\t"                      \
      "mov r1, %0\n\t"                         \
      "b faultWithFrame\n\t" ::"i"(cause))

extern "C" __attribute__((naked)) void HardFault_Handler() { HYQ_FAULT_ENTRY(2); }
// The mps2 watchdog barks through NMI one timeout before it resets the board.
extern "C" __attribute__((naked)) void NMI_Handler() { HYQ_FAULT_ENTRY(1); }
extern "C" void Default_Handler() {}

static_assert(hyq::hal::wire::kResetWatchdog == 1 && hyq::hal::wire::kResetFault == 2,
              "HYQ_FAULT_ENTRY causes follow wire::ResetCause");
