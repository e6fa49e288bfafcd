#include "hal/host/qemu_link.hpp"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace hyq::hal {
namespace {

int64_t nowMs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000 + ts.tv_nsec / 1000000;
}

bool waitReadable(int fd, int timeout_ms) {
  pollfd p{fd, POLLIN, 0};
  int r;
  do {
    r = ::poll(&p, 1, timeout_ms);
  } while (r < 0 && errno == EINTR);
  return r > 0;
}

}  // namespace

bool QemuLink::fail(const char* what) {
  std::snprintf(error_, sizeof error_, "%s%s%s", what, errno ? ": " : "", errno ? std::strerror(errno) : "");
  close();
  return false;
}

bool QemuLink::spawnQemu(const char* elf_path, const QemuLinkOptions& options) {
  char netdev[192];
  char log_serial[300];
  char icount[48];
  char gdb_chardev[200];
  std::snprintf(netdev, sizeof netdev, "stream,id=link,server=off,addr.type=unix,addr.path=%s", socket_path_);
  std::snprintf(log_serial, sizeof log_serial, "%s%s", options.log_path ? "file:" : "null",
                options.log_path ? options.log_path : "");
  std::snprintf(icount, sizeof icount, "shift=%d", options.icount_shift);
  const char* argv[32];
  int n = 0;
  argv[n++] = options.qemu;
  argv[n++] = "-M";
  argv[n++] = "mps2-an500";
  argv[n++] = "-nodefaults";
  argv[n++] = "-display";
  argv[n++] = "none";
  argv[n++] = "-kernel";
  argv[n++] = elf_path;
  argv[n++] = "-netdev";  // the board's LAN9118: the link
  argv[n++] = netdev;
  argv[n++] = "-net";
  argv[n++] = "nic,netdev=link,model=lan9118";
  argv[n++] = "-serial";  // UART0: the board's log channel
  argv[n++] = log_serial;
  if (options.icount_shift >= 0) {
    argv[n++] = "-icount";
    argv[n++] = icount;
  }
  if (options.gdb_socket != nullptr) {
    std::snprintf(gdb_chardev, sizeof gdb_chardev, "socket,id=gdb,path=%s,server=on,wait=off", options.gdb_socket);
    argv[n++] = "-chardev";
    argv[n++] = gdb_chardev;
    argv[n++] = "-gdb";
    argv[n++] = "chardev:gdb";
  }
  argv[n] = nullptr;
  // The child writes exec's errno here; the pipe closes unread on success.
  int started[2];
  if (::pipe2(started, O_CLOEXEC) != 0) return false;
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) {
    // Only async-signal-safe calls until exec. QEMU and whatever it starts
    // form a process group of their own, which close() ends as a whole;
    // out of the terminal's group (which Ctrl-C reaches), QEMU is killed
    // when this process ends, however it ends.
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);
    // QEMU's own chatter must not mix with the caller's stdout.
    const int null_in = ::open("/dev/null", O_RDONLY);
    const int null_out = ::open("/dev/null", O_WRONLY);
    if (null_in < 0 || null_out < 0 || ::dup2(null_in, STDIN_FILENO) < 0 || ::dup2(null_out, STDOUT_FILENO) < 0)
      ::_exit(127);
    ::execvp(options.qemu, const_cast<char* const*>(argv));
    const int error = errno;
    (void)!::write(started[1], &error, sizeof error);
    ::_exit(127);
  }
  const int fork_error = errno;
  ::close(started[1]);
  int error = pid < 0 ? fork_error : 0;
  if (pid > 0) {
    ssize_t got;
    while ((got = ::read(started[0], &error, sizeof error)) < 0 && errno == EINTR) {
    }
    if (got != static_cast<ssize_t>(sizeof error)) error = 0;
  }
  ::close(started[0]);
  if (error != 0) {
    if (pid > 0) ::waitpid(pid, nullptr, 0);
    errno = error;
    return false;
  }
  child_ = group_ = pid;
  return true;
}

