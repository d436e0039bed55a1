#pragma once
/// \file
/// Sequential reading of an LCM log (lcm-logger's format) through liblcm's reader, with the byte
/// offset of every event and of the first place the file stops making sense. liblcm returns
/// nothing on a short read or when an event is not followed by a valid header (1.3), or skips
/// bytes to the next sync word (newer versions); each is reported here as a break (the offset of
/// the first event not returned, and the reason, naming the damaged byte where it can) instead of
/// passing silently, and reading stops there, so everything before the break is intact. Every
/// event's header is checked before liblcm reads it (sync word, channel length 1..999, data length
/// at most 64 MiB, the event inside the file), so no declared length is allocated unchecked.

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

namespace lcm {
class LogFile;
}

namespace overstep::monitor {

struct LogEvent {
  std::int64_t offset = 0;     ///< byte offset of the event's sync word in the file
  std::int64_t timestamp = 0;  ///< us, when the logger received it
  std::string channel;
  const void* data = nullptr;  ///< valid until the next call to next()
  int size = 0;
};

class LogReader {
 public:
  /// InputError when the file cannot be opened.
  explicit LogReader(const std::string& path);
  ~LogReader();
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;

  /// The next event; false at the end of the log or at a break (see broken()).
  bool next(LogEvent& ev);

  bool broken() const { return break_offset_ >= 0; }
  std::int64_t breakOffset() const { return break_offset_; }  ///< -1 when intact
  const std::string& breakReason() const { return break_reason_; }
  std::int64_t fileSize() const { return size_; }
  std::int64_t events() const { return events_; }
  const std::string& path() const { return path_; }

 private:
  std::string checkEvent(FILE* f, std::int64_t at, std::int64_t& end) const;
  std::string path_;
  std::unique_ptr<lcm::LogFile> log_;
  std::int64_t size_ = 0;
  std::int64_t events_ = 0;
  std::int64_t break_offset_ = -1;
  std::string break_reason_;
  bool done_ = false;
};

}  // namespace overstep::monitor
