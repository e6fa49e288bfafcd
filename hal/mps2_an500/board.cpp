// ARM MPS2 with the AN500 FPGA image (Cortex-M7, double-precision FPU), as
// modelled by `qemu-system-arm -M mps2-an500` (QEMU 7.2):
//   LAN9118 0xA0000000 Ethernet: the link to the bridge/simulator, one wire
//                      message per frame (EtherType 0x88B5, local experimental)
//   UART0 0x40004000   log channel (QEMU serial 0)
//   TIMER0 0x40000000  free-running clock, 25 MHz
//   watchdog 0x40008000 (CMSDK APB watchdog: NMI at the first expiry, reset
//                      at the second)
// All CMSDK peripherals run from the 25 MHz system clock.
//
// Why Ethernet and not a UART for the link: 1 kHz x (386 + 1218) bytes is
// 1.6 MB/s, beyond any UART, and QEMU's CMSDK UART takes one byte per main
// loop round trip, which made a lock-step exchange take ~100 ms on a loaded
// host. The LAN9118 model queues whole frames.
#include "hal/board.hpp"
#include "hal/cortex_m.hpp"
#include "hal/wire.hpp"

namespace hyq::hal {
namespace {

using cortex_m::reg;

constexpr uint32_t kCoreClockHz = 25000000;

constexpr uint32_t kLogUart = 0x40004000;
constexpr uint32_t kUartData = 0x00;
constexpr uint32_t kUartState = 0x04;
constexpr uint32_t kUartCtrl = 0x08;
constexpr uint32_t kUartBaudDiv = 0x10;
constexpr uint32_t kUartTxFull = 1u << 0;
constexpr uint32_t kUartTxEnable = 1u << 0;
// The smallest divider the CMSDK UART accepts; QEMU does not pace bytes by it.
constexpr uint32_t kUartMinBaudDiv = 16;

// SMSC LAN9118 (QEMU hw/net/lan9118.c), direct register interface.
constexpr uint32_t kEth = 0xA0000000;  // AN500 map (AN385: 0x40200000)
constexpr uint32_t kEthIrq = 13;  // NVIC line on AN385/AN500
constexpr uint32_t kEthRxData = 0x00;
constexpr uint32_t kEthTxData = 0x20;
constexpr uint32_t kEthRxStatus = 0x40;
constexpr uint32_t kEthIrqCfg = 0x54;
constexpr uint32_t kEthIntStatus = 0x58;
constexpr uint32_t kEthIntEnable = 0x5C;
constexpr uint32_t kEthRxCfg = 0x6C;
constexpr uint32_t kEthTxCfg = 0x70;
constexpr uint32_t kEthRxFifoInfo = 0x7C;
constexpr uint32_t kEthMacCmd = 0xA4;
constexpr uint32_t kEthMacData = 0xA8;
constexpr uint32_t kEthIrqEnableActiveHigh = 0x111;  // IRQ_EN | IRQ_POL | IRQ_TYPE (push-pull)
constexpr uint32_t kEthRxStatusLevelInt = 1u << 3;   // RSFL: a frame is in the RX status FIFO
constexpr uint32_t kEthTxOn = 1u << 1;
constexpr uint32_t kEthTxStatusOverrunAllowed = 1u << 2;  // TX status entries are never read
constexpr uint32_t kEthMacBusy = 1u << 31;
constexpr uint32_t kMacControl = 1;
constexpr uint32_t kMacAddressHigh = 2;
constexpr uint32_t kMacAddressLow = 3;
// RXEN | TXEN | full duplex | promiscuous (the link is point to point).
constexpr uint32_t kMacControlValue = (1u << 2) | (1u << 3) | (1u << 20) | (1u << 18);
constexpr uint32_t kTxFirstAndLastSegment = (1u << 13) | (1u << 12);
constexpr size_t kEthHeaderBytes = 14;
constexpr size_t kEthFcsBytes = 4;
constexpr uint8_t kBoardMac[6] = {0x02, 0x00, 0x00, 0x00, 0x00, 0x01};
constexpr uint8_t kHostMac[6] = {0x02, 0x00, 0x00, 0x00, 0x00, 0x02};
constexpr uint16_t kEtherType = 0x88B5;

constexpr uint32_t kTimer0 = 0x40000000;
constexpr uint32_t kTimerCtrl = 0x00;
constexpr uint32_t kTimerValue = 0x04;
constexpr uint32_t kTimerReload = 0x08;

constexpr uint32_t kWatchdog = 0x40008000;
constexpr uint32_t kWdogLoad = 0x000;
constexpr uint32_t kWdogControl = 0x008;
constexpr uint32_t kWdogIntClear = 0x00C;
constexpr uint32_t kWdogLock = 0xC00;
constexpr uint32_t kWdogUnlockKey = 0x1ACCE551;
constexpr uint32_t kWdogInterruptEnable = 1u << 0;
constexpr uint32_t kWdogResetEnable = 1u << 1;
constexpr uint32_t kEmulatedWatchdogStretch = 20;  // [-] see watchdogStart()

// Best effort: a log byte that cannot leave within the bound is dropped.
void uartWriteByte(uint32_t uart, uint8_t byte) {
  if (cortex_m::waitForBits(uart + kUartState, kUartTxFull, 0, 100000)) reg(uart + kUartData) = byte;
}

void macWrite(uint32_t index, uint32_t value) {
  reg(kEth + kEthMacData) = value;
  reg(kEth + kEthMacCmd) = kEthMacBusy | index;
  cortex_m::waitForBits(kEth + kEthMacCmd, kEthMacBusy, 0, 1000);
}

void ethernetInit() {
  // Interrupt line active high before the NVIC sees it: the reset default
  // (active low) would hold it pending and WFI would never sleep.
  reg(kEth + kEthIrqCfg) = kEthIrqEnableActiveHigh;
  reg(kEth + kEthIntStatus) = 0xFFFFFFFFu;
  reg(kEth + kEthIntEnable) = kEthRxStatusLevelInt;
  reg(kEth + kEthRxCfg) = 0;
  reg(kEth + kEthTxCfg) = kEthTxOn | kEthTxStatusOverrunAllowed;
  macWrite(kMacAddressLow, kBoardMac[0] | (kBoardMac[1] << 8) | (kBoardMac[2] << 16) |
                               (static_cast<uint32_t>(kBoardMac[3]) << 24));
  macWrite(kMacAddressHigh, kBoardMac[4] | (kBoardMac[5] << 8));
  macWrite(kMacControl, kMacControlValue);
}

uint8_t ethernetHeaderByte(size_t i) {
  if (i < 6) return kHostMac[i];
  if (i < 12) return kBoardMac[i - 6];
  return static_cast<uint8_t>(i == 12 ? kEtherType >> 8 : kEtherType & 0xFF);
}

void watchdogReload(uint32_t load) {
  reg(kWatchdog + kWdogLock) = kWdogUnlockKey;
  reg(kWatchdog + kWdogLoad) = load;
  reg(kWatchdog + kWdogIntClear) = 1;
  reg(kWatchdog + kWdogLock) = 0;
}

}  // namespace

void Board::init() {
  reset_cause_ = wire::kResetPowerOn;
  reg(kLogUart + kUartBaudDiv) = kUartMinBaudDiv;
  reg(kLogUart + kUartCtrl) = kUartTxEnable;
  ethernetInit();
  // The Ethernet interrupt only wakes WFI (PRIMASK is set): no handler runs.
  cortex_m::clearWakeSources(kEthIrq);
  cortex_m::enableWakeSource(kEthIrq);

  reg(kTimer0 + kTimerCtrl) = 0;
  reg(kTimer0 + kTimerReload) = 0xFFFFFFFFu;
  reg(kTimer0 + kTimerValue) = 0xFFFFFFFFu;
  reg(kTimer0 + kTimerCtrl) = 1;

  cortex_m::startSysTick1kHz(kCoreClockHz);
  last_tick_counts_ = clockCounts();
}

uint32_t Board::pollTick() {
  if (!cortex_m::sysTickWrapped()) return 0;
  return periodsSinceLastTick(clockCounts());
}

uint64_t Board::clockCounts() {
  // TIMER0 counts down from 0xFFFFFFFF.
  return extendClock(0xFFFFFFFFu - reg(kTimer0 + kTimerValue));
}

uint32_t Board::clockHz() const { return kCoreClockHz; }

size_t Board::linkFetchFrame() {
  if ((reg(kEth + kEthRxFifoInfo) >> 16 & 0xFFu) == 0) return 0;
  const uint32_t status = reg(kEth + kEthRxStatus);
  const size_t frame_bytes = (status >> 16) & 0x3FFFu;  // including the FCS
  const size_t words = (frame_bytes + 3) / 4;
  size_t kept = 0;
  for (size_t w = 0; w < words; ++w) {
    const uint32_t word = reg(kEth + kEthRxData);
    for (int b = 0; b < 4 && kept < kLinkFrameBytes; ++b) link_frame_[kept++] = static_cast<uint8_t>(word >> (8 * b));
  }
  const bool ours = frame_bytes >= kEthHeaderBytes + kEthFcsBytes && frame_bytes <= kLinkFrameBytes &&
                    link_frame_[12] == (kEtherType >> 8) && link_frame_[13] == (kEtherType & 0xFF);
  // Other traffic on the wire is not ours to count: the decoder only sees
  // payloads, and validates them itself.
  link_frame_position_ = kEthHeaderBytes;
  link_frame_length_ = ours ? frame_bytes - kEthFcsBytes : kEthHeaderBytes;
  return link_frame_length_ - link_frame_position_;
}

size_t Board::linkRead(uint8_t* dst, size_t capacity) {
  if (link_frame_position_ >= link_frame_length_ && linkFetchFrame() == 0) return 0;
  size_t n = 0;
  while (n < capacity && link_frame_position_ < link_frame_length_) dst[n++] = link_frame_[link_frame_position_++];
  return n;
}

void Board::linkWrite(const uint8_t* src, size_t n) {
  const size_t frame_bytes = kEthHeaderBytes + n;
  reg(kEth + kEthTxData) = kTxFirstAndLastSegment | static_cast<uint32_t>(frame_bytes);
  reg(kEth + kEthTxData) = static_cast<uint32_t>(frame_bytes);
  for (size_t i = 0; i < frame_bytes; i += 4) {
    uint32_t word = 0;
    for (size_t b = 0; b < 4 && i + b < frame_bytes; ++b) {
      const size_t k = i + b;
      const uint8_t byte = k < kEthHeaderBytes ? ethernetHeaderByte(k) : src[k - kEthHeaderBytes];
      word |= static_cast<uint32_t>(byte) << (8 * b);
    }
    reg(kEth + kEthTxData) = word;
  }
}

void Board::log(const char* line) {
  for (size_t i = 0; line[i] != '\0' && i < 256; ++i) uartWriteByte(kLogUart, static_cast<uint8_t>(line[i]));
  uartWriteByte(kLogUart, '\n');
}

void Board::watchdogStart(uint32_t timeout_ms) {
  // NMI (fault snapshot) after the timeout. Under QEMU the watchdog counts
  // host time, and a loaded host can stall the emulator for tens of
  // milliseconds: the timeout is stretched so that only a hung loop, not a
  // busy host, resets the board.
  watchdogReload(timeout_ms * kEmulatedWatchdogStretch * (kCoreClockHz / 1000u));
  reg(kWatchdog + kWdogLock) = kWdogUnlockKey;
  reg(kWatchdog + kWdogControl) = kWdogInterruptEnable | kWdogResetEnable;
  reg(kWatchdog + kWdogLock) = 0;
}

// Writing LOAD restarts the count from the timeout.
void Board::watchdogKick() { watchdogReload(reg(kWatchdog + kWdogLoad)); }

void Board::waitForEvent() {
  if (link_frame_position_ < link_frame_length_ || (reg(kEth + kEthRxFifoInfo) >> 16 & 0xFFu) != 0) return;
  cortex_m::waitForInterrupt();
  reg(kEth + kEthIntStatus) = kEthRxStatusLevelInt;
  cortex_m::clearWakeSources(kEthIrq);
}

uint32_t Board::boardId() const { return wire::kBoardMps2An500; }

bool Board::fpuIsDoublePrecision() const { return cortex_m::fpuHasDoublePrecision(); }

}  // namespace hyq::hal
