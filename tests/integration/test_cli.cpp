// The `overstep` front end as a user runs it: exit codes, one-line errors, JSON output.
#include <gtest/gtest.h>

#include <cstdlib>
#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "run_cli.hpp"
#include "test_util.hpp"

namespace overstep {
namespace {

using test::RunResult;

RunResult run(const std::string& args) { return test::runOverstep(args); }

void expectOneLineError(const RunResult& r, int code, const std::string& fragment) {
  EXPECT_EQ(r.code, code) << r.err;
  EXPECT_NE(r.err.find(fragment), std::string::npos) << r.err;
  ASSERT_FALSE(r.err.empty());
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "not one line: " << r.err;
}

TEST(Cli, HelpListsModelWithExamples) {
  const RunResult r = run("--help");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("model"), std::string::npos);
  EXPECT_NE(r.out.find("Examples"), std::string::npos);
  const RunResult m = run("model --help");
  EXPECT_EQ(m.code, 0);
  EXPECT_NE(m.out.find("--json"), std::string::npos);
}

TEST(Cli, ModelJsonReportsTheHrp2ClassModel) {
  const RunResult r = run("model --json --robot " + test::hrp2Yaml());
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["dofs"], 40);
  EXPECT_EQ(j["actuated"], 30);
  EXPECT_EQ(j["elastic"], 4);
  EXPECT_GE(j["mass"].get<double>(), 56.0);
  EXPECT_LE(j["mass"].get<double>(), 59.0);
  EXPECT_GE(j["com"][2].get<double>(), 0.78);
  EXPECT_LE(j["com"][2].get<double>(), 0.84);
  // Sole centres on the ground, left foot on +y, 0.19 m + sole asymmetry apart.
  EXPECT_NEAR(j["feet"]["left"][2].get<double>(), 0.0, 1e-9);
  EXPECT_NEAR(j["feet"]["right"][2].get<double>(), 0.0, 1e-9);
  EXPECT_GT(j["feet"]["left"][1].get<double>(), 0.09);
  EXPECT_LT(j["feet"]["right"][1].get<double>(), -0.09);
  EXPECT_EQ(j["joints"].size(), 30u);
}

TEST(Cli, MissingRobotFileIsBadInput) {
  expectOneLineError(run("model --robot /nonexistent/robot.yaml"), 2, "no such file");
}

TEST(Cli, MalformedRobotYamlIsBadInput) {
  test::TempDir dir;
  test::writeText(dir.path() / "bad.yaml", "name: [unclosed\n");
  expectOneLineError(run("model --robot " + dir.file("bad.yaml")), 2, "malformed YAML");
}

TEST(Cli, NegativeStiffnessIsBadInput) {
  test::TempDir dir;
  test::writeText(dir.path() / "hrp2.urdf", test::slurp(test::hrp2Urdf()));
  test::writeText(dir.path() / "hrp2.yaml", test::replaceOnce(test::slurp(test::hrp2Yaml()),
                                                              "stiffness: 502", "stiffness: -502"));
  expectOneLineError(run("model --robot " + dir.file("hrp2.yaml")), 2, "expected >= 0");
}

TEST(Cli, UnknownSubcommandOrFlagIsBadInput) {
  expectOneLineError(run("fly"), 2, "error");
  expectOneLineError(run("model --frobnicate"), 2, "frobnicate");
}

// Issue 20: `overstep check` said VALID after checking a negative number of grid points (an int
// overflow: --rate 5e9 on this 0.5 s plan, 3e9 on the 5.29 s default), never ended (--rate 1e9, a
// last sample at 1e6 s), read phase index 0.7 as 0 and
// ended "internal error" on a non-boolean contact flag. Each is now a one-line exit 2.
TEST(Cli, CheckRefusesWhatItCannotCheckInFull) {
  test::TempDir dir;
  const std::string plan = dir.file("stand.json");
  ASSERT_EQ(run("plan --stand 0.5 --out " + plan).code, 0);
  EXPECT_EQ(run("check " + plan).code, 0);
  for (const char* rate : {"5e9", "3e9", "1e9", "0", "-5"}) {
    const RunResult r = run("check " + plan + " --rate " + rate);
    expectOneLineError(r, 2, "check rate: expected a rate in (0, 10000] Hz");
    EXPECT_LT(r.seconds, 30.0) << rate;
  }
  const auto edited = [&](const std::string& name,
                          const std::function<void(nlohmann::json&)>& edit) {
    nlohmann::json j = nlohmann::json::parse(test::slurp(plan));
    edit(j);
    test::writeText(dir.path() / name, j.dump());
    return "check " + dir.file(name);
  };
  using J = nlohmann::json;
  expectOneLineError(run(edited("late.json", [](J& j) { j["samples"]["t"].back() = 1e6; })), 2,
                     "late.json: samples.t[100]: expected samples at most 1 / rate");
  expectOneLineError(run(edited("phase.json", [](J& j) { j["samples"]["phase"][3] = 0.7; })), 2,
                     "phase.json: samples.phase[3]: expected an integer in [0, 1), got 0.7");
  expectOneLineError(run(edited("flag.json", [](J& j) { j["phases"][0]["right_contact"] = 1; })), 2,
                     "flag.json: phases[0].right_contact: expected true or false, got 1");
  test::writeText(dir.path() / "deep.json", std::string(60000, '[') + std::string(60000, ']'));
  expectOneLineError(run("check " + dir.file("deep.json")), 2,
                     "deep.json: JSON nested deeper than 16 levels");
}

