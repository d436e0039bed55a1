// Monitoring library: log reading and damaged logs, decoding, CSV export round trip, rates.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "log_fixtures.hpp"
#include "overstep/core/error.hpp"
#include "overstep/monitor/export.hpp"
#include "overstep/monitor/lcm_log.hpp"
#include "overstep/monitor/messages.hpp"
#include "overstep/monitor/monitor.hpp"
#include "overstep/monitor/plan_match.hpp"
#include "test_util.hpp"

namespace overstep {
namespace {

using test::SyntheticLog;
using test::TempDir;

/// Minimal CSV reader (our files: quoted text fields may hold commas and doubled quotes).
std::vector<std::vector<std::string>> readCsv(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::string cur;
    bool q = false;
    for (std::size_t i = 0; i < line.size(); ++i) {
      const char c = line[i];
      if (q) {
        if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
          cur += '"';
          ++i;
        } else if (c == '"') {
          q = false;
        } else {
          cur += c;
        }
      } else if (c == '"') {
        q = true;
      } else if (c == ',') {
        f.push_back(cur);
        cur.clear();
      } else {
        cur += c;
      }
    }
    f.push_back(cur);
    rows.push_back(f);
  }
  return rows;
}

int column(const std::vector<std::string>& header, const std::string& name) {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return static_cast<int>(i);
  return -1;
}

void truncateFile(const std::string& path, std::int64_t size) {
  std::filesystem::resize_file(path, static_cast<std::uintmax_t>(size));
}

TEST(MonitorLog, ReadsEveryEventWithItsOffset) {
  TempDir dir;
  const SyntheticLog log = test::writeSyntheticLog(dir.file("a.lcmlog"), 1.0, 7);
  monitor::LogReader r(dir.file("a.lcmlog"));
  monitor::LogEvent ev;
  std::size_t i = 0;
  while (r.next(ev)) {
    ASSERT_LT(i, log.events.size());
    EXPECT_EQ(ev.offset, log.events[i].offset);
    EXPECT_EQ(ev.timestamp, log.events[i].timestamp);
    EXPECT_EQ(ev.channel, log.events[i].channel);
    ASSERT_EQ(ev.size, static_cast<int>(log.events[i].data.size()));
    EXPECT_EQ(0, std::memcmp(ev.data, log.events[i].data.data(), log.events[i].data.size()));
    ++i;
  }
  EXPECT_EQ(i, log.events.size());
  EXPECT_FALSE(r.broken());
}

TEST(MonitorLog, MissingFileIsBadInput) {
  EXPECT_THROW(monitor::LogReader("/nonexistent/x.lcmlog"), InputError);
}

