#pragma once
/// \file
/// `overstep report RUN_DIR`: plan against measurement, as the seed's figures show them. The C++
/// side aligns the log with the plan tick by tick (one row per runtime tick that executed the
/// plan) and writes the data (report/data/: ticks.csv, meta.json, frames.json); Matplotlib
/// (Debian's python3-matplotlib, driven by monitor/python/report_plots.py) draws the PNG figures,
/// report/index.html and report/report.json, a manifest of every figure with its series and time
/// range. docs/report.md describes each figure.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace overstep::monitor {

/// The most snapshots in the side-view sequence (16 rows of 4 panels).
constexpr int kMaxFrames = 64;

struct ReportOptions {
  std::string run_dir;
  std::string robot;                        ///< robot YAML (must be the plan's robot)
  std::string plan;                         ///< default RUN_DIR/plan.json
  std::string log;                          ///< default RUN_DIR/bus.lcmlog
  std::string out;                          ///< default RUN_DIR/report
  std::string python = "/usr/bin/python3";  ///< Debian's, where python3-matplotlib lives
  std::string script;  ///< default: monitor/python/report_plots.py of this source tree
  int frames = 8;      ///< snapshots in the side-view sequence, 2 to kMaxFrames
  int dpi = 80;        ///< PNG resolution
};

struct ReportSummary {
  std::string out_dir, index_html, manifest;
  int ticks = 0;                      ///< aligned runtime ticks
  double t_begin = 0.0, t_end = 0.0;  ///< plan time covered by the measurement, s
  std::vector<std::string> figures;   ///< PNG paths
  long long log_break_offset = -1;    ///< where a damaged log stopped being read (-1: intact)
  nlohmann::json fidelity;            ///< the execution's figures (monitor/fidelity.hpp)
};

/// Writes the data files and runs the plotting script. InputError (one line) when the run folder
/// lacks the plan or the log, the log has no executed plan ticks, or the plan is for another
/// robot; std::runtime_error when the plotting script fails.
ReportSummary makeReport(const ReportOptions& options);

/// InputError for options outside their ranges (--dpi 20..400, --frames 2..kMaxFrames); called
/// by makeReport, and by the command before it prints anything.
void checkReportOptions(const ReportOptions& options);

/// Runs `python script args...` and waits; std::runtime_error naming `what` when it cannot start
/// or fails (the figures of `overstep report` and `overstep identify --plots`).
void runPlotScript(const std::string& python, const std::string& script,
                   const std::vector<std::string>& args, const std::string& what);
/// A Python script shipped in this source tree (e.g. "sysid/python/residual_plots.py").
std::string shippedScript(const std::string& relative);

/// Only the data files (no Python): what makeReport() feeds the script. Returns the tick count.
int writeReportData(const ReportOptions& options, ReportSummary& summary);

}  // namespace overstep::monitor
