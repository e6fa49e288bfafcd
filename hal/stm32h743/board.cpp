// STM32H743 (Cortex-M7 at 480 MHz, double-precision FPU), registers only,
// no vendor HAL. Builds and fits; not yet run on hardware.
//   clocks   HSI 64 MHz -> PLL1 (M 4, N 60, P 2) = 480 MHz core, VOS0,
//            AHB 240 MHz, APB1/2/3/4 120 MHz, flash 4 wait states
//   USART1   PA9/PA10 (AF7): the link, 6 Mbit/s
//   USART3   PD8/PD9 (AF7): the log channel (ST-LINK virtual COM port on a
//            NUCLEO-H743ZI), 115200 bit/s
//   DWT      cycle counter: the monotonic clock (480 MHz)
//   IWDG1    independent watchdog on the 32 kHz LSI
// A full frame pair at 1 kHz is 1.5 MB/s: USART1 carries the protocol for
// bring-up at a reduced rate; at full rate the link belongs on the H743's
// Ethernet MAC, as on the mps2-an500 (docs/firmware.md).
#include "hal/board.hpp"
#include "hal/cortex_m.hpp"
#include "hal/wire.hpp"

namespace hyq::hal {
namespace {

using cortex_m::reg;
using cortex_m::waitForBits;

constexpr uint32_t kCoreClockHz = 480000000;
constexpr uint32_t kApbClockHz = 120000000;
constexpr uint32_t kLinkBaud = 6000000;
constexpr uint32_t kLogBaud = 115200;
constexpr uint32_t kPollAttempts = 1000000;

constexpr uint32_t kRcc = 0x58024400;
constexpr uint32_t kRccCr = kRcc + 0x00;
constexpr uint32_t kRccCfgr = kRcc + 0x10;
constexpr uint32_t kRccD1Cfgr = kRcc + 0x18;
constexpr uint32_t kRccD2Cfgr = kRcc + 0x1C;
constexpr uint32_t kRccD3Cfgr = kRcc + 0x20;
constexpr uint32_t kRccPllCkSelr = kRcc + 0x28;
constexpr uint32_t kRccPllCfgr = kRcc + 0x2C;
constexpr uint32_t kRccPll1Divr = kRcc + 0x30;
constexpr uint32_t kRccRsr = kRcc + 0xD0;
constexpr uint32_t kRccAhb4Enr = kRcc + 0xE0;
constexpr uint32_t kRccApb1LEnr = kRcc + 0xE8;
constexpr uint32_t kRccApb2Enr = kRcc + 0xF0;
constexpr uint32_t kRccApb4Enr = kRcc + 0xF4;

constexpr uint32_t kPwrCr3 = 0x58024800 + 0x0C;
constexpr uint32_t kPwrCsr1 = 0x58024800 + 0x04;
constexpr uint32_t kPwrD3Cr = 0x58024800 + 0x18;
constexpr uint32_t kSyscfgPwrCr = 0x58000400 + 0x2C;
constexpr uint32_t kFlashAcr = 0x52002000;

constexpr uint32_t kGpioA = 0x58020000;
constexpr uint32_t kGpioD = 0x58020C00;
constexpr uint32_t kUsart1 = 0x40011000;
constexpr uint32_t kUsart3 = 0x40004800;
constexpr uint32_t kUsart1Irq = 37;
constexpr uint32_t kUsartCr1 = 0x00;
constexpr uint32_t kUsartBrr = 0x0C;
constexpr uint32_t kUsartIsr = 0x1C;
constexpr uint32_t kUsartRdr = 0x24;
constexpr uint32_t kUsartTdr = 0x28;
constexpr uint32_t kUsartEnable = 1u << 0;
constexpr uint32_t kUsartRxEnable = 1u << 2;
constexpr uint32_t kUsartTxEnable = 1u << 3;
constexpr uint32_t kUsartRxInterrupt = 1u << 5;
constexpr uint32_t kUsartFifoEnable = 1u << 29;
constexpr uint32_t kUsartRxNotEmpty = 1u << 5;
constexpr uint32_t kUsartTxNotFull = 1u << 7;

constexpr uint32_t kIwdg = 0x58004800;
constexpr uint32_t kIwdgKey = kIwdg + 0x00;
constexpr uint32_t kIwdgPrescaler = kIwdg + 0x04;
constexpr uint32_t kIwdgReload = kIwdg + 0x08;
constexpr uint32_t kIwdgStatus = kIwdg + 0x0C;
constexpr uint32_t kIwdgCountsPerMs = 8;  // LSI 32 kHz / prescaler 4
constexpr uint32_t kRsrWatchdogReset = 1u << 26;  // IWDG1RSTF
constexpr uint32_t kRsrClearFlags = 1u << 16;     // RMVF

// HSI (64 MHz) / 4 = 16 MHz into PLL1; x60 = 960 MHz VCO; /2 = 480 MHz.
void startClocks() {
  reg(kPwrCr3) = (reg(kPwrCr3) & ~1u) | (1u << 1);  // LDO supply, no bypass
  waitForBits(kPwrCsr1, 1u << 13, 1u << 13, kPollAttempts);  // ACTVOSRDY
  reg(kPwrD3Cr) = (reg(kPwrD3Cr) & ~(3u << 14)) | (3u << 14);  // VOS1
  waitForBits(kPwrD3Cr, 1u << 13, 1u << 13, kPollAttempts);
  reg(kRccApb4Enr) |= 1u << 1;  // SYSCFG clock, for the overdrive bit
  reg(kSyscfgPwrCr) |= 1u;      // ODEN: VOS0, needed above 400 MHz
  waitForBits(kPwrD3Cr, 1u << 13, 1u << 13, kPollAttempts);

  reg(kFlashAcr) = 4u | (2u << 4);  // 4 wait states, WRHIGHFREQ 2 (AXI 240 MHz)
  waitForBits(kFlashAcr, 0xFu, 4u, kPollAttempts);

  reg(kRccPllCkSelr) = (4u << 4) | 0u;  // DIVM1 4, source HSI
  reg(kRccPllCfgr) = (3u << 2) | (1u << 16) | (1u << 17) | (1u << 18);  // 8-16 MHz input, P/Q/R on
  reg(kRccPll1Divr) = (59u << 0) | (1u << 9) | (1u << 16) | (1u << 24);  // N 60, P 2, Q 2, R 2
  reg(kRccCr) |= 1u << 24;  // PLL1ON
  waitForBits(kRccCr, 1u << 25, 1u << 25, kPollAttempts);

  reg(kRccD1Cfgr) = (8u << 0) | (4u << 4);  // AHB /2, APB3 /2
  reg(kRccD2Cfgr) = (4u << 4) | (4u << 8);  // APB1 /2, APB2 /2
  reg(kRccD3Cfgr) = (4u << 4);              // APB4 /2
  reg(kRccCfgr) = (reg(kRccCfgr) & ~7u) | 3u;  // system clock from PLL1
  waitForBits(kRccCfgr, 7u << 3, 3u << 3, kPollAttempts);
}

// Instruction cache on (no DMA shares memory with the CPU, so no cache
// maintenance is needed; data lives in DTCM, which is not cached).
void enableInstructionCache() {
  cortex_m::dataSyncBarrier();
  reg(0xE000EF50) = 0;  // ICIALLU
  cortex_m::dataSyncBarrier();
  reg(0xE000ED14) |= 1u << 17;  // CCR.IC
  cortex_m::dataSyncBarrier();
}

void pinToAlternateFunction7(uint32_t gpio, uint32_t pin) {
  reg(gpio + 0x00) = (reg(gpio + 0x00) & ~(3u << (2 * pin))) | (2u << (2 * pin));  // MODER: AF
  const uint32_t afr = gpio + (pin < 8 ? 0x20 : 0x24);
  const uint32_t shift = 4 * (pin % 8);
  reg(afr) = (reg(afr) & ~(0xFu << shift)) | (7u << shift);
}

void usartStart(uint32_t usart, uint32_t baud, uint32_t extra_control) {
  reg(usart + kUsartCr1) = 0;
  reg(usart + kUsartBrr) = kApbClockHz / baud;
  reg(usart + kUsartCr1) = kUsartFifoEnable | kUsartTxEnable | kUsartRxEnable | extra_control | kUsartEnable;
}

void usartWriteByte(uint32_t usart, uint8_t byte) {
  waitForBits(usart + kUsartIsr, kUsartTxNotFull, kUsartTxNotFull, kPollAttempts);
  reg(usart + kUsartTdr) = byte;
}

}  // namespace

void Board::init() {
  const uint32_t rsr = reg(kRccRsr);
  reset_cause_ = (rsr & kRsrWatchdogReset) ? wire::kResetWatchdog : wire::kResetPowerOn;
  reg(kRccRsr) = kRsrClearFlags;

  startClocks();
  enableInstructionCache();

  reg(kRccAhb4Enr) |= (1u << 0) | (1u << 3);  // GPIOA, GPIOD
  reg(kRccApb2Enr) |= 1u << 4;                // USART1
  reg(kRccApb1LEnr) |= 1u << 18;              // USART3
  pinToAlternateFunction7(kGpioA, 9);
  pinToAlternateFunction7(kGpioA, 10);
  pinToAlternateFunction7(kGpioD, 8);
  pinToAlternateFunction7(kGpioD, 9);
  usartStart(kUsart1, kLinkBaud, kUsartRxInterrupt);
  usartStart(kUsart3, kLogBaud, 0);
  cortex_m::clearWakeSources(kUsart1Irq);
  cortex_m::enableWakeSource(kUsart1Irq);

  reg(cortex_m::kDemcr) |= cortex_m::kDemcrTraceEnable;
  reg(cortex_m::kDwtLock) = 0xC5ACCE55;  // Cortex-M7 DWT software unlock
  reg(cortex_m::kDwtCycleCount) = 0;
  reg(cortex_m::kDwtCtrl) |= 1u;

  cortex_m::startSysTick1kHz(kCoreClockHz);
  last_tick_counts_ = clockCounts();
}

uint32_t Board::pollTick() {
  if (!cortex_m::sysTickWrapped()) return 0;
  return periodsSinceLastTick(clockCounts());
}

uint64_t Board::clockCounts() { return extendClock(reg(cortex_m::kDwtCycleCount)); }

uint32_t Board::clockHz() const { return kCoreClockHz; }

size_t Board::linkFetchFrame() { return 0; }  // a byte stream: nothing to fetch

size_t Board::linkRead(uint8_t* dst, size_t capacity) {
  size_t n = 0;
  while (n < capacity && (reg(kUsart1 + kUsartIsr) & kUsartRxNotEmpty)) {
    dst[n++] = static_cast<uint8_t>(reg(kUsart1 + kUsartRdr));
  }
  return n;
}

void Board::linkWrite(const uint8_t* src, size_t n) {
  for (size_t i = 0; i < n; ++i) usartWriteByte(kUsart1, src[i]);
}

void Board::log(const char* line) {
  for (size_t i = 0; line[i] != '\0' && i < 256; ++i) usartWriteByte(kUsart3, static_cast<uint8_t>(line[i]));
  usartWriteByte(kUsart3, '\r');
  usartWriteByte(kUsart3, '\n');
}

void Board::watchdogStart(uint32_t timeout_ms) {
  reg(kIwdgKey) = 0xCCCC;  // start (cannot be stopped again)
  reg(kIwdgKey) = 0x5555;  // unlock PR and RLR
  reg(kIwdgPrescaler) = 0;  // /4
  reg(kIwdgReload) = timeout_ms * kIwdgCountsPerMs;
  waitForBits(kIwdgStatus, 0x7u, 0u, kPollAttempts);
  reg(kIwdgKey) = 0xAAAA;
}

void Board::watchdogKick() { reg(kIwdgKey) = 0xAAAA; }

void Board::waitForEvent() {
  if (reg(kUsart1 + kUsartIsr) & kUsartRxNotEmpty) return;
  cortex_m::waitForInterrupt();
  cortex_m::clearWakeSources(kUsart1Irq);
}

uint32_t Board::boardId() const { return wire::kBoardStm32h743; }

bool Board::fpuIsDoublePrecision() const { return cortex_m::fpuHasDoublePrecision(); }

}  // namespace hyq::hal
