#include "overstep/monitor/lcm_log.hpp"

#include <sys/stat.h>

#include <cstdio>
#include <lcm/lcm-cpp.hpp>

#include "overstep/core/error.hpp"

namespace overstep::monitor {

namespace {
constexpr std::int64_t kHeaderBytes = 4 + 8 + 8 + 4 + 4;  // sync, number, time, lengths
constexpr std::int64_t kMaxDataBytes = 64 << 20;  // our messages are ~1 kB; lcm-logger's < 4 GB
}  // namespace

namespace {

std::int64_t bigEndian(const unsigned char* p, int n) {
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  if (n == 4) return static_cast<std::int32_t>(static_cast<std::uint32_t>(v));
  return static_cast<std::int64_t>(v);
}

}  // namespace

/// Why the event at `at` cannot be read, from its header: "" when the header is sound and the
/// whole event lies inside the file (`end`: the byte after it). Checked before liblcm reads the
/// event, which allocates the declared data length + 1 first (0x7fffffff overflowed to a failed
/// calloc, then a write through the null pointer: SIGSEGV on a 32-byte file).
std::string LogReader::checkEvent(FILE* f, std::int64_t at, std::int64_t& end) const {
  const std::int64_t left = size_ - at;
  if (left < kHeaderBytes)
    return "truncated event header (" + std::to_string(left) + " bytes left)";
  unsigned char h[kHeaderBytes];
  if (fseeko(f, at, SEEK_SET) != 0 || fread(h, 1, sizeof h, f) != sizeof h ||
      fseeko(f, at, SEEK_SET) != 0)  // back to the event for liblcm
    return "unreadable event header";
  if (static_cast<std::uint32_t>(bigEndian(h, 4)) != 0xEDA1DA01u) return "no sync word";
  const std::int64_t channel = bigEndian(h + 20, 4), data = bigEndian(h + 24, 4);
  if (channel <= 0 || channel >= 1000 || data < 0 || data > kMaxDataBytes)
    return "invalid channel length (" + std::to_string(channel) + ") or data length (" +
           std::to_string(data) + ", at most " + std::to_string(kMaxDataBytes) +
           ") in the event header";
  end = at + kHeaderBytes + channel + data;
  if (end > size_)
    return "truncated event: it needs " + std::to_string(end - at) + " bytes, the file has " +
           std::to_string(left) + " left";
  return "";
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
  std::int64_t end = 0;
  const std::string problem = checkEvent(f, before, end);
  const lcm::LogEvent* e = problem.empty() ? log_->readNextEvent() : nullptr;
  if (e == nullptr) {
    // liblcm 1.3 also refuses an intact event that is not followed by a valid header or the end.
    done_ = true;
    break_offset_ = before;
    break_reason_ = problem.empty() ? "no valid event header at byte " + std::to_string(end) +
                                          " (after this event)"
                                    : problem;
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