/// An lcm-logger event header (big-endian): sync word, event number, time, lengths.
std::string eventHeader(std::int32_t channel_len, std::int32_t data_len) {
  std::string h;
  const auto put = [&h](std::uint64_t v, int bytes) {
    for (int i = bytes - 1; i >= 0; --i) h += static_cast<char>((v >> (8 * i)) & 0xff);
  };
  put(0xEDA1DA01u, 4);
  put(0, 8);
  put(1'700'000'000'000'000, 8);
  put(static_cast<std::uint32_t>(channel_len), 4);
  put(static_cast<std::uint32_t>(data_len), 4);
  return h;
}

// Issue 20: liblcm allocates the declared data length + 1 before reading; 0x7fffffff overflowed
// to a failed calloc and a write through the null pointer (SIGSEGV in export, monitor, identify,
// report). Now a break at the event, naming the lengths.
TEST(MonitorLog, A32ByteLogDeclaringTwoGigabytesIsABreakNotACrash) {
  TempDir dir;
  test::writeText(dir.path() / "a.lcmlog", eventHeader(1, 0x7fffffff) + "A" + "xyz");
  ASSERT_EQ(std::filesystem::file_size(dir.file("a.lcmlog")), 32u);
  monitor::LogReader r(dir.file("a.lcmlog"));
  monitor::LogEvent ev;
  EXPECT_FALSE(r.next(ev));
  EXPECT_TRUE(r.broken());
  EXPECT_EQ(r.breakOffset(), 0);
  EXPECT_NE(r.breakReason().find("data length (2147483647, at most 67108864)"), std::string::npos)
      << r.breakReason();
  for (const std::int32_t data : {-5, 0x7fffffff}) {
    test::writeText(dir.path() / "b.lcmlog", eventHeader(1, data) + "A" + "xyz");
    monitor::LogReader b(dir.file("b.lcmlog"));
    EXPECT_FALSE(b.next(ev));
    EXPECT_EQ(b.breakOffset(), 0);
  }
  test::writeText(dir.path() / "c.lcmlog", eventHeader(1, 100) + "A" + "xyz");
  monitor::LogReader c(dir.file("c.lcmlog"));
  EXPECT_FALSE(c.next(ev));
  EXPECT_NE(c.breakReason().find("truncated event: it needs 129 bytes, the file has 32 left"),
            std::string::npos)
      << c.breakReason();
}

// The same length after intact events, in a (sparse) file long enough to hold it: refused by the
// 64 MiB cap, the events before it read.
TEST(MonitorLog, AnEventLongerThanTheCapIsABreakAtItsOffset) {
  TempDir dir;
  const SyntheticLog log = test::writeSyntheticLog(dir.file("a.lcmlog"), 0.1, 3);
  const auto bad = static_cast<std::int64_t>(std::filesystem::file_size(dir.file("a.lcmlog")));
  {
    std::ofstream f(dir.file("a.lcmlog"), std::ios::app | std::ios::binary);
    f << eventHeader(14, 0x7fffffff) << "OVERSTEP_STATE";
  }
  std::filesystem::resize_file(dir.file("a.lcmlog"), (std::uintmax_t{1} << 31) + 4096);
  monitor::LogReader r(dir.file("a.lcmlog"));
  monitor::LogEvent ev;
  std::size_t n = 0;
  while (r.next(ev)) ++n;
  EXPECT_EQ(n, log.events.size());
  EXPECT_EQ(r.breakOffset(), bad);
  EXPECT_NE(r.breakReason().find("data length (2147483647"), std::string::npos) << r.breakReason();
}

long peakRssKb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

// Issue 20: the generated decoders resize the joint arrays to the declared count before reading
// them: a negative count threw std::length_error (exit 1), 2^26 joints in a 1 kB event allocated
// 512 MB. Now Malformed before anything is allocated (and the count's offset is the right one: a
// valid message still decodes).
TEST(MonitorDecode, JointCountsTheBytesCannotHoldAreMalformedBeforeAllocating) {
  struct Case {
    std::vector<std::uint8_t> bytes;
    int at;  // offset of num_joints
  };
  for (Case c : {Case{test::encodeMsg(test::makeState(30)), 32},
                 Case{test::encodeMsg(test::makeCommand(30)), 24}}) {
    monitor::AnyMessage m;
    ASSERT_EQ(monitor::decode(c.bytes.data(), static_cast<int>(c.bytes.size()), m),
              monitor::DecodeStatus::Ok);
    ASSERT_EQ(c.bytes[static_cast<std::size_t>(c.at) + 3], 30);  // big-endian int32 30
    const long before = peakRssKb();
    for (const std::uint32_t n : {0xffffffffu, 0x80000000u, 0x7fffffffu, 1u << 26}) {
      for (int i = 0; i < 4; ++i)
        c.bytes[static_cast<std::size_t>(c.at + i)] = static_cast<std::uint8_t>(n >> (24 - 8 * i));
      EXPECT_EQ(monitor::decode(c.bytes.data(), static_cast<int>(c.bytes.size()), m),
                monitor::DecodeStatus::Malformed)
          << n;
    }
    EXPECT_LT(peakRssKb() - before, 64 * 1024) << "kB allocated for a 1 kB message";
  }
}

TEST(MonitorDecode, KnowsOurTypesAndRejectsOthers) {
  monitor::AnyMessage m;
  const auto st = test::encodeMsg(test::makeState(30));
  ASSERT_EQ(monitor::decode(st.data(), static_cast<int>(st.size()), m), monitor::DecodeStatus::Ok);
  EXPECT_EQ(monitor::typeName(m), "robot_state_t");
  const auto ss = test::encodeMsg(test::makeSimStatus());
  ASSERT_EQ(monitor::decode(ss.data(), static_cast<int>(ss.size()), m), monitor::DecodeStatus::Ok);
  EXPECT_EQ(monitor::typeName(m), "sim_status_t");
  const std::uint8_t junk[12] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  EXPECT_EQ(monitor::decode(junk, 12, m), monitor::DecodeStatus::UnknownType);
  // Our fingerprint, but cut short: malformed.
  EXPECT_EQ(monitor::decode(st.data(), static_cast<int>(st.size()) - 9, m),
            monitor::DecodeStatus::Malformed);
}

TEST(MonitorDecode, FlattensEveryFieldWithUnits) {
  std::vector<monitor::Cell> cells;
  monitor::AnyMessage m = test::makeState(30);
  std::vector<std::string> names;
  for (int i = 0; i < 30; ++i) names.push_back("J" + std::to_string(i));
  monitor::flatten(m, names, cells);
  // utime, seq, last_command_seq, num_joints, 3 x 30 joints, 2 x 6 F/T, 4 + 3 + 3 IMU,
  // has_ground_truth, 3 + 4 + 3 + 3 base.
  EXPECT_EQ(cells.size(), 4u + 90u + 12u + 10u + 1u + 13u);
  bool found = false;
  for (const auto& c : cells)
    if (c.name == "q[J3]") {
      found = true;
      EXPECT_EQ(c.unit, "rad");
    }
  EXPECT_TRUE(found);
  for (const auto& c : cells) {
    if (c.name == "ft_left[Mz]") {
      EXPECT_EQ(c.unit, "N m");
    }
  }
  monitor::flatten(m, {}, cells);  // no names: indices
  EXPECT_EQ(cells[4].name, "q[0]");
}

TEST(MonitorExport, CsvRoundTripsEveryValueExactly) {
  TempDir dir;
  const SyntheticLog log = test::writeSyntheticLog(dir.file("a.lcmlog"), 0.5, 11);
  const auto sum = monitor::exportCsv(dir.file("a.lcmlog"), dir.file("csv"), {});
  EXPECT_EQ(sum.break_offset, -1);
  EXPECT_EQ(sum.events, static_cast<std::int64_t>(log.events.size()));
  EXPECT_EQ(sum.skipped.at("OTHER_TOOL"), 1);
  ASSERT_EQ(sum.rows.at("OVERSTEP_STATE"), static_cast<std::int64_t>(log.states.size()));
  const auto rows = readCsv(sum.files.at("OVERSTEP_STATE"));
  ASSERT_EQ(rows.size(), log.states.size() + 1);
  const auto& h = rows[0];
  EXPECT_EQ(h[0], "log_time [us]");
  const int utime = column(h, "utime [us]"), q7 = column(h, "q[7] [rad]"),
            fz = column(h, "ft_right[Fz] [N]");
  ASSERT_GE(utime, 0);
  ASSERT_GE(q7, 0);
  ASSERT_GE(fz, 0);
  for (std::size_t k = 0; k < log.states.size(); ++k) {
    const auto& r = rows[k + 1];
    EXPECT_EQ(std::stoll(r[static_cast<std::size_t>(utime)]), log.states[k].utime);
    EXPECT_EQ(std::strtod(r[static_cast<std::size_t>(q7)].c_str(), nullptr), log.states[k].q[7]);
    EXPECT_EQ(std::strtod(r[static_cast<std::size_t>(fz)].c_str(), nullptr),
              log.states[k].ft_right[2]);
  }
  const auto rt = readCsv(sum.files.at("OVERSTEP_RUNTIME"));
  const int reason = column(rt[0], "fault_reason");
  ASSERT_GE(reason, 0);
  EXPECT_EQ(rt[1][static_cast<std::size_t>(reason)], log.statuses[0].fault_reason);
}

TEST(MonitorExport, TruncatedLogExportsEverythingBeforeTheBreak) {
  TempDir dir;
  const SyntheticLog log = test::writeSyntheticLog(dir.file("a.lcmlog"), 0.5, 3);
  const std::size_t cut = log.events.size() * 2 / 3;
  truncateFile(dir.file("a.lcmlog"), log.events[cut].offset + 30);  // inside event `cut`
  const auto sum = monitor::exportCsv(dir.file("a.lcmlog"), dir.file("csv"), {});
  EXPECT_EQ(sum.break_offset, log.events[cut].offset);
  EXPECT_EQ(sum.events, static_cast<std::int64_t>(cut));
  std::int64_t states = 0;
  for (std::size_t i = 0; i < cut; ++i) states += log.events[i].channel == "OVERSTEP_STATE";
  EXPECT_EQ(sum.rows.at("OVERSTEP_STATE"), states);
  EXPECT_EQ(readCsv(sum.files.at("OVERSTEP_STATE")).size(), static_cast<std::size_t>(states + 1));
}

TEST(MonitorExport, CorruptSyncWordIsReportedAtItsOffset) {
  TempDir dir;
  const SyntheticLog log = test::writeSyntheticLog(dir.file("a.lcmlog"), 0.5, 5);
  const std::size_t bad = log.events.size() / 3;
  {
    std::fstream f(dir.file("a.lcmlog"), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(log.events[bad].offset);
    f.write("XXXX", 4);  // the sync word of event `bad`
  }
  const auto sum = monitor::exportCsv(dir.file("a.lcmlog"), dir.file("csv"), {});
  // liblcm 1.3 refuses an event that is not followed by a valid header: the break is the event
  // before the damaged one, and the reason names the damaged byte.
  EXPECT_EQ(sum.break_offset, log.events[bad - 1].offset);
  EXPECT_EQ(sum.events, static_cast<std::int64_t>(bad - 1));
  EXPECT_NE(sum.break_reason.find(std::to_string(log.events[bad].offset)), std::string::npos)
      << sum.break_reason;
}

/// Writes one OVERSTEP_STATE event per payload into a log at `path`; returns the file offset of
/// each event.
std::vector<std::int64_t> writeStateEvents(const std::string& path,
                                           std::vector<std::vector<std::uint8_t>> payloads) {
  std::vector<std::int64_t> offsets;
  lcm::LogFile file(path, "w");
  for (auto& data : payloads) {
    offsets.push_back(ftello(file.getFilePtr()));
    lcm::LogEvent le{};
    le.timestamp = 1;
    le.channel = "OVERSTEP_STATE";
    le.datalen = static_cast<int32_t>(data.size());
    le.data = data.data();
    file.writeEvent(&le);
  }
  return offsets;
}

TEST(MonitorExport, UndecodablePayloadOfOurTypeIsABreak) {
  TempDir dir;
  const std::string path = dir.file("a.lcmlog");
  auto cut = test::encodeMsg(test::makeState(30));
  cut.resize(cut.size() / 2);  // our fingerprint, half a message
  const std::vector<std::int64_t> at = writeStateEvents(
      path, {test::encodeMsg(test::makeState(30)), cut, test::encodeMsg(test::makeState(30))});
  const auto sum = monitor::exportCsv(path, dir.file("csv"), {});
  EXPECT_EQ(sum.break_offset, at[1]);
  EXPECT_EQ(sum.rows.at("OVERSTEP_STATE"), 1);
}

// Issue 20: a state declaring -1 joints ended export with "internal error" (std::length_error).
TEST(MonitorExport, ANegativeJointCountIsABreakAtItsEvent) {
  TempDir dir;
  const std::string path = dir.file("a.lcmlog");
  auto bad = test::encodeMsg(test::makeState(30));
  std::fill(bad.begin() + 32, bad.begin() + 36, 0xff);  // num_joints = -1
  const std::vector<std::int64_t> at =
      writeStateEvents(path, {test::encodeMsg(test::makeState(30)), bad});
  const auto sum = monitor::exportCsv(path, dir.file("csv"), {});
  EXPECT_EQ(sum.break_offset, at[1]);
  EXPECT_NE(sum.break_reason.find("does not decode"), std::string::npos) << sum.break_reason;
  EXPECT_EQ(sum.rows.at("OVERSTEP_STATE"), 1);
}

/// Every path under `root` (recursively), relative to it, sorted.
std::vector<std::string> treeOf(const std::string& root) {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::recursive_directory_iterator(root))
    out.push_back(std::filesystem::relative(e.path(), root).string());
  std::sort(out.begin(), out.end());
  return out;
}

// Issue 20: an export of a damaged log into a folder holding a complete export replaced the
// complete CSVs with partial ones and left the previous export's other files and `.csv.tmp`
// files beside them. Now the folder is replaced as a whole, by a complete log's export only.
TEST(MonitorExport, APreviousExportIsReplacedByACompleteOneOnly) {
  TempDir dir;
  const SyntheticLog log = test::writeSyntheticLog(dir.file("a.lcmlog"), 0.5, 21);
  const std::string csv = dir.file("csv");
  auto first = monitor::exportCsv(dir.file("a.lcmlog"), csv, {});
  ASSERT_TRUE(first.written);
  EXPECT_EQ(first.files.at("OVERSTEP_STATE"), csv + "/OVERSTEP_STATE.csv");
  // A file of an earlier export of another log, and an older version's temporary file: a
  // complete export replaces the folder, so neither survives it.
  test::writeText(dir.path() / "csv" / "OLD_CHANNEL.csv", "log_time [us],type\n");
  test::writeText(dir.path() / "csv" / "OVERSTEP_STATE.csv.tmp", "partial");
  first = monitor::exportCsv(dir.file("a.lcmlog"), csv, {});
  ASSERT_TRUE(first.written);
  const std::vector<std::string> complete = treeOf(csv);
  EXPECT_EQ(complete.size(), first.files.size());
  for (const auto& f : complete) EXPECT_EQ(f.find("OLD"), std::string::npos) << f;
  for (const auto& f : complete) EXPECT_EQ(f.find(".tmp"), std::string::npos) << f;
  const std::string states = test::slurp(csv + "/OVERSTEP_STATE.csv");

  // The same log cut inside an event: its part before the break does not replace the export.
  std::filesystem::copy_file(dir.file("a.lcmlog"), dir.file("cut.lcmlog"));
  std::filesystem::resize_file(
      dir.file("cut.lcmlog"),
      static_cast<std::uintmax_t>(log.events[log.events.size() / 2].offset + 30));
  const auto cut = monitor::exportCsv(dir.file("cut.lcmlog"), csv, {});
  EXPECT_GE(cut.break_offset, 0);
  EXPECT_FALSE(cut.written);
  EXPECT_TRUE(cut.files.empty());
  EXPECT_EQ(treeOf(csv), complete);
  EXPECT_EQ(test::slurp(csv + "/OVERSTEP_STATE.csv"), states);
  // Nothing is left beside the folder either (the temporary sibling is gone).
  EXPECT_EQ(treeOf(dir.path().string()).size(), complete.size() + 3u)  // a, cut, csv/
      << ::testing::PrintToString(treeOf(dir.path().string()));
  // Into a new folder (or an empty one) the part before the break is written.
  std::filesystem::create_directory(dir.file("empty"));
  for (const char* d : {"fresh", "empty"}) {
    const auto part = monitor::exportCsv(dir.file("cut.lcmlog"), dir.file(d), {});
    EXPECT_TRUE(part.written) << d;
    EXPECT_LT(part.rows.at("OVERSTEP_STATE"), first.rows.at("OVERSTEP_STATE")) << d;
    EXPECT_EQ(treeOf(dir.file(d)).size(), part.files.size()) << d;
  }
}

TEST(MonitorExport, AFolderHoldingOtherFilesIsRefusedUntouched) {
  TempDir dir;
  test::writeSyntheticLog(dir.file("a.lcmlog"), 0.2, 5);
  std::filesystem::create_directory(dir.path() / "out");
  test::writeText(dir.path() / "out" / "notes.txt", "mine");
  try {
    monitor::exportCsv(dir.file("a.lcmlog"), dir.file("out"), {});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("notes.txt"), std::string::npos) << e.what();
  }
  EXPECT_EQ(treeOf(dir.file("out")), std::vector<std::string>{"notes.txt"});
  EXPECT_EQ(treeOf(dir.path().string()).size(), 3u);  // a.lcmlog, out, out/notes.txt
  test::writeText(dir.path() / "file", "x");
  EXPECT_THROW(monitor::exportCsv(dir.file("a.lcmlog"), dir.file("file"), {}), InputError);
  // The folder this process works in (or one holding it) is never replaced.
  std::filesystem::create_directories(dir.path() / "cwd" / "inner");
  const auto before = std::filesystem::current_path();
  std::filesystem::current_path(dir.path() / "cwd" / "inner");
  EXPECT_THROW(monitor::exportCsv(dir.file("a.lcmlog"), ".", {}), InputError);
  EXPECT_THROW(monitor::exportCsv(dir.file("a.lcmlog"), "..", {}), InputError);
  EXPECT_TRUE(monitor::exportCsv(dir.file("a.lcmlog"), "csv", {}).written);  // a subfolder is fine
  std::filesystem::current_path(before);
  EXPECT_TRUE(std::filesystem::is_directory(dir.path() / "cwd" / "inner" / "csv"));
}