bool QemuLink::reapedChild() {
  int status = 0;
  if (child_ <= 0 || ::waitpid(child_, &status, WNOHANG) != child_) return false;
  child_status_ = status;
  child_ = -1;
  return true;
}

bool QemuLink::failEnded(const char* when) {
  if (WIFSIGNALED(child_status_))
    std::snprintf(error_, sizeof error_, "qemu-system-arm was killed by signal %d %s", WTERMSIG(child_status_),
                  when);
  else
    std::snprintf(error_, sizeof error_, "qemu-system-arm exited with status %d %s", WEXITSTATUS(child_status_),
                  when);
  close();
  return false;
}

bool QemuLink::awaitConnection(int timeout_ms) {
  const int64_t deadline = nowMs() + timeout_ms;
  for (int64_t left = timeout_ms; left > 0; left = deadline - nowMs()) {
    // In slices of 20 ms, to notice an emulator that ends without connecting.
    if (waitReadable(listen_fd_, static_cast<int>(std::min<int64_t>(left, 20)))) return true;
    if (reapedChild()) return failEnded("before it connected to the link socket");
  }
  errno = 0;
  return fail("qemu did not connect to the link socket");
}

bool QemuLink::open(const char* elf_path, const QemuLinkOptions& options) {
  close();
  errno = 0;
  if (::access(elf_path, R_OK) != 0) return fail("board image not readable");
  std::snprintf(dir_, sizeof dir_, "/tmp/hyq_qemu_XXXXXX");
  if (!::mkdtemp(dir_)) return fail("mkdtemp");
  std::snprintf(socket_path_, sizeof socket_path_, "%s/link.sock", dir_);

  listen_fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) return fail("socket");
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  if (std::strlen(socket_path_) >= sizeof address.sun_path) return fail("socket path too long");
  std::memcpy(address.sun_path, socket_path_, std::strlen(socket_path_) + 1);
  if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) return fail("bind");
  if (::listen(listen_fd_, 1) != 0) return fail("listen");

  if (!spawnQemu(elf_path, options)) return fail("cannot start qemu-system-arm");
  // QEMU connects as soon as it has parsed its command line.
  if (!awaitConnection(options.boot_timeout_ms)) return false;
  fd_ = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
  if (fd_ < 0) return fail("accept");

  reply_timeout_ms_ = options.reply_timeout_ms;
  decoder_.reset();
  decoder_.expect(wire::MessageType::kCommand, wire::MessageType::kHello);
  tx_sequence_ = 0;
  safe_commands_skipped_ = 0;
  rx_length_ = rx_position_ = 0;
  payload_length_ = payload_position_ = 0;
  const int64_t deadline = nowMs() + options.boot_timeout_ms;
  while (nowMs() < deadline) {
    if (!receive(message_, static_cast<int>(deadline - nowMs()))) break;
    if (message_.type == wire::MessageType::kHello) {
      hello_ = message_.hello;
      if (hello_.wire_version != wire::kVersion) {
        errno = 0;
        return fail("board image speaks another wire version");
      }
      return true;
    }
  }
  // An emulator that ended closes the link: said as such (its exit is
  // seen shortly after the socket's end).
  for (int i = 0; i < 20 && child_ > 0; ++i) {
    if (reapedChild()) return failEnded("before the board's Hello");
    ::usleep(10000);
  }
  errno = 0;
  return fail("no Hello from the board");
}

void QemuLink::close() {
  if (fd_ >= 0) ::close(fd_);
  if (listen_fd_ >= 0) ::close(listen_fd_);
  fd_ = listen_fd_ = -1;
  if (group_ > 0) {
    // QEMU's whole process group: QEMU and anything it started.
    ::kill(-group_, SIGTERM);
    // Give QEMU a moment, then make sure it and the rest of its group are
    // gone.
    for (int i = 0; i < 100 && child_ > 0 && !reapedChild(); ++i) ::usleep(10000);
    ::kill(-group_, SIGKILL);
    if (child_ > 0) ::waitpid(child_, nullptr, 0);
  }
  child_ = group_ = -1;
  if (socket_path_[0] != '\0') ::unlink(socket_path_);
  if (dir_[0] != '\0') ::rmdir(dir_);
  socket_path_[0] = dir_[0] = '\0';
}

