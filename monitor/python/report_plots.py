#!/usr/bin/python3
"""Draws the figures of `overstep report` from the data that the C++ side wrote.

Usage: report_plots.py REPORT_DIR [DPI]   (reads REPORT_DIR/data/{ticks.csv,meta.json,frames.json};
writes REPORT_DIR/fig*.png, index.html and report.json, the manifest of every figure: its file,
title, and per axes the plotted series and their time range; and the fidelity metrics and the
verdict (RUN_DIR/verdict.json, from `overstep demo`) shown at the top of index.html).

Plotting library: Matplotlib (Debian package python3-matplotlib), Agg backend (no display).
"""
import csv
import html
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Circle, Rectangle  # noqa: E402

PLAN = dict(color="tab:blue", lw=1.2)
MEAS = dict(color="tab:red", lw=1.0)
OTHER = dict(color="tab:green", lw=1.0, ls="--")
DPI = 80
STABILIZER_SHADE = 5.0  # shade where a correction reaches 5 mrad / 5 mm (stab_level is in 1 mrad / 1 mm)


def load(out):
    with open(os.path.join(out, "data", "ticks.csv")) as f:
        rows = list(csv.DictReader(f))
    cols = {k: [float(r[k]) if r[k] not in ("", "nan") else math.nan for r in rows] for k in rows[0]}
    with open(os.path.join(out, "data", "meta.json")) as f:
        meta = json.load(f)
    with open(os.path.join(out, "data", "frames.json")) as f:
        frames = json.load(f)
    return cols, meta, frames


class Manifest:
    def __init__(self):
        self.figures = []

    def axes(self, ax, title):
        """Records the data series (lines with a label) of one axes."""
        series, t0, t1 = [], math.inf, -math.inf
        for line in ax.get_lines():
            label = line.get_label()
            if label.startswith("_"):
                continue
            xs = [x for x, y in zip(line.get_xdata(), line.get_ydata()) if not math.isnan(y)]
            series.append(label)
            if xs:
                t0, t1 = min(t0, min(xs)), max(t1, max(xs))
        return {"title": title, "series": series,
                "t_range": [t0, t1] if series and t0 <= t1 else None}

    def add(self, out, fig, name, title, axes):
        path = os.path.join(out, name)
        fig.savefig(path + ".tmp.png", dpi=DPI)
        os.replace(path + ".tmp.png", path)
        plt.close(fig)
        self.figures.append({"file": name, "title": title, "axes": axes})


def shade_phases(ax, meta):
    for p in meta["phases"]:
        if p["right_contact"] and p["left_contact"]:
            ax.axvspan(p["start"], p["start"] + p["duration"], color="0.92", lw=0)


def fig_zmp(out, c, meta, man):
    fig, axs = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    recs = []
    for ax, k in zip(axs, "xy"):
        shade_phases(ax, meta)
        ax.plot(c["t"], c["zmp_wb_" + k], label="plan: whole-body ZMP", **PLAN)
        ax.plot(c["t"], c["zmp_tc_" + k], label="plan: table-cart ZMP", **OTHER)
        ax.plot(c["t"], c["zmp_meas_" + k], label="measured ZMP", **MEAS)
        ax.set_ylabel(f"ZMP {k} (m)")
        ax.grid(alpha=0.3)
        recs.append(man.axes(ax, "ZMP " + k))
    axs[0].legend(fontsize=8, loc="best")
    axs[-1].set_xlabel("plan time (s); grey: double support")
    fig.suptitle("Whole-body ZMP vs table-cart ZMP (seed Fig. 3)")
    fig.tight_layout()
    man.add(out, fig, "fig3_zmp.png", "Whole-body vs table-cart ZMP", recs)


def fig_torso(out, c, meta, man):
    fig, axs = plt.subplots(2, 1, figsize=(8, 4.5), sharex=True)
    recs = []
    lim = meta["pelvis_tilt"]
    src = "ground truth" if meta["ground_truth"] else "IMU"
    for ax, k in zip(axs, ("roll", "pitch")):
        shade_phases(ax, meta)
        ax.plot(c["t"], c[k + "_plan"], label="plan", **PLAN)
        ax.plot(c["t"], c[k + "_meas"], label=f"measured ({src})", **MEAS)
        for s in (-lim, lim):
            ax.axhline(s, color="0.4", lw=0.8, ls=":")
        ax.set_ylabel(f"{k} (rad)")
        ax.grid(alpha=0.3)
        recs.append(man.axes(ax, "pelvis " + k))
    axs[0].legend(fontsize=8)
    axs[-1].set_xlabel("plan time (s); dotted: planner bound")
    fig.suptitle("Pelvis (BODY) roll and pitch, plan vs measured (seed Fig. 4)")
    fig.tight_layout()
    man.add(out, fig, "fig4_torso.png", "Pelvis roll and pitch", recs)


