// Monitoring as a person uses it (issue 21): lcm-spy in a real X server (Xvfb) driven by xdotool,
// the report page in headless Chromium, `overstep monitor` in a real terminal (tmux). One run is
// recorded first (MonitorUiRun, the CTest fixture monitor_ui_record: `overstep demo` of a standing
// plan inside the private network namespace of netns_run.sh); the other tests use it. Screenshots
// and screen captures are kept in OVERSTEP_UI_DIR/<test>/ (printed).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include "run_cli.hpp"

namespace overstep {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

fs::path uiDir() { return fs::path(OVERSTEP_UI_DIR); }
fs::path runDir() { return uiDir() / "run"; }

/// The folder of this test's artefacts, made empty; its path is printed.
fs::path artefacts() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path d = uiDir() / (std::string(info->test_suite_name()) + "." + info->name());
  fs::remove_all(d);
  fs::create_directories(d);
  std::printf("artefacts: %s\n", d.c_str());
  return d;
}

struct Sh {
  int code = -1;
  std::string out;
};

/// `cmd` through /bin/sh, stdout captured (stderr passes through).
Sh sh(const std::string& cmd) {
  Sh r;
  FILE* p = popen(cmd.c_str(), "r");
  if (p == nullptr) return r;
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

void sleepFor(double s) { std::this_thread::sleep_for(std::chrono::duration<double>(s)); }

/// Polls `ok` every 0.1 s until it holds or `timeout` s have passed.
template <class F>
bool waitUntil(double timeout, F ok) {
  const auto t0 = std::chrono::steady_clock::now();
  while (!ok()) {
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeout)
      return false;
    sleepFor(0.1);
  }
  return true;
}

