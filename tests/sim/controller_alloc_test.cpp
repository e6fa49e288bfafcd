// No heap after init: every allocation function of the process is replaced
// by a counting one, and 10,000+ closed-loop controller ticks (standing,
// swinging, touch-downs, slips, a corrupt frame) must allocate nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <new>

#include "firmware/controller/controller.hpp"
#include "sim_host/scenario/scenario.hpp"
#include "sim_host/physics/simulator.hpp"

namespace {
bool g_counting = false;
long g_allocations = 0;
}  // namespace

extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void* malloc(size_t n) {
  if (g_counting) ++g_allocations;
  return __libc_malloc(n);
}
void* calloc(size_t n, size_t m) {
  if (g_counting) ++g_allocations;
  return __libc_calloc(n, m);
}
void* realloc(void* p, size_t n) {
  if (g_counting) ++g_allocations;
  return __libc_realloc(p, n);
}
}

void* operator new(size_t n) {
  if (g_counting) ++g_allocations;
  void* p = __libc_malloc(n ? n : 1);
  if (!p) std::abort();
  return p;
}
void* operator new[](size_t n) { return operator new(n); }
void* operator new(size_t n, const std::nothrow_t&) noexcept { return operator new(n); }
void* operator new[](size_t n, const std::nothrow_t&) noexcept { return operator new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }
void operator delete[](void* p, size_t) noexcept { std::free(p); }

namespace hyq::sim {

TEST(ControllerHeap, CountingAllocatorSeesAnAllocation) {
  // The counter works: otherwise the test below could not fail.
  g_allocations = 0;
  g_counting = true;
  void* volatile p = std::malloc(16);
  int* volatile q = new int(3);
  g_counting = false;
  std::free(p);
  delete q;
  EXPECT_EQ(g_allocations, 2);
}

TEST(ControllerHeap, TenThousandClosedLoopStepsAllocateNothing) {
  // Walking onto a low-friction patch, so slip detection, estimation and
  // recovery run too.
  Scenario scenario = parseScenario(
      "name: heap\nduration: 12.0\nterrain:\n  mu: 0.8\n  patches:\n"
      "    - {x: [0.3, 2.0], y: [-2.0, 2.0], mu: 0.2}\n",
      "heap-test");
  Simulator sim(scenario);
  Controller controller;
  controller.init(scenario.controller_params);
  hal::CommandFrame command{};
  TickRecord record;
  long steps = 0;
  uint32_t flags_seen = 0;
  g_allocations = 0;
  while (sim.time() < scenario.duration && !sim.fallen()) {
    hal::SensorFrame frame = sim.sensorFrame();
    if (steps == 5000) frame.q[4] = std::nan("");  // one corrupt frame
    g_counting = true;
    controller.step(frame, command);
    g_counting = false;
    flags_seen |= command.flags;
    sim.step(command, record);
    ++steps;
  }
  EXPECT_GE(steps, 10000);
  EXPECT_NE(flags_seen & hal::kFlagBadSensorFrame, 0u);
  EXPECT_EQ(g_allocations, 0);
}

}  // namespace hyq::sim
