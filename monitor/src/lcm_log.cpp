#include "overstep/monitor/lcm_log.hpp"

#include <sys/stat.h>

#include <cstdio>
#include <lcm/lcm-cpp.hpp>

#include "overstep/core/error.hpp"

namespace overstep::monitor {

namespace {
constexpr std::int64_t kHeaderBytes = 4 + 8 + 8 + 4 + 4;  // sync, number, time, lengths
}

LogReader::LogReader(const std::string& path) : path_(path) {
  struct stat sb {};
  if (::stat(path.c_str(), &sb) != 0 || !S_ISREG(sb.st_mode)) {
    throw InputError(path + ": no such log file");
  }
  size_ = static_cast<std::int64_t>(sb.st_size);
  log_ = std::make_unique<lcm::LogFile>(path, "r");
  if (!log_->good()) throw InputError(path + ": cannot open the log for reading");
}

LogReader::~LogReader() = default;

bool LogReader::next(LogEvent& ev) {
  if (done_) return false;
  FILE* f = log_->getFilePtr();
  const std::int64_t before = ftello(f);
  if (before >= size_) {
    done_ = true;
    return false;
  }
  const lcm::LogEvent* e = log_->readNextEvent();
  if (e == nullptr) {
    done_ = true;
    break_offset_ = before;
    break_reason_ =
        size_ - before < kHeaderBytes
            ? "truncated event header (" + std::to_string(size_ - before) + " bytes left)"
            : "truncated or corrupt event (no complete event from here to the end)";
    return false;
  }
  const std::int64_t after = ftello(f);
  const std::int64_t expected = kHeaderBytes + static_cast<std::int64_t>(e->channel.size()) +
                                static_cast<std::int64_t>(e->datalen);
  if (after - before != expected) {
    // liblcm skipped garbage to find the next sync word: the file is damaged at `before`.
    done_ = true;
    break_offset_ = before;
    break_reason_ = "no sync word: " + std::to_string(after - before - expected) +
                    " bytes of garbage before the next event";
    return false;
  }
  ev.offset = before;
  ev.timestamp = e->timestamp;
  ev.channel = e->channel;
  ev.data = e->data;
  ev.size = e->datalen;
  ++events_;
  return true;
}

}  // namespace overstep::monitor