TEST(MonitorExport, AnInterruptedExportLeavesNothing) {
  TempDir dir;
  test::writeSyntheticLog(dir.file("a.lcmlog"), 0.2, 5);
  const std::atomic<bool> stop{true};
  const auto sum = monitor::exportCsv(dir.file("a.lcmlog"), dir.file("csv"), {}, &stop);
  EXPECT_TRUE(sum.interrupted);
  EXPECT_FALSE(sum.written);
  EXPECT_EQ(treeOf(dir.path().string()), std::vector<std::string>{"a.lcmlog"});
}

// Issue 20: "A B" and "A_B" (or any two names differing only in characters a file name cannot
// hold) were written into one CSV, their rows interleaved.
TEST(MonitorExport, ChannelNamesMapToFileNamesInjectively) {
  EXPECT_EQ(monitor::channelFileName("OVERSTEP_STATE"), "OVERSTEP_STATE.csv");
  EXPECT_EQ(monitor::channelFileName("A B"), "A%20B.csv");
  EXPECT_EQ(monitor::channelFileName("A_B"), "A_B.csv");
  EXPECT_EQ(monitor::channelFileName("A%20B"), "A%2520B.csv");
  EXPECT_EQ(monitor::channelFileName(".."), "%2E..csv");
  EXPECT_EQ(monitor::channelFileName("a/b"), "a%2Fb.csv");
  const std::string long_a(900, 'x'), long_b = std::string(899, 'x') + "y";
  const std::string fa = monitor::channelFileName(long_a), fb = monitor::channelFileName(long_b);
  EXPECT_NE(fa, fb);
  EXPECT_LE(fa.size(), 255u);
  EXPECT_LE(fb.size(), 255u);
  // Through a log: four channels whose '_' mapping was one file, each its own CSV with its row.
  TempDir dir;
  const std::string path = dir.file("a.lcmlog");
  const std::vector<std::string> channels = {"S T", "S_T", "S/T", long_a, long_b};
  {
    lcm::LogFile file(path, "w");
    for (const auto& ch : channels) {
      auto data = test::encodeMsg(test::makeState(30));
      lcm::LogEvent le{};
      le.timestamp = 1;
      le.channel = ch;
      le.datalen = static_cast<int32_t>(data.size());
      le.data = data.data();
      file.writeEvent(&le);
    }
  }
  const auto sum = monitor::exportCsv(path, dir.file("csv"), {});
  ASSERT_TRUE(sum.written);
  ASSERT_EQ(sum.files.size(), channels.size());
  EXPECT_EQ(treeOf(dir.file("csv")).size(), channels.size());
  for (const auto& ch : channels) {
    EXPECT_EQ(sum.rows.at(ch), 1);
    EXPECT_EQ(readCsv(sum.files.at(ch)).size(), 2u) << ch.substr(0, 10);
  }
}

