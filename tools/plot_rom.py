#!/usr/bin/env python3
"""Draws a reduced-order-model prediction (pdamp rom --out FILE.csv) as one PNG or SVG: the
response ratio |X/(F0/K)| (force) or |X/Y| (base) and the phase against frequency, one line per
branch, stable solid, unstable dashed, marginal or unknown dotted; arrows where a stepped sine
sweeping up or down jumps from one branch to another; triangles along the bottom (top) edge where
a solution lies below (above) the characterised amplitudes.

usage: tools/plot_rom.py PREDICTION.csv [--out FILE.png|.svg] [--title TEXT]
       (default output: PREDICTION.png). Needs Debian's python3-matplotlib.
"""
import argparse
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {"stable": "-", "unstable": "--"}


def read(path):
    header, rows = {}, []
    with open(path, newline="") as file:
        lines = []
        for line in file:
            if line.startswith("#"):
                key, _, value = line[1:].partition("=")
                if value:
                    header[key.strip()] = value.strip()
            else:
                lines.append(line)
    if not header.get("format", "").startswith("pdamp rom prediction"):
        sys.exit(f"plot_rom: {path} is not a pdamp rom prediction (its '# format =' line)")
    for row in csv.DictReader(lines):
        rows.append(row)
    return header, rows


def runs(points):
    """Consecutive points of one branch with one stability, joined where the stability changes."""
    out, current = [], []
    for p in points:
        if current and p["stability"] != current[-1]["stability"]:
            out.append(current)
            current = [current[-1]]
        current.append(p)
    if current:
        out.append(current)
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("prediction")
    parser.add_argument("--out")
    parser.add_argument("--title")
    args = parser.parse_args()
    header, rows = read(args.prediction)
    out = args.out or args.prediction.rsplit(".", 1)[0] + ".png"

    branches = {}
    outside = []
    for r in rows:
        if r["branch"]:
            branches.setdefault(int(r["branch"]), []).append(
                {"f": float(r["frequency_hz"]), "ratio": float(r["response_ratio"]),
                 "phase": float(r["phase_deg"]), "stability": r["stability"],
                 "up": r["sweep_up"] == "1", "down": r["sweep_down"] == "1"})
        else:
            outside.append((float(r["frequency_hz"]), r["flags"]))

    fig, (ax_a, ax_p) = plt.subplots(2, 1, figsize=(8, 8), sharex=True)
    fig.suptitle(args.title or f"{header.get('table', args.prediction)}\n{header.get('excitation', '')}", fontsize=9)
    for branch, points in sorted(branches.items()):
        color = f"C{(branch - 1) % 10}"
        for run in runs(points):
            style = STYLE.get(run[-1]["stability"], ":")
            f = [p["f"] for p in run]
            ax_a.plot(f, [p["ratio"] for p in run], style, color=color)
            ax_p.plot(f, [p["phase"] for p in run], style, color=color)
        ax_a.plot([], [], "-", color=color, label=f"branch {branch}")
    for direction, color in (("up", "tab:red"), ("down", "tab:purple")):
        path = sorted(((p["f"], p["ratio"], branch) for branch, ps in branches.items() for p in ps if p[direction]),
                      reverse=(direction == "down"))
        for (f0, a0, b0), (f1, a1, b1) in zip(path, path[1:]):
            if b0 != b1:
                ax_a.annotate("", xy=(f1, a1), xytext=(f0, a0),
                              arrowprops=dict(arrowstyle="->", color=color, linewidth=1.0))
        ax_a.plot([], [], "-", color=color, linewidth=1.0, label=f"jump of a stepped sine sweeping {direction}")
    ax_a.set_yscale("log")
    marks = {"solution_below_grid": ("v", 0.02, "a solution below the table's amplitudes"),
             "solution_above_grid": ("^", 0.98, "a solution above the table's amplitudes"),
             "not_covered": ("x", 0.5, "the table covers no amplitude")}
    for flag, (marker, y, label) in marks.items():
        f = [f for f, flags in outside if flag in flags]
        if f:
            ax_a.plot(f, [y] * len(f), marker, color="0.4", markersize=4, label=label,
                      transform=ax_a.get_xaxis_transform())
    ax_a.plot([], [], "--", color="k", label="unstable")
    ratio = "|X| K / F0" if "force" in header.get("excitation", "") else "|X| / Y"
    ax_a.set_ylabel(ratio)
    ax_a.legend(fontsize=8)
    ax_p.set_ylabel("phase (deg)")
    ax_p.set_xlabel("frequency (Hz)")
    for ax in (ax_a, ax_p):
        ax.grid(True, which="both", linewidth=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print(f"plot_rom: wrote {out}")


if __name__ == "__main__":
    main()