bool QemuLink::writeAll(const uint8_t* data, size_t n) {
  size_t sent = 0;
  while (sent < n) {
    const ssize_t r = ::send(fd_, data + sent, n - sent, MSG_NOSIGNAL);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return false;
    sent += static_cast<size_t>(r);
  }
  return true;
}

// QEMU's stream netdev carries each Ethernet frame as a 4-byte big-endian
// length and the frame.
bool QemuLink::sendRaw(const uint8_t* data, size_t n) {
  if (n > kMaxPayload) return false;
  const size_t frame_bytes = kEthernetHeaderBytes + n;
  uint8_t header[4 + kEthernetHeaderBytes] = {
      static_cast<uint8_t>(frame_bytes >> 24), static_cast<uint8_t>(frame_bytes >> 16),
      static_cast<uint8_t>(frame_bytes >> 8), static_cast<uint8_t>(frame_bytes),
      0x02, 0x00, 0x00, 0x00, 0x00, 0x01,  // to the board
      0x02, 0x00, 0x00, 0x00, 0x00, 0x02,  // from the host
      0x88, 0xB5};                         // EtherType: local experimental
  return writeAll(header, sizeof header) && writeAll(data, n);
}

bool QemuLink::sendSensorWithSequence(const SensorFrame& sensors, uint32_t sequence) {
  // Later messages continue after the newest sequence sent.
  if (static_cast<int32_t>(sequence - tx_sequence_) > 0) tx_sequence_ = sequence;
  const size_t n = wire::encodeSensor(sensors, sequence, tx_buffer_, sizeof tx_buffer_);
  return n > 0 && sendRaw(tx_buffer_, n);
}

bool QemuLink::sendSensor(const SensorFrame& sensors) {
  return sendSensorWithSequence(sensors, ++tx_sequence_);
}

// Next link payload byte from the stream of length-prefixed frames; false
// on timeout or a closed link.
bool QemuLink::nextPayloadByte(uint8_t& byte, int64_t deadline_ms) {
  for (;;) {
    if (payload_position_ < payload_length_) {
      byte = frame_[payload_position_++];
      return true;
    }
    // Need a whole frame: 4 length bytes, then the frame.
    while (rx_length_ - rx_position_ >= 4) {
      const uint8_t* p = rx_buffer_ + rx_position_;
      const size_t frame_bytes = (size_t{p[0]} << 24) | (size_t{p[1]} << 16) | (size_t{p[2]} << 8) | p[3];
      if (frame_bytes > sizeof frame_) return false;  // not a frame stream: give up
      if (rx_length_ - rx_position_ < 4 + frame_bytes) break;
      std::memcpy(frame_, p + 4, frame_bytes);
      rx_position_ += 4 + frame_bytes;
      const bool ours = frame_bytes > kEthernetHeaderBytes && frame_[12] == 0x88 && frame_[13] == 0xB5;
      payload_position_ = kEthernetHeaderBytes;
      payload_length_ = ours ? frame_bytes : kEthernetHeaderBytes;
      if (ours) break;
    }
    if (payload_position_ < payload_length_) continue;
    // Keep the partial frame at the front, then read more.
    std::memmove(rx_buffer_, rx_buffer_ + rx_position_, rx_length_ - rx_position_);
    rx_length_ -= rx_position_;
    rx_position_ = 0;
    const int64_t left = deadline_ms - nowMs();
    if (left <= 0 || !waitReadable(fd_, static_cast<int>(left))) return false;
    const ssize_t r = ::recv(fd_, rx_buffer_ + rx_length_, sizeof rx_buffer_ - rx_length_, 0);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return false;
    rx_length_ += static_cast<size_t>(r);
  }
}