// Issue 20: `identify` and `report` read a log against any plan given to them (and the report
// indexed the plan's phases with the log's phase index). A plan reference is checked first.
TEST(MonitorPlanMatch, APlanReferenceOfAnotherPlanIsNamed) {
  core::Plan plan;
  plan.rate = 200.0;
  plan.t = Eigen::VectorXd::LinSpaced(401, 0.0, 2.0);
  plan.phases = {{"ds_start", 0.0, 1.0, true, true}, {"ss_right_swing", 1.0, 1.0, false, true}};
  overstep::plan_reference_t ref{};
  ref.plan_duration = 2.0;
  ref.plan_time = 1.5;
  ref.phase = 1;
  ref.phase_name = "ss_right_swing";
  EXPECT_EQ(monitor::planReferenceMismatch(ref, plan), "");
  ref.plan_duration = 2.004;  // within a sample period (a re-sampled copy)
  EXPECT_EQ(monitor::planReferenceMismatch(ref, plan), "");
  auto with = [&](auto change) {
    overstep::plan_reference_t r = ref;
    change(r);
    return monitor::planReferenceMismatch(r, plan);
  };
  EXPECT_NE(
      with([](auto& r) { r.plan_duration = 5.26; }).find("of a plan of 5.26 s, the plan lasts 2 s"),
      std::string::npos);
  EXPECT_NE(with([](auto& r) { r.plan_duration = std::nan(""); }), "");
  EXPECT_NE(with([](auto& r) { r.plan_time = 2.5; }).find("plan time 2.5 s"), std::string::npos);
  EXPECT_NE(with([](auto& r) { r.plan_time = -0.1; }), "");
  EXPECT_NE(with([](auto& r) { r.plan_time = std::nan(""); }), "");
  EXPECT_NE(with([](auto& r) { r.phase = 2; }).find("phase 2, the plan has 2 phases"),
            std::string::npos);
  EXPECT_NE(with([](auto& r) { r.phase = -1; }), "");
  EXPECT_NE(
      with([](auto& r) { r.phase_name = "ds_mid"; }).find("'ds_mid', the plan 'ss_right_swing'"),
      std::string::npos);
  try {
    monitor::checkJointCount(12, 30, "OVERSTEP_STATE", "a.lcmlog", "p.json");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "a.lcmlog: OVERSTEP_STATE carries 12 joints, p.json and its robot have 30 (a run of "
              "another robot?)");
  }
  EXPECT_NO_THROW(monitor::checkJointCount(30, 30, "OVERSTEP_STATE", "a.lcmlog", "p.json"));
}

