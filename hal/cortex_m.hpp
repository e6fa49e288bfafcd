// Cortex-M7 core registers shared by every ARM board (System Control Space:
// SysTick, SCB, NVIC, FPU feature registers). Board-specific peripherals live
// in hal/<board>/.
#pragma once
#include <cstdint>

namespace hyq::hal::cortex_m {

inline volatile uint32_t& reg(uint32_t address) {
  return *reinterpret_cast<volatile uint32_t*>(address);
}

constexpr uint32_t kSysTickCtrl = 0xE000E010;   // SYST_CSR
constexpr uint32_t kSysTickLoad = 0xE000E014;   // SYST_RVR
constexpr uint32_t kSysTickValue = 0xE000E018;  // SYST_CVR
constexpr uint32_t kSysTickEnable = 1u << 0;
constexpr uint32_t kSysTickInterrupt = 1u << 1;
constexpr uint32_t kSysTickCoreClock = 1u << 2;
constexpr uint32_t kSysTickCountFlag = 1u << 16;

constexpr uint32_t kIcsr = 0xE000ED04;          // SCB->ICSR
constexpr uint32_t kIcsrPendSysTickClear = 1u << 25;
constexpr uint32_t kAircr = 0xE000ED0C;         // SCB->AIRCR
constexpr uint32_t kAircrResetRequest = (0x05FAu << 16) | (1u << 2);
constexpr uint32_t kCpacr = 0xE000ED88;         // SCB->CPACR
constexpr uint32_t kCfsr = 0xE000ED28;
constexpr uint32_t kHfsr = 0xE000ED2C;
constexpr uint32_t kMmfar = 0xE000ED34;
constexpr uint32_t kBfar = 0xE000ED38;
constexpr uint32_t kMvfr0 = 0xE000EF40;         // FPU media and FP feature register 0
constexpr uint32_t kNvicIser0 = 0xE000E100;
constexpr uint32_t kNvicIcpr0 = 0xE000E280;

constexpr uint32_t kDemcr = 0xE000EDFC;
constexpr uint32_t kDemcrTraceEnable = 1u << 24;
constexpr uint32_t kDwtCtrl = 0xE0001000;
constexpr uint32_t kDwtCycleCount = 0xE0001004;
constexpr uint32_t kDwtLock = 0xE0001FB0;

// SysTick from the core clock: one wrap (COUNTFLAG) per millisecond. Its
// interrupt only wakes the core from WFI (PRIMASK stays set, no handler runs).
inline void startSysTick1kHz(uint32_t core_clock_hz) {
  reg(kSysTickCtrl) = 0;
  reg(kSysTickLoad) = core_clock_hz / 1000u - 1u;
  reg(kSysTickValue) = 0;
  reg(kSysTickCtrl) = kSysTickEnable | kSysTickInterrupt | kSysTickCoreClock;
}

// COUNTFLAG clears on read, so each wrap is reported once.
inline bool sysTickWrapped() { return (reg(kSysTickCtrl) & kSysTickCountFlag) != 0; }

// MVFR0 bits [11:8]: 2 = double precision supported.
inline bool fpuHasDoublePrecision() { return ((reg(kMvfr0) >> 8) & 0xFu) == 2u; }

inline void disableInterrupts() { __asm volatile("cpsid i" ::: "memory"); }
inline void waitForInterrupt() { __asm volatile("dsb\n\twfi" ::: "memory"); }
inline void dataSyncBarrier() { __asm volatile("dsb\n\tisb" ::: "memory"); }

// A device interrupt that only wakes WFI: enabled in the NVIC, never taken
// (PRIMASK stays set, so no handler and no vector are needed).
inline void enableWakeSource(uint32_t irq) { reg(kNvicIser0 + 4 * (irq / 32)) = 1u << (irq % 32); }

// Clears what woke WFI: the SysTick and the device interrupt stay pending
// otherwise, and the next WFI would return at once.
inline void clearWakeSources(uint32_t irq) {
  reg(kIcsr) = kIcsrPendSysTickClear;
  reg(kNvicIcpr0 + 4 * (irq / 32)) = 1u << (irq % 32);
}

// Polls a register until (value & mask) == expected, at most `attempts`
// reads; false if it never did (every loop of the image is bounded).
inline bool waitForBits(uint32_t address, uint32_t mask, uint32_t expected, uint32_t attempts) {
  for (uint32_t i = 0; i < attempts; ++i)
    if ((reg(address) & mask) == expected) return true;
  return false;
}

[[noreturn]] inline void systemReset() {
  dataSyncBarrier();
  reg(kAircr) = kAircrResetRequest;
  dataSyncBarrier();
  for (;;) {
  }
}

}  // namespace hyq::hal::cortex_m
