#include "overstep/monitor/export.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include "overstep/core/error.hpp"
#include "overstep/monitor/lcm_log.hpp"
#include "overstep/monitor/messages.hpp"

namespace overstep::monitor {

namespace fs = std::filesystem;

std::string channelFileName(const std::string& channel) {
  std::string s = channel;
  for (char& c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) c = '_';
  return s + ".csv";
}

namespace {

std::string quoted(const std::string& s) {
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

struct ChannelFile {
  std::string final_path, tmp_path;
  std::ofstream out;
  std::vector<std::string> header;  // column names of the first message
  std::int64_t rows = 0;
};

}  // namespace

ExportSummary exportCsv(const std::string& log_path, const std::string& dir,
                        const std::vector<std::string>& joint_names) {
  LogReader reader(log_path);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) throw InputError(dir + ": cannot create the output folder");
  ExportSummary sum;
  std::map<std::string, std::unique_ptr<ChannelFile>> files;
  LogEvent ev;
  AnyMessage msg;
  std::vector<Cell> cells;
  std::string line;
  char buf[64];
  while (reader.next(ev)) {
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
      cf->final_path = (fs::path(dir) / channelFileName(ev.channel)).string();
      cf->tmp_path = cf->final_path + ".tmp";
      cf->out.open(cf->tmp_path, std::ios::trunc);
      if (!cf->out) throw InputError(cf->tmp_path + ": cannot write");
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
  for (auto& [channel, cf] : files) {
    cf->out.close();
    if (!cf->out) throw InputError(cf->tmp_path + ": write failed");
    fs::rename(cf->tmp_path, cf->final_path, ec);
    if (ec) throw InputError(cf->final_path + ": cannot rename into place");
    sum.rows[channel] = cf->rows;
    sum.files[channel] = cf->final_path;
  }
  if (sum.break_offset < 0) {
    sum.break_offset = reader.breakOffset();
    sum.break_reason = reader.breakReason();
  }
  return sum;
}

}  // namespace overstep::monitor
