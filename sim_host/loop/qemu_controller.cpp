#include "sim_host/loop/qemu_controller.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>

#include "hal/host/qemu_link.hpp"
#include "sim_host/scenario/scenario.hpp"

namespace hyq::sim {

// The configuration goes to the board in one link frame: Params, with the
// wire's header and CRC, within the frame's payload (an Ethernet frame's).
static_assert(hal::wire::kHeaderBytes + sizeof(Params) + hal::wire::kCrcBytes <= hal::QemuLink::kMaxPayload,
              "Params no longer fits one link frame");

namespace {

// QEMU's own stderr (e.g. "qemu: fatal: Lockup ..." and a register dump
// from an image that is not a board image) goes to a memory file instead
// of hyq_sim's stderr: the failure is then reported in one line, with the
// first line QEMU wrote.
class QemuStderr {
 public:
  QemuStderr() : fd_(::memfd_create("hyq_qemu_stderr", MFD_CLOEXEC)) {}
  ~QemuStderr() {
    if (fd_ >= 0) ::close(fd_);
  }
  QemuStderr(const QemuStderr&) = delete;
  QemuStderr& operator=(const QemuStderr&) = delete;

  // Runs `start` with this process's stderr pointing at the memory file,
  // so that the child it starts inherits that as its stderr.
  template <typename F>
  bool whileStarting(F start) {
    std::fflush(stderr);
    const int saved = fd_ >= 0 ? ::dup(STDERR_FILENO) : -1;
    if (saved >= 0) ::dup2(fd_, STDERR_FILENO);
    const bool ok = start();
    if (saved >= 0) {
      ::dup2(saved, STDERR_FILENO);
      ::close(saved);
    }
    return ok;
  }

  // " (qemu: <its first non-empty line>)", or "" if it wrote nothing.
  std::string said() const {
    if (fd_ < 0) return "";
    char text[512];
    const ssize_t n = ::pread(fd_, text, sizeof text, 0);
    if (n <= 0) return "";
    std::string_view all(text, static_cast<size_t>(n));
    while (!all.empty()) {
      const size_t end = all.find('\n');
      const std::string_view line = all.substr(0, end);
      if (line.find_first_not_of(" \t\r") != std::string_view::npos)
        return " (qemu: " + clipForMessage(line, 160) + ")";
      if (end == std::string_view::npos) break;
      all.remove_prefix(end + 1);
    }
    return "";
  }

 private:
  int fd_;
};

class QemuController final : public ControllerPort {
 public:
  explicit QemuController(const Scenario& scenario) {
    const std::string elf = defaultFirmwareImage();
    if (!stderr_.whileStarting([&] { return link_.open(elf.c_str()); })) {
      const std::string error = link_.error();
      throw std::runtime_error("qemu controller: cannot boot " + clipForMessage(elf, 200) + ": " +
                               error + stderr_.said());
    }
    // The board runs the scenario's parameters, not its built-in defaults.
    const hyq::Params& params = scenario.controller_params;
    if (!link_.configure(&params, sizeof params))
      throw std::runtime_error(std::string("qemu controller: configure failed: ") + link_.error() +
                               stderr_.said());
  }
  void step(const hal::SensorFrame& s, hal::CommandFrame& c) override {
    if (!link_.exchange(s, c))
      throw std::runtime_error(std::string("qemu controller: link failed: ") + link_.error() +
                               stderr_.said());
  }

 private:
  QemuStderr stderr_;  // outlives the link: QEMU writes to it until closed
  hal::QemuLink link_;
};

}  // namespace

std::string defaultFirmwareImage() {
  if (const char* env = std::getenv("HYQ_FW_MPS2_ELF")) return env;
  return HYQ_DEFAULT_FW_ELF;
}

std::unique_ptr<ControllerPort> makeQemuController(const Scenario& scenario) {
  return std::make_unique<QemuController>(scenario);
}

}  // namespace hyq::sim
