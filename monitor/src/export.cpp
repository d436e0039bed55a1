#include "overstep/monitor/export.hpp"

#include <fcntl.h>
#include <stdlib.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>

#include "overstep/core/error.hpp"
#include "overstep/monitor/lcm_log.hpp"
#include "overstep/monitor/messages.hpp"

namespace overstep::monitor {

namespace fs = std::filesystem;

std::string channelFileName(const std::string& channel) {
  static const char* const hex = "0123456789ABCDEF";
  std::string s;
  for (std::size_t i = 0; i < channel.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(channel[i]);
    const bool plain = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                       c == '_' || c == '-' || (c == '.' && i > 0);
    if (plain) {
      s += static_cast<char>(c);
    } else {
      s += '%';
      s += hex[c >> 4];
      s += hex[c & 15];
    }
  }
  constexpr std::size_t kMaxStem = 200;  // + ".csv": well inside NAME_MAX (255)
  if (s.size() > kMaxStem) {
    std::uint64_t h = 14695981039346656037ull;  // FNV-1a of the whole name
    for (const char c : channel) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ull;
    std::string tail = "~";
    for (int k = 15; k >= 0; --k) tail += hex[(h >> (4 * k)) & 15];
    s = s.substr(0, kMaxStem - tail.size()) + tail;
  }
  return s + ".csv";
}

namespace {

std::string quoted(const std::string& s) {
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

struct ChannelFile {
  std::string name, path;
  std::ofstream out;
  std::vector<std::string> header;  // column names of the first message
  std::int64_t rows = 0;
};

bool endsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

/// A folder created beside the export's target, removed with what it holds unless released.
struct TempFolder {
  fs::path path;
  TempFolder() = default;
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
  ~TempFolder() {
    std::error_code ec;
    if (!path.empty()) fs::remove_all(path, ec);
  }
  /// mkdtemp(3) of `prefix` + "XXXXXX"; empty on failure.
  static fs::path make(const fs::path& prefix) {
    std::string tmpl = prefix.string() + "XXXXXX";
    if (!::mkdtemp(tmpl.data())) return {};
    return tmpl;
  }
};

/// The folder `dir` names, absolute, symbolic links resolved, without a trailing separator.
fs::path exportTarget(const std::string& dir) {
  std::error_code ec;
  fs::path t = fs::weakly_canonical(fs::absolute(dir, ec), ec);
  if (ec) throw InputError(dir + ": cannot resolve the output folder (" + ec.message() + ")");
  if (!t.has_filename()) t = t.parent_path();
  if (!t.has_filename() || t == t.root_path())
    throw InputError(dir + ": cannot export into the root folder");
  // DIR is replaced as a whole: never the folder a process (this one, its shell) works in.
  const fs::path cwd = fs::current_path(ec);
  if (!ec) {
    const auto rel = cwd.lexically_relative(t);
    if (!rel.empty() && *rel.begin() != "..")
      throw InputError(dir + ": is the current folder or holds it (it is replaced as a whole): " +
                       "export into a folder of its own");
  }
  return t;
}

}  // namespace

ExportSummary exportCsv(const std::string& log_path, const std::string& dir,
                        const std::vector<std::string>& joint_names,
                        const std::atomic<bool>* stop) {
  LogReader reader(log_path);
  const fs::path target = exportTarget(dir);
  std::error_code ec;
  // What DIR holds now: nothing, or a previous export (CSV files only; `.csv.tmp` are the
  // leftovers of versions that wrote beside the final files). Anything else stays untouched.
  const bool existed = fs::exists(fs::symlink_status(target, ec));
  std::size_t previous = 0;
  if (existed) {
    if (!fs::is_directory(target, ec)) throw InputError(dir + ": exists and is not a folder");
    for (const auto& e : fs::directory_iterator(target, ec)) {
      const std::string n = e.path().filename().string();
      if (!fs::is_regular_file(e.symlink_status()) ||
          !(endsWith(n, ".csv") || endsWith(n, ".csv.tmp")))
        throw InputError(dir + ": holds '" + n +
                         "', which is not an export's CSV file (choose a new or empty folder; "
                         "nothing was written)");
      ++previous;
    }
    if (ec) throw InputError(dir + ": cannot list the output folder (" + ec.message() + ")");
  }
  fs::create_directories(target.parent_path(), ec);
  TempFolder tmp;
  tmp.path =
      TempFolder::make(target.parent_path() / ("." + target.filename().string() + ".export-"));
  if (tmp.path.empty())
    throw InputError(dir + ": cannot create a folder beside it (" + std::strerror(errno) + ")");

  ExportSummary sum;
  std::map<std::string, std::unique_ptr<ChannelFile>> files;  // closed before `tmp` is removed
  std::set<std::string> names;
  LogEvent ev;
  AnyMessage msg;
  std::vector<Cell> cells;
  std::string line;
  char buf[64];
  while (reader.next(ev)) {
    if (stop && stop->load()) {
      sum.interrupted = true;
      return sum;
    }
    const DecodeStatus st = decode(ev.data, ev.size, msg);
    if (st == DecodeStatus::Malformed) {
      // One of our types whose bytes do not decode: the payload is damaged (LCM logs carry no
      // checksum, so this is the only corruption inside a well-framed event that shows).
      sum.break_offset = ev.offset;
      sum.break_reason = "the event on " + ev.channel + " does not decode";
      break;
    }
    ++sum.events;
    if (st != DecodeStatus::Ok) {
      ++sum.skipped[ev.channel];
      continue;
    }
    flatten(msg, joint_names, cells);
    auto& cf = files[ev.channel];
    if (!cf) {
      cf = std::make_unique<ChannelFile>();
      cf->name = channelFileName(ev.channel);
      if (!names.insert(cf->name).second)  // a 64-bit hash collision of two long names
        throw InputError(log_path + ": two channels map to the file name " + cf->name);
      cf->path = (tmp.path / cf->name).string();
      cf->out.open(cf->path, std::ios::trunc);
      if (!cf->out) throw InputError(dir + ": cannot write " + cf->name);
      line = "log_time [us],type";
      for (const auto& c : cells) {
        cf->header.push_back(c.name);
        line += "," + c.name + (c.unit.empty() ? "" : " [" + c.unit + "]");
      }
      cf->out << line << '\n';
    }
    if (cells.size() != cf->header.size()) {  // e.g. another joint count mid-log
      ++sum.skipped[ev.channel];
      continue;
    }
    line = std::to_string(ev.timestamp) + "," + typeName(msg);
    for (const auto& c : cells) {
      line += ',';
      switch (c.kind) {
        case Cell::Kind::Integer:
          line += std::to_string(c.integer);
          break;
        case Cell::Kind::Real:
          std::snprintf(buf, sizeof buf, "%.17g", c.real);
          line += buf;
          break;
        case Cell::Kind::Text:
          line += quoted(c.text);
          break;
      }
    }
    cf->out << line << '\n';
    ++cf->rows;
  }
  if (stop && stop->load()) {
    sum.interrupted = true;
    return sum;
  }
  if (sum.break_offset < 0) {
    sum.break_offset = reader.breakOffset();
    sum.break_reason = reader.breakReason();
  }
  for (auto& [channel, cf] : files) {
    cf->out.close();
    if (!cf->out) throw InputError(dir + ": writing " + cf->name + " failed");
    sum.rows[channel] = cf->rows;
  }
  // Into place: a new folder by one rename; over a previous export (or an empty folder) by an
  // exchange, after which `tmp` holds the old export and is removed. A damaged log's part never
  // replaces a previous export.
  const bool complete = sum.break_offset < 0;
  if (existed && previous > 0 && !complete) return sum;
  if (!existed) {
    fs::rename(tmp.path, target, ec);
    if (ec) throw InputError(dir + ": cannot move the export into place (" + ec.message() + ")");
    tmp.path.clear();
  } else if (::renameat2(AT_FDCWD, tmp.path.c_str(), AT_FDCWD, target.c_str(), RENAME_EXCHANGE) !=
             0) {
    // A file system without the exchange: the old export aside, the new one in, the old removed.
    const int why = errno;
    if (why != EINVAL && why != ENOSYS)
      throw InputError(dir + ": cannot move the export into place (" + std::strerror(why) + ")");
    TempFolder old;
    old.path =
        TempFolder::make(target.parent_path() / ("." + target.filename().string() + ".old-"));
    if (old.path.empty() || std::rename(target.c_str(), old.path.c_str()) != 0)
      throw InputError(dir + ": cannot move the previous export aside (" + std::strerror(errno) +
                       ")");
    if (std::rename(tmp.path.c_str(), target.c_str()) != 0) {
      const int e = errno;
      std::rename(old.path.c_str(), target.c_str());
      throw InputError(dir + ": cannot move the export into place (" + std::strerror(e) + ")");
    }
    tmp.path.clear();
  }
  sum.written = true;
  for (const auto& [channel, cf] : files) sum.files[channel] = (fs::path(dir) / cf->name).string();
  return sum;
}

}  // namespace overstep::monitor