/// Background processes of one test: `exec cmd` through /bin/sh; SIGTERM, then SIGKILL after 3 s,
/// at destruction (an X server or a spy never outlives its test).
class Background {
 public:
  pid_t start(const std::string& cmd) {
    const pid_t pid = fork();
    if (pid == 0) {
      execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    pids_.push_back(pid);
    return pid;
  }
  /// SIGTERM and wait; the exit code (-signal if killed).
  int stop(pid_t pid) {
    kill(pid, SIGTERM);
    const int code = test::waitOverstep(pid, 3.0);
    pids_.erase(std::remove(pids_.begin(), pids_.end(), pid), pids_.end());
    return code;
  }
  ~Background() {
    for (auto it = pids_.rbegin(); it != pids_.rend(); ++it) {
      kill(*it, SIGTERM);
      test::waitOverstep(*it, 3.0);
    }
  }

 private:
  std::vector<pid_t> pids_;
};

/// Channel names of an LCM log, each once (the log format: big-endian header [sync, event
/// number, timestamp, channel length, data length], channel, data), and the receive time of the
/// last channel's first message after the log's first event, s.
std::set<std::string> logChannels(const std::string& path, double* last_first_seen) {
  std::ifstream in(path, std::ios::binary);
  const std::string d((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto be = [&](std::size_t at, int n) {
    std::uint64_t v = 0;
    for (int i = 0; i < n; ++i) v = (v << 8) | static_cast<unsigned char>(d[at + i]);
    return v;
  };
  std::set<std::string> out;
  std::size_t off = 0;
  std::int64_t t0 = -1;
  *last_first_seen = 0.0;
  while (off + 28 <= d.size() && be(off, 4) == 0xEDA1DA01u) {
    const auto t = static_cast<std::int64_t>(be(off + 12, 8));
    const auto cl = static_cast<std::size_t>(be(off + 20, 4)),
               dl = static_cast<std::size_t>(be(off + 24, 4));
    if (t0 < 0) t0 = t;
    if (out.insert(d.substr(off + 28, cl)).second)
      *last_first_seen = static_cast<double>(t - t0) * 1e-6;
    off += 28 + cl + dl;
  }
  return out;
}

/// OVERSTEP_STATE's mean rate in an LCM log by its receive times, Hz.
double stateRate(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string d((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto be = [&](std::size_t at, int n) {
    std::uint64_t v = 0;
    for (int i = 0; i < n; ++i) v = (v << 8) | static_cast<unsigned char>(d[at + i]);
    return v;
  };
  std::size_t off = 0;
  std::int64_t first = -1, last = -1, n = 0;
  while (off + 28 <= d.size() && be(off, 4) == 0xEDA1DA01u) {
    const auto cl = static_cast<std::size_t>(be(off + 20, 4)),
               dl = static_cast<std::size_t>(be(off + 24, 4));
    if (d.compare(off + 28, cl, "OVERSTEP_STATE") == 0 && cl == 14) {
      last = static_cast<std::int64_t>(be(off + 12, 8));
      if (first < 0) first = last;
      ++n;
    }
    off += 28 + cl + dl;
  }
  return n > 1 ? static_cast<double>(n - 1) / (static_cast<double>(last - first) * 1e-6) : 0.0;
}

/// Pixel statistics of PNGs (decoded by Debian's Matplotlib, which the report draws with, in one
/// Python): standard deviation over every channel (0 for a blank image) and, if `box` = "x y w h"
/// is given, the number of red pixels in that box (a jchart2d trace is drawn red).
struct PngStats {
  bool ok = false;
  int width = 0, height = 0;
  double stddev = 0.0;
  long red = 0;
};
std::vector<PngStats> pngStats(const std::vector<fs::path>& pngs, const std::string& box = "") {
  const std::string py =
      "import sys, json, matplotlib.image as m\n"
      "for f in sys.argv[2:]:\n"
      "  try:\n"
      "    a = m.imread(f)[:, :, :3].astype(float)\n"
      "  except Exception:\n"
      "    print('{}'); continue\n"
      "  r = {'w': a.shape[1], 'h': a.shape[0], 'std': float(a.std()), 'red': 0}\n"
      "  if sys.argv[1]:\n"
      "    x, y, w, h = map(int, sys.argv[1].split())\n"
      "    b = a[y:y + h, x:x + w]\n"
      "    r['red'] = int(((b[:, :, 0] > .75) & (b[:, :, 1] < .35) & (b[:, :, 2] < .35)).sum())\n"
      "  print(json.dumps(r))\n";
  std::string cmd = "/usr/bin/python3 -c " + quote(py) + " " + quote(box);
  for (const auto& p : pngs) cmd += " " + quote(p.string());
  const Sh r = sh(cmd);
  std::vector<PngStats> out(pngs.size());
  std::stringstream ss(r.out);
  std::string line;
  for (std::size_t i = 0; i < pngs.size() && std::getline(ss, line); ++i) {
    const json j = json::parse(line, nullptr, false);
    if (!j.is_object() || !j.contains("w")) continue;
    out[i] = {true, j["w"], j["h"], j["std"], j["red"]};
  }
  return out;
}
PngStats pngStats(const fs::path& png, const std::string& box = "") {
  return pngStats(std::vector<fs::path>{png}, box)[0];
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string l;
  while (std::getline(ss, l)) out.push_back(l);
  return out;
}

// ------------------------------------------------------------------------------ the recorded run
TEST(MonitorUiRun, RecordsADemoRunOfAStandingPlan) {
  if (!std::getenv("OVERSTEP_NETNS")) GTEST_SKIP() << "run through netns_run.sh";
  fs::remove_all(runDir());
  fs::create_directories(uiDir());
  const std::string plan = (uiDir() / "stand.json").string();
  const auto p = test::runOverstep("plan --stand 1.5 --out " + plan);
  ASSERT_EQ(p.code, 0) << p.err;
  // Not cleared (the robot stands before the bar): exit 4; the run is what the tests use.
  const auto d = test::runOverstep("demo --plan " + plan +
                                   " --obstacle-height 0.05 --no-report --json --timeout 60 "
                                   "--run-dir " +
                                   runDir().string());
  ASSERT_TRUE(d.code == 0 || d.code == 4) << d.err;
  EXPECT_TRUE(fs::is_regular_file(runDir() / "bus.lcmlog"));
  EXPECT_TRUE(fs::is_regular_file(runDir() / "verdict.json"));
  std::printf("run: %s (%.1f s)\n", runDir().c_str(), d.seconds);
}

class RecordedRun : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::is_regular_file(runDir() / "bus.lcmlog"))
        << runDir() << ": no recorded run (the CTest fixture monitor_ui_record makes it)";
  }
  static std::string log() { return (runDir() / "bus.lcmlog").string(); }
};

// ------------------------------------------------------------------------------ lcm-spy in Xvfb
/// An X server on a free display (Xvfb -displayfd), for one test.
class Xvfb {
 public:
  Xvfb(Background& bg, const fs::path& dir) {
    const fs::path fd = dir / "xvfb.display";
    bg.start("Xvfb -displayfd 3 -screen 0 1280x800x24 -nolisten tcp 3>" + fd.string() + " 2>" +
             (dir / "xvfb.err").string());
    waitUntil(10.0, [&] { return fs::exists(fd) && fs::file_size(fd) > 0; });
    std::string n = test::slurp(fd.string());
    while (!n.empty() && (n.back() == '\n' || n.back() == ' ')) n.pop_back();
    if (!n.empty()) display_ = ":" + n;
  }
  const std::string& display() const { return display_; }
  /// The visible top-level window named exactly `name` (xdotool), 0 if none.
  long window(const std::string& name) const {
    const Sh r = sh(env() + "xdotool search --onlyvisible --name " + quote("^" + name + "$") +
                    " 2>/dev/null");
    return r.code == 0 && !r.out.empty() ? std::stol(r.out) : 0;
  }
  /// Names of the visible windows.
  std::string windows() const {
    return sh(env() + "xdotool search --onlyvisible --name . getwindowname %@ 2>/dev/null").out;
  }
  /// x, y, width, height of a window.
  std::array<int, 4> geometry(long w) const {
    const Sh r = sh(env() + "xdotool getwindowgeometry --shell " + std::to_string(w));
    std::array<int, 4> g{-1, -1, -1, -1};
    const char* keys[] = {"X=", "Y=", "WIDTH=", "HEIGHT="};
    for (const std::string& l : lines(r.out))
      for (int i = 0; i < 4; ++i)
        if (l.rfind(keys[i], 0) == 0)
          g[static_cast<std::size_t>(i)] = std::stoi(l.substr(l.find('=') + 1));
    return g;
  }
  void click(int x, int y, int times) const {
    sh(env() + "xdotool mousemove --sync " + std::to_string(x) + " " + std::to_string(y) +
       " click --repeat " + std::to_string(times) + " --delay 80 1");
  }
  /// The whole screen as a PNG (ImageMagick's import).
  bool screenshot(const fs::path& png) const {
    return sh(env() + "import -window root " + quote(png.string())).code == 0 &&
           fs::is_regular_file(png);
  }

 private:
  std::string env() const { return "DISPLAY=" + display_ + " "; }
  std::string display_;
};

// lcm-spy's table of channels (lcm/spy/Spy.java, Debian's liblcm-java 1.3.1): the "LCM Spy" frame
// (800 x 600 at the origin: Xvfb runs no window manager) holds the column header, 20 px, then one
// row of 16 px per channel, sorted by name. A double-click on a row opens that channel's message
// viewer, a frame titled with the channel (ObjectPanel). In the viewer each message is a section
// whose header row is drawn at y 7..22 and each field a row of 15 px below it (robot_state_t's
// first field, utime, at y 22..37); a click on a number field's row opens a chart of it
// (ZoomableChartScrollWheel.newChartFrame), a frame titled with the field's name.
constexpr int kSpyHeader = 20, kSpyRow = 16, kViewerFirstField = 30;

class SpyUi : public RecordedRun {};

TEST_F(SpyUi, ViewerOpensOnADoubleClickAndPlotsAField) {
  if (!std::getenv("OVERSTEP_NETNS")) GTEST_SKIP() << "run through netns_run.sh";
  const fs::path out = artefacts();
  Background bg;
  Xvfb x(bg, out);
  ASSERT_FALSE(x.display().empty()) << test::slurp((out / "xvfb.err").string());
  setenv("DISPLAY", x.display().c_str(), 1);
  const std::string url = "udpm://239.255.76.67:7811?ttl=0";
  const fs::path spy_out = out / "spy.stdout", spy_err = out / "spy.stderr";
  const pid_t spy = bg.start(std::string(OVERSTEP_BIN) + " spy --lcm-url " + quote(url) + " >" +
                             spy_out.string() + " 2>" + spy_err.string());
  long main_win = 0;
  ASSERT_TRUE(waitUntil(30.0, [&] { return (main_win = x.window("LCM Spy")) != 0; }))
      << "no LCM Spy window; spy stderr:\n"
      << test::slurp(spy_err.string());

  double all_seen = 0.0;
  const std::set<std::string> channels = logChannels(log(), &all_seen);
  ASSERT_TRUE(channels.count("OVERSTEP_STATE"));
  const int row =
      static_cast<int>(std::distance(channels.begin(), channels.find("OVERSTEP_STATE")));
  const pid_t player = bg.start("lcm-logplayer " + quote("--lcm-url=" + url) + " " + quote(log()) +
                                " >" + (out / "logplayer.out").string() + " 2>&1");
  sleepFor(all_seen + 1.0);  // every channel of the log has its row
  EXPECT_TRUE(x.screenshot(out / "spy_channels.png"));

  const auto g = x.geometry(main_win);
  long viewer = 0;
  // The row a person double-clicks: in the Channel column, the middle of OVERSTEP_STATE's row;
  // again if nothing opened (as a person would, when a loaded machine took the two clicks for
  // two single ones).
  bool opened = false;
  for (int attempt = 0; attempt < 2 && !opened; ++attempt) {
    x.click(g[0] + 80, g[1] + kSpyHeader + kSpyRow * row + kSpyRow / 2, 2);
    opened = waitUntil(5.0, [&] { return (viewer = x.window("OVERSTEP_STATE")) != 0; });
  }
  EXPECT_TRUE(opened) << "no message viewer after a double-click on OVERSTEP_STATE; windows:\n"
                      << x.windows() << "spy stderr:\n"
                      << test::slurp(spy_err.string());
  sleepFor(0.5);
  EXPECT_TRUE(x.screenshot(out / "spy_viewer.png"));

  long chart = 0;
  if (viewer != 0) {
    const auto v = x.geometry(viewer);
    x.click(v[0] + 60, v[1] + kViewerFirstField, 1);
    EXPECT_TRUE(waitUntil(10.0, [&] { return (chart = x.window("utime")) != 0; }))
        << "no chart after a click on the field utime; windows:\n"
        << x.windows();
    sleepFor(1.0);  // the chart follows the messages still playing
  }
  EXPECT_TRUE(x.screenshot(out / "spy_plot.png"));
  if (chart != 0) {
    // The chart holds a trace: red points and lines (jchart2d's first trace colour).
    const auto c = x.geometry(chart);
    const PngStats s =
        pngStats(out / "spy_plot.png", std::to_string(c[0]) + " " + std::to_string(c[1]) + " " +
                                           std::to_string(c[2]) + " " + std::to_string(c[3]));
    ASSERT_TRUE(s.ok);
    EXPECT_GT(s.red, 200) << "the chart of utime shows no trace";
  }
  bg.stop(player);
  bg.stop(spy);
  // No exception anywhere: Swing prints uncaught ones on stderr, lcm-spy some on stdout.
  for (const fs::path& f : {spy_err, spy_out}) {
    const std::string text = test::slurp(f.string());
    EXPECT_EQ(text.find("Exception"), std::string::npos) << f << ":\n" << text;
    EXPECT_EQ(text.find("Error"), std::string::npos) << f << ":\n" << text;
  }
}

// ------------------------------------------------------------------------ the report in Chromium
class ReportPage : public RecordedRun {};

/// `chromium --headless` with the flags a container needs (no sandbox as root, no GPU).
std::string chromium(const std::string& args) {
  return "timeout 60 chromium --headless --no-sandbox --disable-gpu --hide-scrollbars "
         "--no-first-run --disable-extensions --user-data-dir=" +
         quote((uiDir() / "chromium-profile").string()) + " " + args + " 2>/dev/null";
}

TEST_F(ReportPage, OpensWithEveryFigureAndTheVerdictAtTheTop) {
  const fs::path out = artefacts();
  const auto r = test::runOverstep("report " + runDir().string() + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const json s = json::parse(r.out);
  const fs::path index = s["index"].get<std::string>();
  const json man = json::parse(test::slurp(s["manifest"].get<std::string>()));
  const json verdict = json::parse(test::slurp((runDir() / "verdict.json").string()));
  std::printf("page: %s\n", index.c_str());

  // Every <img> of the page is a file beside it holding a PNG that is not blank.
  const std::string page = test::slurp(index.string());
  const std::regex img_re("<img src='([^']+)'");
  std::vector<std::string> imgs;
  for (std::sregex_iterator it(page.begin(), page.end(), img_re), end; it != end; ++it)
    imgs.push_back((*it)[1]);
  ASSERT_EQ(imgs.size(), man["figures"].size());
  std::vector<fs::path> pngs;
  for (const std::string& src : imgs) {
    pngs.push_back(index.parent_path() / src);
    ASSERT_TRUE(fs::is_regular_file(pngs.back())) << src;
  }
  const std::vector<PngStats> stats = pngStats(pngs);
  for (std::size_t i = 0; i < imgs.size(); ++i) {
    ASSERT_TRUE(stats[i].ok) << imgs[i] << ": not a PNG";
    EXPECT_GT(stats[i].width, 100) << imgs[i];
    EXPECT_GT(stats[i].stddev, 0.05) << imgs[i] << ": blank";
  }

  // The page as the browser has it after loading: a copy with a <base> at the report folder
  // and a script that writes, on load, what the browser made of each image and where the
  // verdict is on the screen into the DOM that --dump-dom prints.
  const std::string probe =
      test::replaceOnce(page, "<title>",
                        "<base href='file://" + index.parent_path().string() + "/'><title>") +
      "<script>addEventListener('load', () => {"
      " for (const i of document.images) {"
      "  i.dataset.complete = i.complete; i.dataset.naturalWidth = i.naturalWidth; }"
      " const v = document.getElementById('verdict');"
      " document.body.dataset.verdictBottom = v ? v.getBoundingClientRect().bottom : -1;"
      " document.body.dataset.viewport = innerHeight; });</script>\n";
  const fs::path probe_html = out / "probe.html";
  test::writeText(probe_html, probe);
  const Sh dom = sh(chromium("--window-size=1100,1000 --virtual-time-budget=5000 --dump-dom " +
                             quote("file://" + probe_html.string())));
  ASSERT_EQ(dom.code, 0) << "chromium failed";
  test::writeText(out / "dom.html", dom.out);
  const std::regex loaded_re(
      "<img src=\"([^\"]+)\"[^>]*data-complete=\"true\"[^>]*data-natural-width=\"([0-9]+)\"");
  std::map<std::string, int> widths;
  for (std::sregex_iterator it(dom.out.begin(), dom.out.end(), loaded_re), end; it != end; ++it)
    widths[(*it)[1]] = std::stoi((*it)[2]);
  for (const std::string& src : imgs) {
    ASSERT_TRUE(widths.count(src)) << src << " did not load in the browser (" << out / "dom.html"
                                   << ")";
    EXPECT_GT(widths[src], 100) << src << " is a broken image in the browser";
  }

  // The verdict and the fidelity metrics open the page: before the first figure, within the
  // first screen.
  std::smatch m;
  ASSERT_TRUE(std::regex_search(dom.out, m,
                                std::regex("data-verdict-bottom=\"([-0-9.]+)\"[^>]*"
                                           "data-viewport=\"([0-9.]+)\"")));
  EXPECT_GT(std::stod(m[1]), 0.0) << "no verdict section";
  EXPECT_LE(std::stod(m[1]), std::stod(m[2])) << "the verdict is not on the first screen";
  const auto verdict_at = dom.out.find("id=\"verdict\"");
  ASSERT_NE(verdict_at, std::string::npos);
  EXPECT_LT(verdict_at, dom.out.find("<img"));
  const std::string top = dom.out.substr(verdict_at, dom.out.find("</section>") - verdict_at);
  const bool cleared = verdict["cleared"].get<bool>();
  EXPECT_NE(top.find(cleared ? "<b>CLEARED</b>" : "<b>NOT CLEARED</b>"), std::string::npos) << top;
  // The standing robot never passes the bar: the demo's reason.
  if (!cleared && !verdict["fell"].get<bool>() && !verdict["obstacle_contact"].get<bool>() &&
      verdict["finished"].get<bool>()) {
    EXPECT_NE(top.find("a foot did not get past the obstacle"), std::string::npos) << top;
  }
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4f rad", verdict["tracking_rms"].get<double>());
  EXPECT_NE(top.find(buf), std::string::npos) << "tracking RMS " << buf << " not shown";
  std::snprintf(buf, sizeof buf, "%.4f rad", verdict["stabilizer_effort"].get<double>());
  EXPECT_NE(top.find(buf), std::string::npos) << "stabilizer effort " << buf << " not shown";
  // The execution's figures (data/fidelity.json, issue 19) in the table at the top, each value
  // as the file has it.
  ASSERT_TRUE(man.contains("fidelity") && man["fidelity"].is_object());
  const json& rc = man["fidelity"]["feet"]["right"]["contact_losses"];
  EXPECT_NE(top.find("id=\"fidelity\""), std::string::npos);
  std::snprintf(buf, sizeof buf, "%g ", rc["value"].get<double>());
  EXPECT_NE(top.find(buf), std::string::npos) << "right contact losses " << buf << " not shown";
  // Tracking: every metric of the manifest in the table, the ZMP one recomputed here from the
  // aligned ticks (measured - stabilizer reference).
  ASSERT_TRUE(man.contains("tracking"));
  std::set<std::string> keys;
  for (const auto& f : man["tracking"]) {
    keys.insert(f["key"].get<std::string>());
    std::snprintf(buf, sizeof buf, "%.2f %s", f["rms"].get<double>(),
                  f["unit"].get<std::string>().c_str());
    EXPECT_NE(top.find(buf), std::string::npos) << f["key"] << " RMS " << buf << " not shown";
  }
  EXPECT_EQ(keys, (std::set<std::string>{"zmp", "leg_joints", "pelvis", "right_fz", "left_fz"}));
  {
    std::ifstream csv((index.parent_path() / "data" / "ticks.csv").string());
    std::string header, row;
    std::getline(csv, header);
    std::map<std::string, int> col;
    int k = 0;
    std::stringstream hs(header);
    for (std::string name; std::getline(hs, name, ',');) col[name] = k++;
    double sum = 0.0;
    int n = 0;
    while (std::getline(csv, row)) {
      std::vector<double> v;
      std::stringstream rs(row);
      for (std::string cell; std::getline(rs, cell, ',');) v.push_back(std::atof(cell.c_str()));
      const double ex = v[static_cast<std::size_t>(col["zmp_meas_x"])] -
                        v[static_cast<std::size_t>(col["zmp_ref_x"])];
      const double ey = v[static_cast<std::size_t>(col["zmp_meas_y"])] -
                        v[static_cast<std::size_t>(col["zmp_ref_y"])];
      sum += ex * ex + ey * ey;
      ++n;
    }
    ASSERT_GT(n, 100);
    for (const auto& f : man["tracking"])
      if (f["key"] == "zmp") {
        EXPECT_NEAR(f["rms"].get<double>(), 1e3 * std::sqrt(sum / n), 1e-3);
      }
  }

  // What a reader sees: the top of the page.
  const fs::path shot = out / "report_page.png";
  sh(chromium("--window-size=1100,1300 --screenshot=" + quote(shot.string()) + " " +
              quote("file://" + index.string())));
  const PngStats st = pngStats(shot);
  ASSERT_TRUE(st.ok) << "no screenshot";
  EXPECT_GT(st.stddev, 0.05);
}

// ------------------------------------------------------------------ overstep monitor in tmux
/// A tmux server of its own (a socket of its own, so that it runs inside this network namespace:
/// in /tmp, a socket's path is at most 107 bytes) with one window running `script`.
class Tmux {
 public:
  Tmux(const fs::path& dir, const std::string& script, int cols, int rows)
      : sock_("/tmp/overstep-tmux-" + std::to_string(getpid()) + "-" +
              std::to_string(std::random_device{}() % 100000) + ".sock") {
    const fs::path file = dir / "pane.sh";
    test::writeText(file, script);
    code_ = sh(tmux() + "-f /dev/null new-session -d -s mon -x " + std::to_string(cols) + " -y " +
               std::to_string(rows) + " " + quote("bash --norc --noprofile " + file.string()))
                .code;
  }
  ~Tmux() {
    sh(tmux() + "kill-server 2>/dev/null");
    std::error_code ec;
    fs::remove(sock_, ec);
  }
  bool ok() const { return code_ == 0; }
  /// The screen, wrapped lines joined (a line longer than the width stays one line).
  std::string capture() const { return sh(tmux() + "capture-pane -p -J -t mon").out; }
  std::string format(const std::string& f) const {
    std::string s = sh(tmux() + "display -p -t mon " + quote(f)).out;
    while (!s.empty() && s.back() == '\n') s.pop_back();
    return s;
  }
  void resize(int cols, int rows) const {
    sh(tmux() + "resize-window -t mon -x " + std::to_string(cols) + " -y " + std::to_string(rows));
  }
  void keys(const std::string& k) const { sh(tmux() + "send-keys -t mon " + k); }

 private:
  std::string tmux() const { return "env -u TMUX tmux -S " + quote(sock_) + " "; }
  std::string sock_;
  int code_ = -1;
};

/// The pane's script: the monitor between two `stty -g`, its exit status into a file, then the
/// shell stays (the restored screen can be captured).
std::string paneScript(const fs::path& dir, const std::string& args) {
  return "stty -g > " + (dir / "stty.before").string() + "\n" + std::string(OVERSTEP_BIN) +
         " monitor " + args + "\necho \"exit $?\" > " + (dir / "exit.tmp").string() + "; mv " +
         (dir / "exit.tmp").string() + " " + (dir / "exit").string() + "\nstty -g > " +
         (dir / "stty.after").string() + "\necho 'shell prompt'\nexec sleep 120\n";
}

/// One screen of the monitor, checked as a person reads it: the title and the column header
/// exactly once, every line within the width, at most `rows` lines.
struct Screen {
  std::vector<std::string> rows;
  std::string text;
  int count(const std::string& prefix) const {
    return static_cast<int>(std::count_if(
        rows.begin(), rows.end(), [&](const std::string& l) { return l.rfind(prefix, 0) == 0; }));
  }
  const std::string* find(const std::string& prefix) const {
    for (const auto& l : rows)
      if (l.rfind(prefix, 0) == 0) return &l;
    return nullptr;
  }
};
Screen screen(const Tmux& t) {
  Screen s;
  s.text = t.capture();
  s.rows = lines(s.text);
  while (!s.rows.empty() && s.rows.back().empty()) s.rows.pop_back();
  return s;
}
void expectClean(const Screen& s, int cols, int rows, const std::string& what) {
  EXPECT_EQ(s.count("overstep monitor "), 1) << what << ":\n" << s.text;
  EXPECT_EQ(s.count("CHANNEL "), 1) << what << ":\n" << s.text;
  // The column header does not change: on a narrow terminal it is cut at the width, its last
  // column kept (monitor/src/monitor.cpp writes it).
  const std::string header =
      "CHANNEL                  TYPE                     COUNT   RATE Hz    MSG Hz    AGE s";
  if (const std::string* h = s.find("CHANNEL ")) {
    EXPECT_EQ(*h, header.substr(0, std::min<std::size_t>(header.size(), cols))) << what;
  }
  if (!s.rows.empty()) {
    EXPECT_EQ(s.rows[0].rfind("overstep monitor ", 0), 0u) << what;
  }
  EXPECT_LE(static_cast<int>(s.rows.size()), rows) << what << ":\n" << s.text;
  for (const auto& l : s.rows)
    EXPECT_LE(static_cast<int>(l.size()), cols)
        << what << ": a line wider than the terminal: " << l;
  std::set<std::string> seen;
  for (const auto& l : s.rows)
    if (l.rfind("OVERSTEP_", 0) == 0) {
      EXPECT_TRUE(seen.insert(l.substr(0, l.find(' '))).second) << what << ": twice: " << l;
    }
}

/// The monitor's state, rates and plan progress on the screen.
struct Shown {
  bool state_row = false;
  double rate = -1, msg_rate = -1;
  std::string runtime;
  int bar = -1;  // '#' in the progress bar
};
Shown shown(const Screen& s) {
  Shown r;
  std::smatch m;
  for (const auto& l : s.rows) {
    if (std::regex_search(
            l, m, std::regex("^OVERSTEP_STATE +robot_state_t +[0-9]+ +([0-9.]+) +([0-9.]+)"))) {
      r.state_row = true;
      r.rate = std::stod(m[1]);
      r.msg_rate = std::stod(m[2]);
    }
    if (std::regex_search(
            l, m,
            std::regex("^runtime +(IDLE|MOVING_TO_START|RUNNING|PAUSED|FINISHED|HOLD) +tick")))
      r.runtime = m[1];
    if (std::regex_search(l, m, std::regex("^plan +[0-9.]+ / [0-9.]+ s \\[([#.]{30})\\]"))) {
      const std::string bar = m[1];
      r.bar = static_cast<int>(std::count(bar.begin(), bar.end(), '#'));
    }
  }
  return r;
}

/// After the monitor quit: its exit status, the normal screen back (no frame left), the cursor
/// shown, the terminal's modes as before.
void expectRestored(const Tmux& t, const fs::path& dir, int code) {
  ASSERT_TRUE(waitUntil(10.0, [&] { return fs::exists(dir / "exit"); }))
      << "the monitor did not quit:\n"
      << t.capture();
  EXPECT_EQ(test::slurp((dir / "exit").string()), "exit " + std::to_string(code) + "\n");
  ASSERT_TRUE(
      waitUntil(5.0, [&] { return t.capture().find("shell prompt") != std::string::npos; }));
  EXPECT_EQ(t.format("#{alternate_on}"), "0");
  EXPECT_EQ(t.format("#{cursor_flag}"), "1");
  EXPECT_EQ(test::slurp((dir / "stty.before").string()),
            test::slurp((dir / "stty.after").string()));
  const Screen after = screen(t);
  EXPECT_EQ(after.count("CHANNEL "), 0) << "a frame was left on the screen:\n" << after.text;
}

class MonitorTty : public RecordedRun {};

TEST_F(MonitorTty, LiveOnTheRealTimeSimulatorRedrawsOnResizeAndQuitsOnQ) {
  if (!std::getenv("OVERSTEP_NETNS")) GTEST_SKIP() << "run through netns_run.sh";
  const fs::path out = artefacts();
  Background bg;
  // The robot in real time and the runtime replaying the recorded run's standing plan on it.
  bg.start(std::string(OVERSTEP_BIN) + " sim --realtime --no-obstacle --duration 30 >" +
           (out / "sim.out").string() + " 2>&1");
  // Ticked by the robot's states (--clock lcm) with a lenient watchdog: what is under test is the
  // monitor, not the runtime's deadlines on a loaded machine (with the timer clock it once held
  // after states came late: "no robot state for the watchdog period").
  bg.start(std::string(OVERSTEP_BIN) + " replay " + (runDir() / "plan.json").string() +
           " --clock lcm --watchdog 20 --start --quiet --linger 20 >" +
           (out / "replay.out").string() + " 2>&1");
  Tmux t(out, paneScript(out, "--interval 0.2"), 100, 30);
  ASSERT_TRUE(t.ok());
  // Watch it as the plan runs: the state's rate, the runtime's state, the bar filling.
  std::vector<int> bars;
  Screen s;
  Shown v;
  const bool done = waitUntil(25.0, [&] {
    s = screen(t);
    v = shown(s);
    if (v.bar >= 0 && (bars.empty() || bars.back() != v.bar)) bars.push_back(v.bar);
    return (v.bar == 30 && v.runtime == "FINISHED") || v.runtime == "HOLD";
  });
  test::writeText(out / "live_100x30.txt", s.text);
  EXPECT_TRUE(done) << "the plan did not end on the screen:\n" << s.text;
  // HOLD: the runtime stopped (see replay.out); the screen says so, which is the monitor's part.
  if (v.runtime == "HOLD") std::printf("note: the runtime held:\n%s", s.text.c_str());
  expectClean(s, 100, 30, "live 100x30");
  EXPECT_TRUE(v.state_row) << s.text;
  // 200 Hz by the wall clock on a loaded 2-core machine: a wide band; by its own clock exact.
  EXPECT_GT(v.rate, 120.0) << s.text;
  EXPECT_LT(v.rate, 280.0) << s.text;
  EXPECT_NEAR(v.msg_rate, 200.0, 2.0) << s.text;
  EXPECT_TRUE(std::is_sorted(bars.begin(), bars.end())) << "the progress bar went back";
  EXPECT_GE(bars.size(), 2u) << "the progress bar never showed the plan under way";
  // Narrower and shorter than the frame, then larger: every frame fits and is drawn once.
  for (const auto& [cols, rows] : std::vector<std::pair<int, int>>{{60, 12}, {130, 40}}) {
    t.resize(cols, rows);
    sleepFor(0.6);
    const Screen r = screen(t);
    const std::string name = "live_" + std::to_string(cols) + "x" + std::to_string(rows);
    test::writeText(out / (name + ".txt"), r.text);
    expectClean(r, cols, rows, name);
    if (rows >= 30) {
      EXPECT_TRUE(shown(r).state_row) << r.text;
      EXPECT_EQ(shown(r).runtime, v.runtime) << r.text;
    }
  }
  t.keys("q");
  expectRestored(t, out, 0);
}

TEST_F(MonitorTty, OnARecordedLogRedrawsOnResizeAndStopsOnCtrlC) {
  const fs::path out = artefacts();
  Tmux t(out, paneScript(out, quote(log()) + " --speed 1 --interval 0.2"), 100, 30);
  ASSERT_TRUE(t.ok());
  Screen s;
  Shown v;
  // Until the plan runs (the log's first seconds: the simulator settles, the runtime brings the
  // robot to the plan's start).
  const bool seen = waitUntil(8.0, [&] {
    s = screen(t);
    v = shown(s);
    return v.state_row && v.bar > 0 && v.runtime == "RUNNING";
  });
  test::writeText(out / "log_100x30.txt", s.text);
  ASSERT_TRUE(seen) << s.text;
  expectClean(s, 100, 30, "log 100x30");
  // By the robot's clock 200 Hz (the first messages of a settling simulator a little faster); by
  // the logger's, what the lock-step run made of this machine: around the log's mean.
  EXPECT_NEAR(v.msg_rate, 200.0, 10.0) << s.text;
  const double mean = stateRate(log());
  EXPECT_GT(v.rate, 0.5 * mean) << s.text;
  EXPECT_LT(v.rate, 2.0 * mean) << s.text;
  t.resize(70, 14);
  sleepFor(0.5);
  const Screen r = screen(t);
  test::writeText(out / "log_70x14.txt", r.text);
  expectClean(r, 70, 14, "log 70x14");
  t.keys("C-c");
  expectRestored(t, out, 130);
}

}  // namespace
}  // namespace overstep
