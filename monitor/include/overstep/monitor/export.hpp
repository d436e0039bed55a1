#pragma once
/// \file
/// `overstep export LOG --csv DIR`: one CSV per channel, every field a column with its unit in the
/// header ("q[RLEG_JOINT0] [rad]"), the logger's receive time first. Numbers are written so that
/// they read back bit for bit (17 significant digits). A damaged log is exported up to the break.
///
/// The CSVs are written into a temporary sibling folder of DIR (".DIR.export-XXXXXX") that takes
/// DIR's place at the end (one rename, or an exchange with the previous export), so DIR never holds
/// a half-written export and no temporary file outlives the call. A previous export in DIR (a
/// folder of CSV files only) is replaced by a complete log's export only: the part of a damaged log
/// before its break is written when DIR is new or empty, and otherwise DIR is left as it was.

#include <atomic>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace overstep::monitor {

struct ExportSummary {
  std::int64_t events = 0;
  std::map<std::string, std::int64_t> rows;     ///< per channel
  std::map<std::string, std::string> files;     ///< per channel (empty when nothing was written)
  std::map<std::string, std::int64_t> skipped;  ///< per channel: undecodable messages
  std::int64_t break_offset = -1;               ///< -1: the whole log was read
  std::string break_reason;
  bool written = false;      ///< DIR now holds this export
  bool interrupted = false;  ///< `stop` was set: nothing written, DIR as it was
};

/// `joint_names`: names for the joint arrays (robot YAML order), or empty for indices. `stop`
/// (optional, polled between events) abandons the export. InputError when the log cannot be
/// opened, DIR is not a folder of CSV files (nothing is written then) or it cannot be written.
ExportSummary exportCsv(const std::string& log_path, const std::string& dir,
                        const std::vector<std::string>& joint_names,
                        const std::atomic<bool>* stop = nullptr);

/// The file name used for a channel, one per channel name (injective): [A-Za-z0-9_-] and '.'
/// (not first) are kept, every other byte becomes %XX ("A B" -> "A%20B.csv", "A_B" ->
/// "A_B.csv"); a name longer than 200 characters so written is cut to 183 plus '~' and a 64-bit
/// hash of the whole channel name.
std::string channelFileName(const std::string& channel);

}  // namespace overstep::monitor
