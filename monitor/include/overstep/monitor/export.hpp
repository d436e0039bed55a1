#pragma once
/// \file
/// `overstep export LOG --csv DIR`: one CSV per channel, every field a column with its unit in the
/// header ("q[RLEG_JOINT0] [rad]"), the logger's receive time first. Numbers are written so that
/// they read back bit for bit (17 significant digits). A damaged log is exported up to the break.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace overstep::monitor {

struct ExportSummary {
  std::int64_t events = 0;
  std::map<std::string, std::int64_t> rows;     ///< per channel
  std::map<std::string, std::string> files;     ///< per channel
  std::map<std::string, std::int64_t> skipped;  ///< per channel: undecodable messages
  std::int64_t break_offset = -1;               ///< -1: the whole log was read
  std::string break_reason;
};

/// `joint_names`: names for the joint arrays (robot YAML order), or empty for indices.
/// InputError when the log cannot be opened or the folder cannot be written.
ExportSummary exportCsv(const std::string& log_path, const std::string& dir,
                        const std::vector<std::string>& joint_names);

/// The file name used for a channel (characters other than [A-Za-z0-9_.-] become '_').
std::string channelFileName(const std::string& channel);

}  // namespace overstep::monitor
