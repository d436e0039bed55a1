#!/usr/bin/env python3
"""Figures of `overstep identify --plots DIR`: DIR/residuals.csv (channel, label, t, held_out,
before, after; physical units) and DIR/summary.json -> DIR/fig_residuals.png (per channel: the
residual's RMS over its signals at each time, before and after the identified effect, the
held-out part shaded), DIR/fig_autocorr.png (per channel: autocorrelation of the held-out
residual before and after), DIR/plots.json (the manifest). Usage: residual_plots.py DIR [DPI]."""
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main():
    out = sys.argv[1]
    dpi = int(sys.argv[2]) if len(sys.argv) > 2 else 80
    summary = json.load(open(os.path.join(out, "summary.json")))
    units = {name: c.get("unit", "") for name, c in summary.get("channels", {}).items()}
    series = {}  # channel -> label -> lists
    with open(os.path.join(out, "residuals.csv")) as f:
        for r in csv.DictReader(f):
            s = series.setdefault(r["channel"], {}).setdefault(r["label"], ([], [], [], []))
            s[0].append(float(r["t"]))
            s[1].append(r["held_out"] == "1")
            s[2].append(float(r["before"]))
            s[3].append(float(r["after"]))
    channels = [c for c in series]
    if not channels:
        raise SystemExit("residual_plots: no residual rows")
    effect = summary.get("effect") or "-"
    title = "verdict %s, effect %s" % (summary.get("verdict", "?"), effect)

    fig, axes = plt.subplots(len(channels), 1, figsize=(9, 2.2 * len(channels)), squeeze=False)
    for ax, ch in zip(axes[:, 0], channels):
        labels = series[ch]
        t = np.array(next(iter(labels.values()))[0])
        n = min(len(v[0]) for v in labels.values())
        before = np.sqrt(np.mean([np.square(v[2][:n]) for v in labels.values()], axis=0))
        after = np.sqrt(np.mean([np.square(v[3][:n]) for v in labels.values()], axis=0))
        held = np.array(next(iter(labels.values()))[1][:n])
        ax.plot(t[:n], before, lw=0.8, label="before")
        ax.plot(t[:n], after, lw=0.8, label="after (%s)" % effect)
        if held.any():
            ax.axvspan(t[:n][held][0], t[:n][-1], color="0.9", zorder=-1, label="held out")
        ax.set_ylabel("%s\n[%s]" % (ch, units.get(ch, "")), fontsize=8)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("plan time [s]")
    fig.suptitle("Residual RMS over each channel's signals: " + title, fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fig_residuals.png"), dpi=dpi)
    plt.close(fig)

    fig, axes = plt.subplots(1, len(channels), figsize=(2.6 * len(channels), 2.6), squeeze=False)
    lags = 40
    for ax, ch in zip(axes[0, :], channels):
        for k, name in ((2, "before"), (3, "after")):
            acs = []
            for v in series[ch].values():
                x = np.array([v[k][i] for i in range(len(v[0])) if v[1][i]])
                if len(x) <= lags + 2 or not np.any(x):
                    continue
                # About zero, not the mean: a constant offset (a bias, a payload) is structure.
                den = np.dot(x, x)
                acs.append([np.dot(x[: len(x) - j], x[j:]) / den for j in range(lags + 1)])
            if acs:
                ax.plot(np.mean(acs, axis=0), lw=1, label=name)
        ax.axhline(0, color="0.5", lw=0.5)
        ax.set_title(ch, fontsize=8)
        ax.set_xlabel("lag [rows]", fontsize=7)
        ax.legend(fontsize=7)
    fig.suptitle("Autocorrelation of the held-out residual (mean over signals): " + title, fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fig_autocorr.png"), dpi=dpi)
    plt.close(fig)
    json.dump({"figures": [{"file": "fig_residuals.png"}, {"file": "fig_autocorr.png"}]},
              open(os.path.join(out, "plots.json"), "w"), indent=2)


if __name__ == "__main__":
    main()