/// An LCM log event header (big-endian: sync word, event number 0, time 0, channel length, data
/// length), for logs written byte by byte.
std::string rawEventHeader(std::uint32_t channel_length, std::uint32_t data_length) {
  std::string h;
  const auto put = [&h](std::uint64_t v, int bytes) {
    for (int i = bytes - 1; i >= 0; --i) h += static_cast<char>((v >> (8 * i)) & 0xff);
  };
  put(0xEDA1DA01u, 4);
  put(0, 8);
  put(0, 8);
  put(channel_length, 4);
  put(data_length, 4);
  return h;
}

// Issue 20: a 32-byte log declaring 0x7fffffff data bytes killed every log reader (SIGSEGV).
TEST(Cli, LogReadersReportA32ByteLogAsDamaged) {
  test::TempDir dir;
  // The channel "A" and 3 of the 2^31 - 1 data bytes it declares.
  const std::string log = rawEventHeader(1, 0x7fffffff) + "Axyz";
  ASSERT_EQ(log.size(), 32u);
  test::writeText(dir.path() / "a.lcmlog", log);
  expectOneLineError(run("export " + dir.file("a.lcmlog") + " --csv " + dir.file("csv")), 2,
                     "a.lcmlog: damaged at byte 0");
  expectOneLineError(run("monitor " + dir.file("a.lcmlog") + " --once"), 2,
                     "a.lcmlog: damaged at byte 0");
}

// Issue 20: a channel name that is not UTF-8 ended `export --json` with "internal error".
TEST(Cli, ExportJsonSurvivesAChannelNameThatIsNotUtf8) {
  test::TempDir dir;
  // One event of a foreign type (8 zero bytes) on channel "\xff\xfe".
  const std::string log = rawEventHeader(2, 8) + "\xff\xfe" + std::string(8, '\0');
  test::writeText(dir.path() / "a.lcmlog", log);
  const RunResult r =
      run("export " + dir.file("a.lcmlog") + " --csv " + dir.file("csv") + " --json");
  EXPECT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out, nullptr, false);
  ASSERT_FALSE(j.is_discarded()) << r.out;
  EXPECT_EQ(j["skipped"].size(), 1u) << r.out;
}

// Issue 20: `--lcm-url tcpq://...` ended sim, replay and monitor in liblcm's fd_set assertion
// (SIGABRT), and a malformed URL in demo was an internal error. Every command that opens a bus
// checks the URL first: one line, exit 2, the URL named.
TEST(Cli, LcmUrlsAreCheckedBeforeLiblcmSeesThem) {
  test::TempDir dir;
  const std::vector<std::pair<std::string, std::string>> urls = {
      {"tcpq://127.0.0.1:7700", "provider 'tcpq' is not supported"},
      {"file:///tmp/x.lcmlog", "provider 'file' is not supported"},
      {"239.255.76.67:7667", "expected udpm://"},
      {"udpm://239.255.76.67:99999", "port '99999'"},
      {"udpm://239.255.76.67:", "port ''"},
      {"udpm://10.1.2.3:7667", "group '10.1.2.3': expected a multicast address"},
      {"udpm://300.1.1.1:7667", "group '300.1.1.1': expected an IPv4 address"},
      {"udpm://239.255.76.67:7667?ttl=-1", "ttl '-1'"},
      {"udpm://239.255.76.67:7667?tll=0", "unknown option 'tll'"},
      {"memq://x", "memq:// takes no"},
  };
  const std::vector<std::string> commands = {"sim --lockstep --duration 1 --lcm-url ",
                                             "replay " + dir.file("missing.json") + " --lcm-url ",
                                             "monitor --once --duration 0.1 --lcm-url ",
                                             "demo --no-report --lcm-url ", "spy --lcm-url "};
  for (const auto& cmd : commands) {
    for (const auto& [url, why] : urls) {
      SCOPED_TRACE(cmd + url);
      const RunResult r = run(cmd + "'" + url + "'");
      expectOneLineError(r, 2, "--lcm-url '" + url + "': " + why);
    }
  }
  // demo runs its processes on one bus: memq:// (one process) is refused there.
  expectOneLineError(run("demo --no-report --lcm-url memq://"), 2, "expected udpm://");
  // The default URL from the environment is checked too, and named.
  ::setenv("LCM_DEFAULT_URL", "tcpq://127.0.0.1:7700", 1);
  const RunResult env = run("monitor --once --duration 0.1");
  ::unsetenv("LCM_DEFAULT_URL");
  expectOneLineError(env, 2, "LCM_DEFAULT_URL 'tcpq://127.0.0.1:7700'");
  // A well-formed URL passes: memq:// (in-process) makes a live monitor that sees nothing.
  const RunResult ok = run("monitor --once --duration 0.1 --json --lcm-url memq://");
  EXPECT_EQ(ok.code, 0) << ok.err;
}

