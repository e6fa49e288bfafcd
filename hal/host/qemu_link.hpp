// Host side of processor-in-the-loop: runs the mps2-an500 board image in
// `qemu-system-arm -M mps2-an500` as a child process and exchanges frames
// with it in lock-step over the board's emulated LAN9118 Ethernet (QEMU
// `-netdev stream` on a Unix socket this class listens on): one wire message
// per Ethernet frame. The board's UART0 (log channel) goes to a file.
//
//   hyq::hal::QemuLink link;
//   if (!link.open("build/fw-mps2-an500/hyq_mps2_an500.elf")) { ... link.error() ... }
//   link.exchange(sensors, command);   // once per simulated tick
//   link.close();
#pragma once
#include <sys/types.h>

#include <cstddef>
#include <cstdint>

#include "hal/frames.hpp"
#include "hal/wire.hpp"

namespace hyq::hal {

struct QemuLinkOptions {
  const char* qemu = "qemu-system-arm";
  // -icount shift=N: virtual time = instructions << N ns, so the board's
  // clock counts instructions (timing measurements). -1: real time.
  int icount_shift = -1;
  const char* log_path = nullptr;     // board log (UART1); nullptr: discarded
  int boot_timeout_ms = 10000;        // [ms] until the board's Hello
  int reply_timeout_ms = 5000;        // [ms] until the command for a sensor frame
  // QEMU's gdb stub on this Unix socket (tests that stall the core to
  // reach the watchdog); nullptr: none.
  const char* gdb_socket = nullptr;
};

class QemuLink {
 public:
  QemuLink() = default;
  QemuLink(const QemuLink&) = delete;
  QemuLink& operator=(const QemuLink&) = delete;
  ~QemuLink() { close(); }

  // Starts QEMU on the image and waits for its Hello. False on failure
  // (error() says why).
  bool open(const char* elf_path, const QemuLinkOptions& options = QemuLinkOptions{});
  // Lock-step: sends the sensor frame, returns the board's command for that
  // frame's tick. Safe-state commands sent meanwhile (the host was slower
  // than the board's link timeout) are counted and skipped.
  bool exchange(const SensorFrame& sensors, CommandFrame& command);
  void close();
  bool isOpen() const { return child_ > 0; }

  // Sends controller parameters (the bytes of a hyq::Params) and waits for
  // the board's Hello confirming them; the board's controller restarts with
  // them. Call after open(), before the first exchange():
  //   link.configure(&params, sizeof params);
  bool configure(const void* config, size_t config_bytes);

  // For fault-injection tests: raw bytes as one link frame (at most
  // kMaxPayload), a sensor message with the next sequence number (or an
  // explicit one; later messages continue after the newest sent), and the
  // next message of any type from the board.
  static constexpr size_t kMaxPayload = 1500;
  bool sendRaw(const uint8_t* data, size_t n);
  bool sendSensor(const SensorFrame& sensors);
  bool sendSensorWithSequence(const SensorFrame& sensors, uint32_t sequence);
  bool receive(wire::Message& message, int timeout_ms);

  const wire::Hello& hello() const { return hello_; }
  const wire::BoardStatus& lastStatus() const { return last_status_; }
  const wire::DecoderCounters& decoderCounters() const { return decoder_.counters(); }
  uint32_t safeCommandsSkipped() const { return safe_commands_skipped_; }
  uint32_t nextSequence() const { return tx_sequence_ + 1; }
  // As a sender that restarted: numbering from 1 again, until a Hello from
  // the board says where to continue.
  void forgetNumbering() { tx_sequence_ = 0; }
  const char* error() const { return error_; }

 private:
  bool fail(const char* what);
  // Starts QEMU in a process group of its own (child_ and group_).
  bool spawnQemu(const char* elf_path, const QemuLinkOptions& options);
  // True (and child_status_ set, child_ -1) once QEMU has exited.
  bool reapedChild();
  // Fails with how QEMU ended (child_status_) and `when`.
  bool failEnded(const char* when);
  // Waits until QEMU connects to the link socket (true), QEMU ends, or
  // `timeout_ms` passes (false, error() says which).
  bool awaitConnection(int timeout_ms);
  bool writeAll(const uint8_t* data, size_t n);
  bool nextPayloadByte(uint8_t& byte, int64_t deadline_ms);

  static constexpr size_t kEthernetHeaderBytes = 14;

  pid_t child_ = -1;
  pid_t group_ = -1;       // QEMU's process group (its pid), until close()
  int child_status_ = 0;   // waitpid's status once QEMU has exited
  int listen_fd_ = -1;
  int fd_ = -1;
  char dir_[64] = {};
  char socket_path_[128] = {};
  uint32_t tx_sequence_ = 0;
  int reply_timeout_ms_ = 5000;
  wire::Decoder decoder_;
  wire::Message message_{};
  wire::Hello hello_{};
  wire::BoardStatus last_status_{};
  uint32_t safe_commands_skipped_ = 0;
  uint8_t tx_buffer_[wire::kMaxMessageBytes] = {};
  uint8_t rx_buffer_[65536] = {};   // bytes from the socket: length-prefixed frames
  size_t rx_length_ = 0;
  size_t rx_position_ = 0;
  uint8_t frame_[2048] = {};         // the current Ethernet frame
  size_t payload_length_ = 0;
  size_t payload_position_ = 0;
  char error_[256] = {};
};

}  // namespace hyq::hal