bool QemuLink::receive(wire::Message& message, int timeout_ms) {
  if (fd_ < 0) return false;
  const int64_t deadline = nowMs() + timeout_ms;
  uint8_t byte = 0;
  while (nextPayloadByte(byte, deadline)) {
    if (decoder_.push(byte, message)) {
      if (message.type == wire::MessageType::kCommand) last_status_ = message.status;
      // The board refuses numbers below its next_sequence: continue from it.
      if (message.type == wire::MessageType::kHello && message.hello.next_sequence - 1u - tx_sequence_ < 0x80000000u)
        tx_sequence_ = message.hello.next_sequence - 1u;
      return true;
    }
  }
  return false;
}

bool QemuLink::configure(const void* config, size_t config_bytes) {
  const auto* bytes = static_cast<const uint8_t*>(config);
  const uint32_t sequence = ++tx_sequence_;
  const size_t n = wire::encodeConfig(bytes, config_bytes, sequence, tx_buffer_, sizeof tx_buffer_);
  if (n == 0 || !sendRaw(tx_buffer_, n)) {
    std::snprintf(error_, sizeof error_, "cannot send a configuration of %zu bytes", config_bytes);
    return false;
  }
  const uint32_t expected = wire::crc32(bytes, config_bytes);
  const int64_t deadline = nowMs() + reply_timeout_ms_;
  while (nowMs() < deadline) {
    if (!receive(message_, static_cast<int>(deadline - nowMs()))) break;
    // Only the Hello that answers this config counts (the board also sends
    // Hellos of its own until the first frame).
    if (message_.type != wire::MessageType::kHello || message_.hello.config_sequence != sequence) continue;
    hello_ = message_.hello;
    if (hello_.config_result == wire::kConfigApplied && hello_.config_crc == expected) return true;
    static const char* const kWhy[] = {"applied with another crc", "it is controlling the robot",
                                       "its size is not sizeof(Params)", "a bool is neither 0 nor 1",
                                       "a value is out of range",
                                       "it has walked since its reset and takes only the set it runs"};
    const uint32_t r = hello_.config_result;
    std::snprintf(error_, sizeof error_, "the board refused the configuration (%zu bytes): %s", config_bytes,
                  r < sizeof kWhy / sizeof kWhy[0] ? kWhy[r] : "unknown reason");
    return false;
  }
  std::snprintf(error_, sizeof error_, "the board did not answer the configuration (%zu bytes)", config_bytes);
  return false;
}

bool QemuLink::exchange(const SensorFrame& sensors, CommandFrame& command) {
  if (!sendSensor(sensors)) return false;
  const int64_t deadline = nowMs() + reply_timeout_ms_;
  for (;;) {
    const int64_t left = deadline - nowMs();
    if (left <= 0 || !receive(message_, static_cast<int>(left))) {
      std::snprintf(error_, sizeof error_, "no command from the board for tick %u", sensors.tick);
      return false;
    }
    if (message_.type == wire::MessageType::kHello && message_.hello.link_epoch != hello_.link_epoch) {
      // A new epoch: the board restarted. It runs its built-in parameters
      // until configured again; the caller decides whether to re-send them.
      static const char* const kCause[] = {"power-on", "watchdog", "fault"};
      const uint32_t cause = message_.hello.reset_cause;
      std::snprintf(error_, sizeof error_,
                    "the board restarted (reset cause: %s) and runs parameter set %08x, not the confirmed %08x",
                    cause < 3 ? kCause[cause] : "unknown", message_.hello.config_crc, hello_.config_crc);
      hello_ = message_.hello;
      return false;
    }
    if (message_.type != wire::MessageType::kCommand) continue;
    if (message_.status.config_crc != hello_.config_crc) {
      // The board runs another parameter set than the one it confirmed, in
      // the same epoch (a restart shows as a new epoch, above): someone
      // else configured it. Stop rather than walk on.
      std::snprintf(error_, sizeof error_,
                    "the board runs parameter set %08x, not the confirmed %08x, without a restart: "
                    "another sender configured it",
                    message_.status.config_crc, hello_.config_crc);
      return false;
    }
    if ((message_.command.flags & kFlagLinkLost) != 0 || message_.command.tick != sensors.tick) {
      ++safe_commands_skipped_;
      continue;
    }
    command = message_.command;
    return true;
  }
}

}  // namespace hyq::hal
