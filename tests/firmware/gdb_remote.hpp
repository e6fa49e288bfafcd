// A minimal client of QEMU's gdb stub (the GDB remote serial protocol over a
// Unix socket), for fault injection: stop the core, read a register, patch
// memory, let it run again.
#pragma once
#include <cstdint>
#include <string>

namespace hyq::test {

class GdbRemote {
 public:
  ~GdbRemote();
  // Connects (QEMU stops the core when a debugger attaches).
  bool connect(const std::string& socket_path, int timeout_ms);
  // One command packet, its reply (without framing); false on a timeout.
  bool request(const std::string& packet, std::string& reply, int timeout_ms = 5000);
  bool readRegister(int number, uint32_t& value);  // 32-bit, target little-endian
  bool writeMemory(uint32_t address, const uint8_t* bytes, int n);
  // Detaches: the core runs on.
  bool detach();

 private:
  bool sendPacket(const std::string& packet);
  bool readPacket(std::string& payload, int timeout_ms);
  int fd_ = -1;
};

}  // namespace hyq::test
