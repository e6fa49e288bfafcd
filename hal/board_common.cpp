// Board bookkeeping shared by every backend: clock extension and ticks.
#include "hal/board.hpp"
#include "hal/frames.hpp"

namespace hyq::hal {

uint64_t Board::extendClock(uint32_t raw_up_count) {
  if (raw_up_count < clock_last_raw_) clock_high_ += (uint64_t{1} << 32);
  clock_last_raw_ = raw_up_count;
  return clock_high_ | raw_up_count;
}

uint32_t Board::periodsSinceLastTick(uint64_t now) {
  const uint64_t period = clockHz() / kTicksPerSecond;
  const uint64_t elapsed = now - last_tick_counts_;
  last_tick_counts_ = now;
  // SysTick and this clock may come from different oscillators: round, and
  // a wrap always counts as at least one period.
  const uint64_t periods = (elapsed + period / 2) / period;
  return periods == 0 ? 1u : static_cast<uint32_t>(periods);
}

}  // namespace hyq::hal