// Found by tests/fuzz/fuzz_msgs: lcm-gen's decoder copies a string's declared length - 1 bytes
// after checking only the upper bound: length 0 threw std::length_error ("internal error" in
// export), -2^31 read 2 GB past the buffer (SIGSEGV). The length is checked first, in each type
// with a string, at its offset (the intact message decodes, so the offset is the right one).
template <class T>
void expectStringLengthChecked(const T& m, const std::string& text, int at) {
  const auto good = test::encodeMsg(m);
  monitor::AnyMessage msg;
  ASSERT_EQ(monitor::decode(good.data(), static_cast<int>(good.size()), msg),
            monitor::DecodeStatus::Ok);
  std::uint32_t stored = 0;
  for (int i = 0; i < 4; ++i) stored = (stored << 8) | good[static_cast<std::size_t>(at + i)];
  ASSERT_EQ(stored, text.size() + 1) << "the string's length is not at byte " << at;
  for (const std::uint32_t len : {0u, 0x80000000u, 0xffffffffu, 0x7fffffffu, 100000u}) {
    auto bad = good;
    for (int i = 0; i < 4; ++i)
      bad[static_cast<std::size_t>(at + i)] = static_cast<std::uint8_t>(len >> (24 - 8 * i));
    EXPECT_EQ(monitor::decode(bad.data(), static_cast<int>(bad.size()), msg),
              monitor::DecodeStatus::Malformed)
        << "length " << len;
  }
}

