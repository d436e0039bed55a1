// Fuzz target: the LCM log reader (monitor::LogReader on liblcm's reader, event headers checked
// before allocation) with every event decoded and flattened as export, monitor and report do.
// Seeds: tests/fuzz/corpus/lcm_log/ (the start of a recorded demo run).
#include <cstdint>
#include <vector>

#include "fuzz_util.hpp"
#include "overstep/core/error.hpp"
#include "overstep/monitor/lcm_log.hpp"
#include "overstep/monitor/messages.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace overstep;
  try {
    monitor::LogReader reader(fuzz::asFile(data, size, "bus.lcmlog"));
    monitor::LogEvent ev;
    monitor::AnyMessage msg;
    std::vector<monitor::Cell> cells;
    while (reader.next(ev)) {
      if (monitor::decode(ev.data, ev.size, msg) == monitor::DecodeStatus::Ok)
        monitor::flatten(msg, {}, cells);
    }
    (void)reader.breakReason();
  } catch (const InputError&) {
  }
  return 0;
}
