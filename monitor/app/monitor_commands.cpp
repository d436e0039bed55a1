// `overstep spy`, `overstep monitor`, `overstep export` and `overstep report`.
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <nlohmann/json.hpp>
#include <thread>

#include "overstep/cli/command.hpp"
#include "overstep/cli/lcm_url.hpp"
#include "overstep/core/error.hpp"
#include "overstep/core/robot_description.hpp"
#include "overstep/monitor/export.hpp"
#include "overstep/monitor/lcm_log.hpp"
#include "overstep/monitor/monitor.hpp"
#include "overstep/monitor/report.hpp"

namespace overstep {
namespace {

namespace fs = std::filesystem;

/// JSON text of `j`. Channel names come from the log or the bus: invalid UTF-8 in them becomes
/// U+FFFD instead of failing the dump ("internal error").
std::string jsonText(const nlohmann::json& j, int indent = -1) {
  return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

double wallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
std::int64_t epochMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// ------------------------------------------------------------------------------------- spy
/// Exit code of `overstep spy` when a jar it needs is not installed (main.cpp's list).
constexpr int kExitMissingJar = 5;

struct SpyOptions {
  std::string lcm_url;
  std::string java_dir = OVERSTEP_JAVA_DIR;  // where Debian puts its jars: /usr/share/java
  bool print_classpath = false;
};

/// A jar of lcm-spy's class path is not installed (exit kExitMissingJar).
struct SpyJarMissing : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A jar lcm-spy needs and the Debian package that installs it.
struct SpyJar {
  const char* file;
  const char* package;
  bool on_class_path;  // else found through jchart2d's manifest
};

/// lcm-spy's class path: lcm.jar; jchart2d, which its message viewer and field plots draw with
/// (without it a double-click on a channel threw NoClassDefFoundError); our types. jchart2d's
/// manifest names the jars it needs (Class-Path: /usr/share/java/jide-oss.jar and
/// xmlgraphics-commons.jar), which Java then loads from there: they are checked, not listed
/// (lcm-spy loads every class of every jar listed to find the LCM types, and those two's
/// optional classes fail to load on Java 17, an error line each). The Debian jars are looked up
/// in `java_dir`, ours in the build. Throws SpyJarMissing naming the first jar missing.
std::string spyClasspath(const std::string& java_dir) {
  if (java_dir.find(':') != std::string::npos)
    throw InputError("--java-dir: a class path cannot hold ':' (" + java_dir + ")");
  static const SpyJar debian[] = {
      {"lcm.jar", "liblcm-java", true},
      {"jchart2d.jar", "libjchart2d-java", true},
      {"jide-oss.jar", "libjide-oss-java", false},
      {"xmlgraphics-commons.jar", "libxmlgraphics-commons-java", false}};
  std::string cp;
  for (const SpyJar& j : debian) {
    const std::string jar =
        (fs::path(j.on_class_path ? java_dir : "/usr/share/java") / j.file).string();
    if (!fs::is_regular_file(jar)) {
      throw SpyJarMissing(jar + ": missing, lcm-spy needs it (apt-get install " + j.package +
                          ", or tools/setup.sh)");
    }
    if (j.on_class_path) cp += (cp.empty() ? "" : ":") + jar;
  }
  if (!fs::is_regular_file(OVERSTEP_MSGS_JAR)) {
    throw SpyJarMissing(std::string(OVERSTEP_MSGS_JAR) +
                        ": missing, lcm-spy needs it for our types (build the "
                        "overstep_msgs_jar target)");
  }
  return cp + ":" + OVERSTEP_MSGS_JAR;
}

int runSpy(const SpyOptions& o) {
  cli::checkLcmUrl(o.lcm_url);  // the Java spy takes the same URLs
  std::string cp;
  try {
    cp = spyClasspath(o.java_dir);
  } catch (const SpyJarMissing& e) {
    cli::printError("spy", e.what());
    return kExitMissingJar;
  }
  if (o.print_classpath) {
    std::cout << cp << "\n";
    return kExitOk;
  }
  const char* display = std::getenv("DISPLAY");
  if (display == nullptr || *display == '\0') {
    throw InputError(
        "no display (DISPLAY is unset): lcm-spy is a Swing window; use ssh -X, or "
        "`overstep monitor` in a terminal");
  }
  if (!o.lcm_url.empty()) ::setenv("LCM_DEFAULT_URL", o.lcm_url.c_str(), 1);
  // Debian's lcm-spy wrapper passes -Xincgc, which Java 17 rejects: start the class directly.
  std::vector<char*> argv = {const_cast<char*>("java"), const_cast<char*>("-cp"),
                             const_cast<char*>(cp.c_str()), const_cast<char*>("lcm.spy.Spy"),
                             nullptr};
  ::execvp("java", argv.data());
  cli::printError("spy",
                  "cannot start java (install default-jre): " + std::string(std::strerror(errno)));
  return kExitMissingJar;
}

// ------------------------------------------------------------------------------------- monitor
struct MonitorOptions {
  std::string source;  // a log file; empty: live
  std::string lcm_url;
  bool once = false, json = false;
  double duration = 2.0;  // live --once: seconds to listen
  double speed = 1.0;     // log playback speed; 0: as fast as possible
  double interval = 0.25;
  double window = 1.0;
};

std::atomic<bool>& resized() {
  static std::atomic<bool> flag{false};
  return flag;
}
extern "C" void onWinch(int) { resized().store(true); }

/// The monitor's terminal while it redraws: the alternate screen with the cursor hidden, each
/// frame drawn in place (home, every line cut to the width and cleared to its end, the rest of
/// the screen cleared: no blank frame between two, hence no flicker), redrawn at once on a
/// resize (SIGWINCH); the keyboard unbuffered without echo so that `q` quits. Everything is put
/// back as it was on destruction, also when an error unwinds through it. Inactive (plain
/// output, no keyboard) when stdout is not a terminal.
class Terminal {
 public:
  explicit Terminal(bool active) : active_(active && ::isatty(STDOUT_FILENO) != 0) {
    if (!active_) return;
    keys_ = ::isatty(STDIN_FILENO) != 0 && ::tcgetattr(STDIN_FILENO, &saved_) == 0;
    if (keys_) {
      termios raw = saved_;
      raw.c_lflag &= ~static_cast<tcflag_t>(ICANON | ECHO);  // ISIG kept: Ctrl-C stops
      raw.c_cc[VMIN] = 0;
      raw.c_cc[VTIME] = 0;
      ::tcsetattr(STDIN_FILENO, TCSANOW, &raw);
    }
    struct sigaction sa {};
    sa.sa_handler = onWinch;
    sigemptyset(&sa.sa_mask);
    ::sigaction(SIGWINCH, &sa, &prev_winch_);
    std::fputs("\x1b[?1049h\x1b[?25l\x1b[H\x1b[2J", stdout);
    std::fflush(stdout);
  }
  ~Terminal() {
    if (!active_) return;
    std::fputs("\x1b[?25h\x1b[?1049l", stdout);
    std::fflush(stdout);
    ::sigaction(SIGWINCH, &prev_winch_, nullptr);
    if (keys_) ::tcsetattr(STDIN_FILENO, TCSANOW, &saved_);
  }
  Terminal(const Terminal&) = delete;
  Terminal& operator=(const Terminal&) = delete;

  bool active() const { return active_; }
  /// True once `q` was typed.
  bool quit() {
    if (!keys_) return false;
    char c = 0;
    while (::read(STDIN_FILENO, &c, 1) == 1)
      if (c == 'q' || c == 'Q') quit_ = true;
    return quit_;
  }
  /// The terminal was resized since the last frame.
  static bool resizedSinceLastFrame() { return resized().load(); }

  /// One frame of `text` (lines separated by '\n'): at most the terminal's rows, each cut to
  /// its columns; bytes that are not printable ASCII (channel names come from the bus) as '?'.
  void draw(const std::string& text) {
    winsize ws{};
    const bool known = ::ioctl(STDOUT_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0;
    const std::size_t cols = known ? ws.ws_col : 80, rows = known && ws.ws_row > 0 ? ws.ws_row : 24;
    std::string out = resized().exchange(false) ? "\x1b[H\x1b[2J" : "\x1b[H";
    std::size_t row = 0, begin = 0;
    while (begin < text.size() && row < rows) {
      std::size_t end = text.find('\n', begin);
      if (end == std::string::npos) end = text.size();
      std::string line = text.substr(begin, std::min(end - begin, cols));
      for (char& c : line)
        if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) c = '?';
      if (row > 0) out += "\r\n";
      // Cleared to its end unless it fills the row (the cursor then stays on the last column,
      // whose character an erase would take).
      out += line.size() < cols ? line + "\x1b[K" : line;
      ++row;
      begin = end + 1;
    }
    if (row < rows) out += "\x1b[J";  // the rows below this frame
    std::fwrite(out.data(), 1, out.size(), stdout);
    std::fflush(stdout);
  }

 private:
  bool active_ = false, keys_ = false, quit_ = false;
  termios saved_{};
  struct sigaction prev_winch_ {};
};

void show(const monitor::Monitor& m, std::int64_t now, const std::string& src, bool json,
          Terminal& term) {
  if (json) {
    std::cout << jsonText(m.snapshot(now, src)) << std::endl;
    return;
  }
  if (term.active()) {
    term.draw(m.render(now, src));
    return;
  }
  std::cout << m.render(now, src) << "\n" << std::flush;
}

int monitorLog(const MonitorOptions& o) {
  monitor::LogReader reader(o.source);
  monitor::Monitor mon(o.window);
  monitor::LogEvent ev;
  cli::StopSignals stop;
  bool quit = false;
  std::int64_t now = 0;
  {
    Terminal term(!o.once && !o.json);
    std::int64_t first = -1, last_show = std::numeric_limits<std::int64_t>::min() / 2;
    const double wall0 = wallSeconds();
    while (reader.next(ev)) {
      now = ev.timestamp;
      if (first < 0) first = now;
      if (!o.once && o.speed > 0.0) {  // play at the recorded pace
        const double due = wall0 + static_cast<double>(now - first) * 1e-6 / o.speed;
        while (wallSeconds() < due && !stop.requested() && !(quit = term.quit())) {
          if (Terminal::resizedSinceLastFrame()) show(mon, now, o.source, o.json, term);
          std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
      }
      if (stop.requested() || quit) break;
      mon.add(ev.channel, now, ev.data, ev.size);
      if (!o.once &&
          static_cast<double>(now - last_show) * 1e-6 >= o.interval * std::max(o.speed, 1.0)) {
        show(mon, now, o.source, o.json, term);
        last_show = now;
      }
    }
  }
  // The end of the log (not on q or Ctrl-C): the last snapshot stays on the normal screen.
  if (!stop.requested() && !quit && (o.once || !o.json)) {
    Terminal plain(false);
    show(mon, now, o.source, o.json, plain);
  }
  if (reader.broken()) {
    throw InputError(o.source + ": damaged at byte " + std::to_string(reader.breakOffset()) + " (" +
                     reader.breakReason() + "); shown: the " + std::to_string(reader.events()) +
                     " events before it");
  }
  return stop.requested() ? kExitInterrupted : kExitOk;
}

class LiveFeed {
 public:
  explicit LiveFeed(monitor::Monitor& m) : m_(m) {}
  void handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    m_.add(channel, rbuf->recv_utime, rbuf->data, static_cast<int>(rbuf->data_size));
  }

 private:
  monitor::Monitor& m_;
};

int monitorLive(const MonitorOptions& o) {
  cli::checkLcmUrl(o.lcm_url);
  core::StderrCapture said;  // what liblcm prints while it opens goes into the error line
  lcm::LCM lcm(o.lcm_url);
  cli::lcmOpened(lcm.good(), o.lcm_url, said);
  monitor::Monitor mon(o.window);
  LiveFeed feed(mon);
  lcm.subscribe(".*", &LiveFeed::handle, &feed);
  const std::string src = o.lcm_url.empty() ? "LCM (default URL)" : o.lcm_url;
  cli::StopSignals stop;
  {
    Terminal term(!o.once && !o.json);
    const double start = wallSeconds();
    double last_show = 0.0;
    while (!stop.requested() && !term.quit()) {
      lcm.handleTimeout(20);
      const double w = wallSeconds();
      if (o.once) {
        if (w - start >= o.duration) break;
        continue;
      }
      if (w - last_show >= o.interval || Terminal::resizedSinceLastFrame()) {
        show(mon, epochMicros(), src, o.json, term);
        last_show = w;
      }
    }
  }
  if (o.once) {
    Terminal plain(false);
    show(mon, epochMicros(), src, o.json, plain);
  }
  return o.once || !stop.requested() ? kExitOk : kExitInterrupted;
}

int runMonitor(const MonitorOptions& o) {
  if (!(o.interval > 0.0) || !(o.window > 0.0) || !(o.duration > 0.0) || !(o.speed >= 0.0))
    throw InputError("--interval, --window and --duration must be > 0, --speed >= 0");
  return o.source.empty() ? monitorLive(o) : monitorLog(o);
}

// ------------------------------------------------------------------------------------- export
struct ExportOptions {
  std::string log, dir, robot;
  bool json = false;
};

int runExport(const ExportOptions& o) {
  std::vector<std::string> joints;
  if (!o.robot.empty()) {
    const core::RobotDescription d = core::loadRobotDescription(o.robot);
    for (const auto& a : d.actuated) joints.push_back(a.name);
  }
  const cli::StopSignals stop;  // Ctrl-C / SIGTERM: the temporary folder is removed, DIR kept
  const monitor::ExportSummary s =
      monitor::exportCsv(o.log, o.dir, joints, &cli::StopSignals::flag());
  if (s.interrupted) {
    cli::printError("export", "interrupted; " + o.dir + " left as it was");
    return kExitInterrupted;
  }
  if (o.json) {
    nlohmann::json j;
    j["events"] = s.events;
    j["rows"] = s.rows;
    j["files"] = s.files;
    j["skipped"] = s.skipped;
    j["break_offset"] = s.break_offset;
    j["break_reason"] = s.break_reason;
    j["written"] = s.written;
    std::cout << jsonText(j, 2) << "\n";
  } else {
    for (const auto& [ch, n] : s.rows) {
      const auto f = s.files.find(ch);
      std::fprintf(stderr, "  %-24s %8lld rows -> %s\n", ch.c_str(), static_cast<long long>(n),
                   f == s.files.end() ? "(not written)" : f->second.c_str());
    }
    for (const auto& [ch, n] : s.skipped)
      std::fprintf(stderr, "  %-24s %8lld messages not ours or undecodable (skipped)\n", ch.c_str(),
                   static_cast<long long>(n));
  }
  if (s.break_offset >= 0) {
    throw InputError(o.log + ": damaged at byte " + std::to_string(s.break_offset) + " (" +
                     s.break_reason + "); " +
                     (s.written ? "exported the " + std::to_string(s.events) + " events before it"
                                : o.dir +
                                      " keeps its previous export (only a complete log "
                                      "replaces it; export into a new folder for the " +
                                      std::to_string(s.events) + " events before the break)"));
  }
  return kExitOk;
}

// ------------------------------------------------------------------------------------- report
struct ReportCliOptions {
  monitor::ReportOptions r;
  bool json = false;
};

int runReport(const ReportCliOptions& o) {
  monitor::checkReportOptions(o.r);
  if (!fs::is_directory(o.r.run_dir)) throw InputError(o.r.run_dir + ": no such run folder");
  std::fprintf(stderr, "report: aligning the log with the plan, drawing the figures ...\n");
  const monitor::ReportSummary s = monitor::makeReport(o.r);
  if (o.json) {
    nlohmann::json j;
    j["out_dir"] = s.out_dir;
    j["index"] = s.index_html;
    j["manifest"] = s.manifest;
    j["ticks"] = s.ticks;
    j["t_range"] = {s.t_begin, s.t_end};
    j["figures"] = s.figures;
    j["log_break_offset"] = s.log_break_offset;
    std::cout << jsonText(j, 2) << "\n";
  } else {
    std::printf("report: %d ticks (plan time %.2f .. %.2f s), %zu figures -> %s\n", s.ticks,
                s.t_begin, s.t_end, s.figures.size(), s.index_html.c_str());
  }
  if (s.log_break_offset >= 0)
    std::fprintf(stderr, "report: the log is damaged at byte %lld; figures show what came before\n",
                 s.log_break_offset);
  return kExitOk;
}

}  // namespace

void registerMonitorCommands(CLI::App& app, cli::Registry& registry) {
  auto so = std::make_shared<SpyOptions>();
  CLI::App* spy = app.add_subcommand("spy", "lcm-spy with the overstep types on its class path");
  spy->add_option("--lcm-url", so->lcm_url, "LCM URL (default: LCM_DEFAULT_URL or udpm default)");
  spy->add_option("--java-dir", so->java_dir, "Folder of the Debian jars (lcm, jchart2d, ...)")
      ->capture_default_str();
  spy->add_flag("--print-classpath", so->print_classpath,
                "Print the class path (lcm.jar, jchart2d.jar, overstep_msgs.jar) and exit");
  spy->footer(
      "Examples:\n"
      "  overstep spy                                  # live bus, default URL\n"
      "  overstep spy --lcm-url udpm://239.255.76.67:7667?ttl=0\n"
      "  lcm-logplayer --lcm-url=udpm://239.255.76.67:7700?ttl=0 runs/<run>/bus.lcmlog &\n"
      "  overstep spy --lcm-url udpm://239.255.76.67:7700?ttl=0   # a recorded run\n"
      "Double-click a channel for its fields; click a number field to plot it.\n"
      "Exit: 2 without a display (use ssh -X, or overstep monitor), 5 a jar or java is\n"
      "missing (named, with its Debian package).");
  registry.add(spy, [so] { return runSpy(*so); });

  auto mo = std::make_shared<MonitorOptions>();
  CLI::App* mon = app.add_subcommand("monitor",
                                     "Terminal view of a live bus or a log: rates, runtime, plan, "
                                     "stabilizer, simulator");
  mon->add_option("log", mo->source, "An LCM log to read instead of the live bus");
  mon->add_option("--lcm-url", mo->lcm_url, "LCM URL of the live bus");
  mon->add_flag("--once", mo->once,
                "Print one snapshot and exit (live: after --duration s; log: at its end)");
  mon->add_flag("--json", mo->json, "Snapshots as JSON (one object per line)");
  mon->add_option("--duration", mo->duration, "Live --once: seconds to listen")
      ->capture_default_str();
  mon->add_option("--speed", mo->speed, "Log playback speed (0: as fast as possible)")
      ->capture_default_str();
  mon->add_option("--interval", mo->interval, "Refresh period, s")->capture_default_str();
  mon->add_option("--window", mo->window, "Rate window, s")->capture_default_str();
  mon->footer(
      "Examples:\n"
      "  overstep monitor                              # live, default LCM URL\n"
      "  overstep monitor --lcm-url udpm://239.255.76.67:7700?ttl=0\n"
      "  overstep monitor runs/<run>/bus.lcmlog --speed 4\n"
      "  overstep monitor runs/<run>/bus.lcmlog --once --json | jq .channels\n"
      "Rates: RATE Hz over the last --window s of the receive clock; MSG Hz by the messages'\n"
      "own timestamps (robot time in a lock-step simulation). Exit 2 on a damaged log\n"
      "(the snapshot shows what came before the break).");
  registry.add(mon, [mo] { return runMonitor(*mo); });

  auto eo = std::make_shared<ExportOptions>();
  eo->robot = cli::defaultRobotPath();
  CLI::App* ex =
      app.add_subcommand("export", "Every channel of an LCM log to CSV, units in the header");
  ex->add_option("log", eo->log, "LCM log")->required();
  ex->add_option("--csv", eo->dir, "Output folder (one CSV per channel)")->required();
  ex->add_option("--robot", eo->robot, "Robot YAML naming the joint columns ('' for indices)")
      ->capture_default_str();
  ex->add_flag("--json", eo->json, "Print {events, rows, files, break_offset} as JSON");
  ex->footer(
      "Examples:\n"
      "  overstep export runs/<run>/bus.lcmlog --csv runs/<run>/csv\n"
      "  overstep export bus.lcmlog --csv out --json | jq .rows\n"
      "Columns: log_time [us] (logger receive time), type, then every field, e.g.\n"
      "'q[RLEG_JOINT0] [rad]'. File names: the channel, other bytes than [A-Za-z0-9_.-] as %XX.\n"
      "DIR is replaced as a whole at the end (written beside it first); a previous export\n"
      "in it is replaced by a complete log's only. Exit 2 on a damaged log after exporting\n"
      "what came before (into a new or empty DIR), 130 interrupted (DIR as it was).");
  registry.add(ex, [eo] { return runExport(*eo); });

  auto ro = std::make_shared<ReportCliOptions>();
  ro->r.robot = cli::defaultRobotPath();
  CLI::App* rep = app.add_subcommand("report", "Figures and an HTML page: plan vs measurement");
  rep->add_option("run_dir", ro->r.run_dir, "Run folder (plan.json + bus.lcmlog), e.g. from demo")
      ->required();
  rep->add_option("--robot", ro->r.robot, "Robot YAML")->capture_default_str();
  rep->add_option("--plan", ro->r.plan, "Plan file (default RUN_DIR/plan.json)");
  rep->add_option("--log", ro->r.log, "LCM log (default RUN_DIR/bus.lcmlog)");
  rep->add_option("--out", ro->r.out, "Output folder (default RUN_DIR/report)");
  rep->add_option("--frames", ro->r.frames, "Snapshots in the side-view sequence")
      ->capture_default_str();
  rep->add_option("--python", ro->r.python, "Python with Matplotlib")->capture_default_str();
  rep->add_option("--dpi", ro->r.dpi, "PNG resolution")->capture_default_str();
  rep->add_flag("--json", ro->json, "Print {figures, index, ticks, t_range} as JSON");
  rep->footer(
      "Examples:\n"
      "  overstep report runs/20261122-101500          # -> runs/.../report/index.html\n"
      "  overstep report runs/<run> --frames 12 --json\n"
      "Figures (docs/report.md): side-view sequence, whole-body vs table-cart ZMP, pelvis\n"
      "roll/pitch, foot wrenches, leg joints with limits, local CoP per foot.");
  registry.add(rep, [ro] { return runReport(*ro); });
}

}  // namespace overstep