// What liblcm prints when it cannot open a bus (here: no network at all, a fresh network
// namespace without even `lo` up) is in the one-line error instead of 14 lines of its own.
TEST(Cli, LiblcmsMessagesAreInTheOneLineError) {
  if (std::system("unshare -n true 2>/dev/null") != 0) GTEST_SKIP() << "needs unshare -n (root)";
  test::TempDir dir;
  const std::string cmd =
      "unshare -n " + std::string(OVERSTEP_BIN) +
      " monitor --once --duration 0.2 --lcm-url 'udpm://239.255.76.67:7667?ttl=0'"
      " 2>" +
      dir.file("err") + " >/dev/null";
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = test::slurp(dir.file("err"));
  expectOneLineError(r, 2, "cannot open LCM at 'udpm://239.255.76.67:7667?ttl=0': ");
  EXPECT_NE(r.err.find("multicast route"), std::string::npos) << r.err;
}

// Issue 20: a URDF nested 100,000 deep overflowed TinyXML's stack (SIGSEGV), 1e308 in a URDF or
// a robot YAML reached DART's assertions, and urdfdom printed lines of its own beside our error.
TEST(Cli, RobotFilesAreBoundedBeforeUrdfdomAndDartSeeThem) {
  test::TempDir dir;
  const std::string urdf = test::slurp(test::hrp2Urdf()), yaml = test::slurp(test::hrp2Yaml());
  auto modelWith = [&](const std::string& u, const std::string& y) {
    test::writeText(dir.path() / "hrp2.urdf", u);
    test::writeText(dir.path() / "hrp2.yaml", y);
    return run("model --robot " + dir.file("hrp2.yaml"));
  };
  std::string deep;
  for (int i = 0; i < 100000; ++i) deep += "<a>";
  for (int i = 0; i < 100000; ++i) deep += "</a>";
  const RunResult nested = modelWith(test::replaceOnce(urdf, "</robot>", deep + "</robot>"), yaml);
  expectOneLineError(nested, 2, "hrp2.urdf: elements nested more than 64 deep");
  EXPECT_LT(nested.seconds, 10.0);
  // Comments, quoted attributes and self-closing elements do not count as nesting.
  std::string flat;
  for (int i = 0; i < 1000; ++i) flat += "<!-- <a> --><b c='x>y'/>";
  EXPECT_EQ(modelWith(test::replaceOnce(urdf, "</robot>", flat + "</robot>"), yaml).code, 0);
  expectOneLineError(
      modelWith(test::replaceOnce(urdf, "<mass value=\"14.5\"/>", "<mass value=\"1e308\"/>"), yaml),
      2, "link 'BODY' mass: expected a finite value of magnitude <= 10000, got 1e+308");
  expectOneLineError(modelWith(test::replaceOnce(urdf, "<origin xyz=\"-0.01 0 0.12\"",
                                                 "<origin xyz=\"-0.01 1e308 0.12\""),
                               yaml),
                     2, "link 'BODY' inertial origin xyz");
  expectOneLineError(modelWith(test::replaceOnce(urdf, "<box size=\"0.2 0.24 0.22\"/>",
                                                 "<box size=\"0.2 1e300 0.22\"/>"),
                               yaml),
                     2, "link 'BODY' visual box size");
  // What urdfdom prints about a URDF it cannot parse is in the one line.
  const RunResult broken = modelWith(test::replaceOnce(urdf, "</robot>", "<link"), yaml);
  expectOneLineError(broken, 2, "hrp2.urdf: malformed URDF (urdfdom: ");
  EXPECT_EQ(broken.err.find("could not parse it"), std::string::npos) << "urdfdom said nothing?";
  // 1e308 in the YAML: beyond the magnitude any of our YAML numbers may have.
  expectOneLineError(modelWith(urdf, test::replaceOnce(yaml, "stiffness: 502", "stiffness: 1e308")),
                     2, "stiffness: expected a magnitude of at most 1e+09, got 1e+308");
}

// Issue 20: `report --frames 100000` drew without end.
TEST(Cli, ReportFramesAreBounded) {
  test::TempDir dir;
  for (const char* n : {"100000", "65", "1", "0", "-3"})
    expectOneLineError(run("report " + dir.path().string() + " --frames " + n), 2,
                       std::string("--frames: expected 2 to 64, got ") + n);
}

// Issue 20: a floating-base robot without `feet:` loaded, then `plan` and `check` crashed.
TEST(Cli, ARobotWithoutFeetIsBadInput) {
  test::TempDir dir;
  test::writeText(dir.path() / "hrp2.urdf", test::slurp(test::hrp2Urdf()));
  test::writeText(dir.path() / "hrp2.yaml",
                  test::replaceOnce(test::slurp(test::hrp2Yaml()), "\nfeet:", "\nfeat:"));
  expectOneLineError(run("model --robot " + dir.file("hrp2.yaml")), 2,
                     "hrp2.yaml: feet: missing key");
}

}  // namespace
}  // namespace overstep
