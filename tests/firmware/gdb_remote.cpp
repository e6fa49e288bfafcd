#include "gdb_remote.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <thread>

namespace hyq::test {

namespace {

std::string hexByte(unsigned v) {
  char b[3];
  std::snprintf(b, sizeof b, "%02x", v & 0xFFu);
  return b;
}

}  // namespace

GdbRemote::~GdbRemote() {
  if (fd_ >= 0) ::close(fd_);
}

bool GdbRemote::connect(const std::string& socket_path, int timeout_ms) {
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  if (socket_path.size() >= sizeof address.sun_path) return false;
  std::memcpy(address.sun_path, socket_path.c_str(), socket_path.size() + 1);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (std::chrono::steady_clock::now() < deadline) {
    fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0) return false;
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0) return true;
    ::close(fd_);
    fd_ = -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

bool GdbRemote::sendPacket(const std::string& packet) {
  unsigned sum = 0;
  for (char c : packet) sum += static_cast<unsigned char>(c);
  const std::string framed = "$" + packet + "#" + hexByte(sum);
  return ::write(fd_, framed.data(), framed.size()) == static_cast<ssize_t>(framed.size());
}

// Skips acknowledgements and notifications until a whole "$...#cc" arrives,
// then acknowledges it.
bool GdbRemote::readPacket(std::string& payload, int timeout_ms) {
  payload.clear();
  bool inside = false;
  int checksum_left = -1;
  for (;;) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return false;
    char c = 0;
    if (::read(fd_, &c, 1) != 1) return false;
    if (checksum_left > 0) {
      if (--checksum_left == 0) return ::write(fd_, "+", 1) == 1;
      continue;
    }
    if (!inside) {
      inside = (c == '$');
      continue;
    }
    if (c == '#') {
      checksum_left = 2;
      continue;
    }
    payload.push_back(c);
  }
}

// The stub may also send stop notices on its own (one when it stops the
// core at attach): a command other than "?" skips them.
bool GdbRemote::request(const std::string& packet, std::string& reply, int timeout_ms) {
  if (fd_ < 0 || !sendPacket(packet)) return false;
  do {
    if (!readPacket(reply, timeout_ms)) return false;
  } while (packet != "?" && !reply.empty() && (reply[0] == 'T' || reply[0] == 'S'));
  return true;
}

// From the whole register file ("g": QEMU answers "p" only to a debugger
// that read its target description); the core registers come first, 32 bits
// each.
bool GdbRemote::readRegister(int number, uint32_t& value) {
  std::string reply;
  if (!request("g", reply) || reply.size() < static_cast<size_t>(8 * (number + 1))) return false;
  value = 0;
  for (int i = 3; i >= 0; --i)
    value = (value << 8) | std::stoul(reply.substr(8 * number + 2 * i, 2), nullptr, 16);
  return true;
}

bool GdbRemote::writeMemory(uint32_t address, const uint8_t* bytes, int n) {
  char head[40];
  std::snprintf(head, sizeof head, "M%x,%x:", static_cast<unsigned>(address), static_cast<unsigned>(n));
  std::string packet = head;
  for (int i = 0; i < n; ++i) packet += hexByte(bytes[i]);
  std::string reply;
  return request(packet, reply) && reply == "OK";
}

bool GdbRemote::detach() {
  std::string reply;
  const bool ok = request("D", reply) && reply == "OK";
  ::close(fd_);
  fd_ = -1;
  return ok;
}

}  // namespace hyq::test