TEST(MonitorDecode, StringLengthsAreCheckedBeforeDecoding) {
  overstep::runtime_status_t r = test::makeRuntimeStatus();
  r.fault_reason = "watchdog";
  expectStringLengthChecked(r, r.fault_reason, 25);
  overstep::plan_reference_t p{};
  p.phase_name = "ds_start";
  expectStringLengthChecked(p, p.phase_name, 44);
  overstep::stabilizer_status_t st{};
  st.fault_reason = "";
  expectStringLengthChecked(st, st.fault_reason, 37);
}

TEST(MonitorRates, MatchTheLogsTimestamps) {
  TempDir dir;
  const SyntheticLog log = test::writeSyntheticLog(dir.file("a.lcmlog"), 2.0, 13);
  monitor::Monitor mon(1.0);
  monitor::LogReader r(dir.file("a.lcmlog"));
  monitor::LogEvent ev;
  std::int64_t now = 0;
  while (r.next(ev)) {
    now = ev.timestamp;
    mon.add(ev.channel, now, ev.data, ev.size);
  }
  for (const char* ch : {"OVERSTEP_STATE", "OVERSTEP_RUNTIME"}) {
    std::int64_t n = 0, first = -1, last = 0;
    for (const auto& e : log.events) {
      if (e.channel != ch) continue;
      if (first < 0) first = e.timestamp;
      last = e.timestamp;
      ++n;
    }
    const double expected = static_cast<double>(n - 1) / (static_cast<double>(last - first) * 1e-6);
    const auto& c = mon.channels().at(ch);
    EXPECT_EQ(c.count, n);
    EXPECT_NEAR(c.meanRate(), expected, 1e-12 * expected) << ch;
  }
  // The messages' own clock: exactly the control and status rates.
  EXPECT_NEAR(mon.channels().at("OVERSTEP_STATE").messageClockRate(), log.control_rate, 1e-6);
  EXPECT_NEAR(mon.channels().at("OVERSTEP_RUNTIME").messageClockRate(), log.status_rate, 1e-6);
  EXPECT_EQ(mon.channels().at("OTHER_TOOL").undecodable, 1);
  const auto snap = mon.snapshot(now, "test");
  EXPECT_EQ(snap["channels"]["OVERSTEP_STATE"]["type"], "robot_state_t");
  EXPECT_FALSE(snap["runtime"].is_null());
  EXPECT_TRUE(snap["plan"].is_null());  // no OVERSTEP_PLAN_REF in this log
  // Window rate over the last second: 200 messages (+-1 for the jittered edges).
  EXPECT_NEAR(mon.channels().at("OVERSTEP_STATE").windowRate(now, 1.0), log.control_rate, 1.5);
  const std::string text = mon.render(now, "test");
  EXPECT_NE(text.find("OVERSTEP_STATE"), std::string::npos);
  EXPECT_NE(text.find("runtime"), std::string::npos);
}

}  // namespace
}  // namespace overstep