def fig_wrenches(out, c, meta, man):
    comps = ["Fx", "Fy", "Fz", "Mx", "My", "Mz"]
    fig, axs = plt.subplots(6, 2, figsize=(10, 11), sharex=True)
    recs = []
    for j, side in enumerate(("right", "left")):
        for i, k in enumerate(comps):
            ax = axs[i][j]
            shade_phases(ax, meta)
            ax.plot(c["t"], c[f"{side}_{k}_plan"], label="plan", **PLAN)
            ax.plot(c["t"], c[f"{side}_{k}_meas"], label="measured", **MEAS)
            ax.set_ylabel(f"{k} ({'N' if k[0] == 'F' else 'N m'})", fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
            if i == 0:
                ax.set_title(f"{side} foot (sole frame)", fontsize=9)
            recs.append(man.axes(ax, f"{side} {k}"))
    axs[0][0].legend(fontsize=7)
    for ax in axs[-1]:
        ax.set_xlabel("plan time (s)")
    fig.suptitle("Contact wrenches, plan vs measured (seed Fig. 5)")
    fig.tight_layout()
    man.add(out, fig, "fig5_wrenches.png", "Foot wrenches", recs)


def stabilizer_spans(c):
    spans, start = [], None
    for t, lvl in zip(c["t"], c["stab_level"]):
        on = lvl >= STABILIZER_SHADE
        if on and start is None:
            start = t
        if not on and start is not None:
            spans.append((start, t))
            start = None
    if start is not None:
        spans.append((start, c["t"][-1]))
    return spans


def fig_joints(out, c, meta, man):
    fig, axs = plt.subplots(6, 2, figsize=(10, 12), sharex=True)
    recs = []
    spans = stabilizer_spans(c)
    for n, j in enumerate(meta["joints"]):
        ax = axs[n % 6][n // 6]
        for a, b in spans:
            ax.axvspan(a, b, color="gold", alpha=0.25, lw=0)
        name = j["name"]
        ax.plot(c["t"], c[name + "_plan"], label="plan", **PLAN)
        ax.plot(c["t"], c[name + "_cmd"], label="reference sent", **OTHER)
        ax.plot(c["t"], c[name + "_meas"], label="measured", **MEAS)
        lo, hi = min(min(c[name + "_meas"]), min(c[name + "_plan"])), max(
            max(c[name + "_meas"]), max(c[name + "_plan"]))
        for key, style in (("lower", "-"), ("upper", "-"), ("safe_lower", ":"), ("safe_upper", ":")):
            v = j[key]
            if lo - 0.2 <= v <= hi + 0.2:  # draw the limits near the motion only
                ax.axhline(v, color="k", lw=0.8, ls=style)
        ax.set_title(name, fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
        recs.append(man.axes(ax, name))
    axs[0][0].legend(fontsize=7)
    for ax in axs[-1]:
        ax.set_xlabel("plan time (s)")
    fig.suptitle("Leg joints (rad): plan, reference, measured; limits solid, safety limits dotted;\n"
                 "yellow: stabilizer correcting by 5 mrad / 5 mm or more (seed Fig. 6)", fontsize=10)
    fig.tight_layout()
    man.add(out, fig, "fig6_joints.png", "Leg joint angles", recs)


def fig_cop(out, c, meta, man):
    fig, axs = plt.subplots(1, 2, figsize=(9, 5))
    recs = []
    h = 0.5 * meta["cop_box"]
    for ax, side in zip(axs, ("right", "left")):
        s = meta["soles"][side]
        ax.add_patch(Rectangle((s["x_back"], s["y_min"]), s["x_front"] - s["x_back"],
                               s["y_max"] - s["y_min"], fill=False, color="k", lw=1.2))
        ax.add_patch(Rectangle((-h, -h), 2 * h, 2 * h, fill=False, color="tab:blue", ls="--"))
        xp = [x if ct else math.nan for x, ct in zip(c[f"{side}_cop_x_plan"], c[f"{side}_contact"])]
        yp = [y if ct else math.nan for y, ct in zip(c[f"{side}_cop_y_plan"], c[f"{side}_contact"])]
        ax.plot(xp, yp, label="plan", **PLAN)
        ax.plot(c[f"{side}_cop_x_meas"], c[f"{side}_cop_y_meas"], ".", ms=2, color=MEAS["color"],
                label="measured")
        ax.set_aspect("equal")
        ax.set_xlabel("x (m, sole frame)")
        ax.set_ylabel("y (m)")
        ax.set_title(f"{side} foot: sole outline, CoP box (dashed)", fontsize=9)
        ax.grid(alpha=0.3)
        # Series here are CoP paths: their "time range" is that of the loaded samples.
        rec = {"title": f"{side} CoP", "series": ["plan", "measured"], "t_range": None}
        ts = [t for t, x in zip(c["t"], c[f"{side}_cop_x_meas"]) if not math.isnan(x)]
        if ts:
            rec["t_range"] = [min(ts), max(ts)]
        recs.append(rec)
    axs[0].legend(fontsize=8)
    fig.suptitle("Local CoP of each foot (seed Fig. 7); CoP shown where Fz > 5 % of the weight")
    fig.tight_layout()
    man.add(out, fig, "fig7_cop.png", "Local CoP per foot", recs)


def fig_fidelity(out, meta, man):
    """Touchdown loads and CoP deviation over time (data/fidelity.csv: the plan and the hold
    after it), the plan beside the measurement."""
    with open(os.path.join(out, "data", "fidelity.csv")) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        return
    col = {k: [float(r[k]) if r[k] not in ("", "nan") else math.nan for r in rows] for k in rows[0]}
    t = col["t"]
    fig, axs = plt.subplots(2, 2, figsize=(11, 6), sharex=True)
    recs = []
    for j, side in enumerate(("right", "left")):
        ax = axs[0][j]
        ax.plot(t, col[f"{side}_fz_plan"], label="plan", **PLAN)
        ax.plot(t, col[f"{side}_fz_meas"], label="measured", **MEAS)
        for prev, p in zip(meta["phases"], meta["phases"][1:]):
            if p[f"{side}_contact"] and not prev[f"{side}_contact"]:
                ax.axvline(p["start"], color="0.6", ls=":", lw=0.8, label="_")
        ax.axvline(meta["duration"], color="k", ls="--", lw=0.8, label="_")
        ax.set_ylabel("Fz (N)")
        ax.set_title(f"{side} foot normal force (dotted: planned touchdown; dashed: plan end)",
                     fontsize=8)
        ax.grid(alpha=0.3)
        recs.append(man.axes(ax, f"{side} Fz"))
        ax = axs[1][j]
        dev = [1e3 * math.hypot(xm - xp, ym - yp) for xm, ym, xp, yp in
               zip(col[f"{side}_cop_x_meas"], col[f"{side}_cop_y_meas"],
                   col[f"{side}_cop_x_plan"], col[f"{side}_cop_y_plan"])]
        ax.plot(t, dev, label="|CoP measured - plan|", **MEAS)
        ax.axhline(15.0, color="tab:red", ls="--", lw=0.8, label="_")
        ax.axvline(meta["duration"], color="k", ls="--", lw=0.8, label="_")
        ax.set_ylabel("CoP deviation (mm)")
        ax.set_xlabel("time (s)")
        ax.set_title("local CoP deviation (where the foot is loaded; red: 15 mm p95 target)",
                     fontsize=8)
        ax.grid(alpha=0.3)
        recs.append(man.axes(ax, f"{side} CoP deviation"))
    axs[0][0].legend(fontsize=8)
    fig.suptitle("Execution fidelity: touchdown loads and CoP against the plan")
    fig.tight_layout()
    man.add(out, fig, "fig_fidelity.png", "Touchdown loads and CoP deviation", recs)


def draw_robot(ax, caps, color, alpha):
    for cp in sorted(caps, key=lambda k: -0.5 * (k["p0"][1] + k["p1"][1])):
        far = 0.5 * (cp["p0"][1] + cp["p1"][1]) > 0  # left side: further from the viewer
        ax.plot([cp["p0"][0], cp["p1"][0]], [cp["p0"][2], cp["p1"][2]], color=color,
                alpha=alpha * (0.55 if far else 1.0), lw=max(1.0, 130 * cp["r"]),
                solid_capstyle="round", label="_")


def fig_sequence(out, frames, meta, man):
    n = len(frames)
    cols = min(n, 4)
    rows_ = (n + cols - 1) // cols
    fig, axs = plt.subplots(rows_, cols, figsize=(3.0 * cols, 3.6 * rows_), squeeze=False)
    ob = meta["obstacle"]
    recs = []
    for i, fr in enumerate(frames):
        ax = axs[i // cols][i % cols]
        if ob["shape"] == "box":
            ax.add_patch(Rectangle((ob["x_min"], 0), ob["x_max"] - ob["x_min"], ob["height"],
                                   color="tab:brown", alpha=0.6))
        else:
            ax.add_patch(Circle((ob["centre"][0], ob["centre"][2]), ob["radius"],
                                color="tab:brown", alpha=0.6))
        ax.axhline(0, color="k", lw=1)
        draw_robot(ax, fr["plan"], "tab:blue", 0.35)
        if fr["measured"]:
            draw_robot(ax, fr["measured"], "tab:red", 0.8)
        ax.set_xlim(-0.45, 0.95)
        ax.set_ylim(-0.02, 1.5)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(f"t = {fr['t']:.2f} s  {fr['phase']}", fontsize=8)
        recs.append({"title": f"t = {fr['t']:.2f} s", "series": ["plan"] + (["measured"] if fr["measured"] else []),
                     "t_range": [fr["t"], fr["t"]]})
    for j in range(n, rows_ * cols):
        axs[j // cols][j % cols].axis("off")
    fig.suptitle("The motion seen from the right side: measured (red), plan (blue) (seed Figs. 1-2)",
                 fontsize=10)
    fig.tight_layout()
    man.add(out, fig, "fig1_sequence.png", "Side-view sequence", recs)


def rms_max(errors):
    """(RMS, largest magnitude) of the finite values, None without any."""
    e = [abs(x) for x in errors if not math.isnan(x)]
    if not e:
        return None
    return math.sqrt(sum(x * x for x in e) / len(e)), max(e)


def tracking(c, meta):
    """How closely the executed motion followed the plan, from the aligned ticks: per quantity
    the RMS and the largest error, in display units (mm, mrad, N)."""
    out = []

    def add(key, label, unit, scale, errors):
        r = rms_max(errors)
        if r is not None:
            out.append({"key": key, "label": label, "unit": unit,
                        "rms": r[0] * scale, "max": r[1] * scale})

    add("zmp", "ZMP, measured - stabilizer reference", "mm", 1e3,
        [math.hypot(mx - rx, my - ry) for mx, my, rx, ry in
         zip(c["zmp_meas_x"], c["zmp_meas_y"], c["zmp_ref_x"], c["zmp_ref_y"])])
    legs = []
    for j in meta["joints"]:
        legs += [m - p for m, p in zip(c[j["name"] + "_meas"], c[j["name"] + "_plan"])]
    add("leg_joints", "leg joints, measured - plan (12 joints)", "mrad", 1e3, legs)
    add("pelvis", "pelvis roll and pitch, measured - plan", "mrad", 1e3,
        [m - p for k in ("roll", "pitch") for m, p in zip(c[k + "_meas"], c[k + "_plan"])])
    for side in ("right", "left"):
        add(f"{side}_fz", f"{side} foot Fz, measured - plan", "N", 1.0,
            [m - p for m, p in zip(c[f"{side}_Fz_meas"], c[f"{side}_Fz_plan"])])
    return out


def read_verdict(run_dir):
    """RUN_DIR/verdict.json as `overstep demo` writes it, or None."""
    try:
        with open(os.path.join(run_dir, "verdict.json")) as f:
            v = json.load(f)
        return v if isinstance(v, dict) else None
    except (OSError, ValueError):
        return None


def verdict_reason(v):
    """The reason `overstep demo` prints beside its verdict (app/src/demo_command.cpp)."""
    if v.get("fell", True):
        return "the robot fell"
    if v.get("obstacle_contact", True):
        return "the robot touched the obstacle"
    if not v.get("finished", False):
        return "the runtime stopped: " + str(v.get("runtime_fault", ""))
    if not v.get("feet_beyond_obstacle", False):
        return "a foot did not get past the obstacle"
    if not v.get("static_at_end", False):
        return "the robot was still moving at the end"
    return "both feet past the obstacle, standing still"


def num(v, fmt):
    try:
        return format(float(v), fmt)
    except (TypeError, ValueError):
        return "?"


EXECUTION_ROWS = [  # (key in data/fidelity.json, label, display scale, unit)
    ("contact_losses", "contact losses", 1.0, ""),
    ("peak_touchdown_load", "peak touchdown load", 1.0, "x weight"),
    ("cop_deviation_p95", "local CoP deviation p95", 1e3, "mm"),
    ("cop_deviation_max", "local CoP deviation max", 1e3, "mm"),
    ("chatter_rms", "moment chatter (RMS above 20 Hz)", 1.0, "N m"),
]


def read_execution(out):
    """data/fidelity.json (monitor/fidelity.hpp: each figure with its target), or None."""
    try:
        with open(os.path.join(out, "data", "fidelity.json")) as f:
            x = json.load(f)
        return x if isinstance(x, dict) else None
    except (OSError, ValueError):
        return None


def figure_cell(f, scale, unit):
    """A figure of fidelity.json as 'value unit (target T)' marked met or not."""
    if not isinstance(f, dict):
        return "<td>-</td>"
    val = "n/a" if f.get("value") is None else format(f["value"] * scale, ".2f" if scale != 1.0 or unit else "g")
    cls = "met" if f.get("met") else "miss"
    return (f"<td class='{cls}'>{val} {unit} <small>(target &le; "
            f"{format(f['target'] * scale, 'g')})</small></td>")


def execution_html(x):
    """The execution's figures per foot against their targets (issue 19)."""
    if x is None:
        return "<p>No execution figures (data/fidelity.json missing).</p>"
    feet = x.get("feet", {})
    rows = ["<table id='fidelity'><tr><th>figure</th><th>right foot</th><th>left foot</th></tr>"]
    for key, label, scale, unit in EXECUTION_ROWS:
        rows.append(f"<tr data-key='{key}'><th>{label}</th>"
                    + "".join(figure_cell(feet.get(side, {}).get(key), scale, unit)
                              for side in ("right", "left")) + "</tr>")
    rows.append("<tr data-key='touchdown_timing'><th>first contact - planned touchdown</th>"
                + "".join("<td>" + ("n/a" if not isinstance(feet.get(side, {}).get("touchdown_timing"), (int, float))
                                    else format(1e3 * feet[side]["touchdown_timing"], "+.0f") + " ms") + "</td>"
                          for side in ("right", "left")) + "</tr>")
    rows.append("<tr data-key='pelvis_deviation_max'><th>pelvis roll / pitch from the plan, max</th>"
                + figure_cell(x.get("pelvis_deviation_max"), 1e3, "mrad") + "<td></td></tr>")
    rows.append("<tr data-key='settling_time'><th>static after the plan's end</th>"
                + figure_cell(x.get("settling_time"), 1.0, "s") + "<td></td></tr>")
    rows.append("</table>")
    misses = x.get("misses") or []
    rows.append("<p>" + ("Every figure meets its target." if not misses else
                         "Over target: " + html.escape(", ".join(misses)) + ".") + "</p>")
    return "\n".join(rows)


def verdict_html(v, fid, execution):
    """The top of the page: the run's verdict, the execution's figures and the tracking."""
    e = html.escape
    parts = ["<section id='verdict'>"]
    if v is None:
        parts.append("<p class='verdict none'>No verdict: the run folder has no verdict.json "
                     "(written by <code>overstep demo</code>).</p>")
    else:
        cleared = v.get("cleared") is True
        parts.append(f"<p class='verdict {'cleared' if cleared else 'failed'}'><b>"
                     f"{'CLEARED' if cleared else 'NOT CLEARED'}</b>: {e(verdict_reason(v))}</p>")
        ob = v.get("obstacle") if isinstance(v.get("obstacle"), dict) else {}
        cop = v.get("cop_max") if isinstance(v.get("cop_max"), dict) else {}
        rows = [("executed / plan duration",
                 f"{num(v.get('duration'), '.2f')} s / {num(v.get('plan_duration'), '.2f')} s"
                 + ("" if v.get("plan_valid", True) else " (INVALID plan)")),
                ("obstacle", f"{e(str(ob.get('shape', '?')))} {num(ob.get('height'), '.3f')} m high, "
                             f"{num(ob.get('width'), '.3f')} m wide"),
                ("tracking RMS", f"{num(v.get('tracking_rms'), '.4f')} rad"),
                ("stabilizer effort", f"{num(v.get('stabilizer_effort'), '.4f')} rad"
                                      + ("" if v.get("stabilizer", True) else " (stabilizer off)")),
                ("largest CoP excursion", f"R {num(cop.get('right'), '.3f')} m, "
                                          f"L {num(cop.get('left'), '.3f')} m"),
                ("torso deviation max", f"{num(v.get('torso_deviation_max'), '.3f')} rad"),
                ("fell / obstacle contact", f"{'yes' if v.get('fell') else 'no'} / "
                                            f"{'yes' if v.get('obstacle_contact') else 'no'}"),
                ("runtime", e(str(v.get("runtime_state", "?")))
                 + (f" (fault: {e(str(v['runtime_fault']))})" if v.get("runtime_fault") else ""))]
        parts.append("<table id='verdict-metrics'>" + "".join(
            f"<tr><th>{k}</th><td>{val}</td></tr>" for k, val in rows) + "</table>")
    parts.append("<h2>Execution fidelity: the sensors against the plan, with the hold after it</h2>")
    parts.append(execution_html(execution))
    parts.append("<h2>Tracking: measured vs plan, over the executed ticks</h2>"
                 "<table id='tracking'><tr><th>quantity</th><th>RMS</th><th>max</th></tr>")
    for f in fid:
        parts.append(f"<tr data-key='{f['key']}'><td>{e(f['label'])}</td>"
                     f"<td>{f['rms']:.2f} {f['unit']}</td><td>{f['max']:.2f} {f['unit']}</td></tr>")
    parts.append("</table></section>")
    return "\n".join(parts)


def write_index(out, man, meta, verdict, fid, execution):
    parts = ["<!doctype html><meta charset='utf-8'><title>overstep report</title>",
             "<style>body{font-family:sans-serif;max-width:1100px;margin:auto}img{max-width:100%}"
             "table{border-collapse:collapse}th,td{text-align:left;padding:2px 10px 2px 0}"
             ".verdict{font-size:1.3em}.cleared b{color:#080}.failed b{color:#b00}"
             ".met{color:#080}.miss{color:#b00}</style>",
             f"<h1>overstep report</h1>",
             verdict_html(verdict, fid, execution),
             f"<p>run: {html.escape(str(meta['run_dir']))}<br>plan: "
             f"{html.escape(str(meta['plan']))} ({meta['duration']:.2f} s)<br>log: "
             f"{html.escape(str(meta['log']))}</p>"]
    if meta.get("log_break_offset", -1) >= 0:
        parts.append(f"<p><b>The log is damaged at byte {meta['log_break_offset']}; the figures "
                     "show what came before.</b></p>")
    for f in man.figures:
        parts.append(f"<h2>{html.escape(f['title'])}</h2><img src='{f['file']}' alt='{html.escape(f['title'])}'>")
    tmp = os.path.join(out, "index.html.tmp")
    with open(tmp, "w") as fh:
        fh.write("\n".join(parts) + "\n")
    os.replace(tmp, os.path.join(out, "index.html"))


def main():
    global DPI
    if len(sys.argv) not in (2, 3):
        sys.exit("usage: report_plots.py REPORT_DIR [DPI]")
    out = sys.argv[1]
    if len(sys.argv) == 3:
        DPI = int(sys.argv[2])
    c, meta, frames = load(out)
    man = Manifest()
    fig_sequence(out, frames, meta, man)
    fig_zmp(out, c, meta, man)
    fig_torso(out, c, meta, man)
    fig_wrenches(out, c, meta, man)
    fig_joints(out, c, meta, man)
    fig_cop(out, c, meta, man)
    fig_fidelity(out, meta, man)
    verdict = read_verdict(meta["run_dir"])
    fid = tracking(c, meta)
    execution = read_execution(out)
    write_index(out, man, meta, verdict, fid, execution)
    tmp = os.path.join(out, "report.json.tmp")
    with open(tmp, "w") as fh:
        json.dump({"figures": man.figures, "ticks": len(c["t"]),
                   "t_range": [c["t"][0], c["t"][-1]], "tracking": fid,
                   "fidelity": execution,
                   "verdict": None if verdict is None else {
                       "cleared": verdict.get("cleared") is True,
                       "reason": verdict_reason(verdict)}}, fh, indent=1)
    os.replace(tmp, os.path.join(out, "report.json"))


if __name__ == "__main__":
    main()
