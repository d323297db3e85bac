#!/usr/bin/env python3
"""Draws a stored comparison of the two models (pdamp compare) as one PNG or SVG:
host displacement of both models over time, psi against Gamma for both, and the energy
dissipated by each mechanism over time. Reads the run store with Python's sqlite3.

usage: tools/plot_comparison.py [--db pdamp.sqlite] [--comparison ID] [--out FILE.png|.svg]
       (default: the latest comparison, written to comparison-ID.png)
"""
import argparse
import sqlite3
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--db", default="pdamp.sqlite")
    parser.add_argument("--comparison", type=int)
    parser.add_argument("--out")
    args = parser.parse_args()

    db = sqlite3.connect(f"file:{args.db}?mode=ro", uri=True)
    if args.comparison is None:
        row = db.execute("SELECT max(comparison_id) FROM comparisons").fetchone()
        if row[0] is None:
            sys.exit(f"plot_comparison: no comparison in {args.db} (run 'pdamp compare' first)")
        args.comparison = row[0]
    row = db.execute(
        "SELECT scenario_name, soft_run_id, hard_run_id, hard_restitution FROM comparisons WHERE comparison_id = ?",
        (args.comparison,)).fetchone()
    if row is None:
        sys.exit(f"plot_comparison: comparison {args.comparison} is not in {args.db}")
    scenario, soft, hard, restitution = row
    runs = {"soft": soft, "hard": hard}
    style = {"soft": dict(color="tab:blue"), "hard": dict(color="tab:red", linestyle="--")}

    fig, (ax_z, ax_psi, ax_e) = plt.subplots(3, 1, figsize=(8, 11))
    fig.suptitle(f"{scenario}: soft run {soft} vs hard run {hard} (restitution {restitution})")

    for model, run in runs.items():
        t, z = zip(*db.execute("SELECT t_s, host_z_m FROM samples WHERE run_id = ? ORDER BY t_s", (run,)))
        ax_z.plot(t, [1e3 * v for v in z], label=model, linewidth=0.8, **style[model])
    ax_z.set_xlabel("t (s)")
    ax_z.set_ylabel("host displacement z (mm)")
    ax_z.legend()

    for model, run in runs.items():
        cycles = db.execute("SELECT gamma, psi FROM cycles WHERE run_id = ? AND gamma > 0 ORDER BY cycle", (run,)).fetchall()
        if cycles:
            gamma, psi = zip(*cycles)
            ax_psi.plot(gamma, psi, marker="o", markersize=3, label=model, **style[model])
    ax_psi.set_xscale("log")
    ax_psi.ticklabel_format(axis="y", useOffset=False)
    ax_psi.set_xlabel("Gamma = A w^2 / g (per cycle)")
    ax_psi.set_ylabel("specific damping capacity psi")
    ax_psi.axvline(1.0, color="grey", linewidth=0.5)
    ax_psi.legend()

    colors = {"impact": "tab:orange", "friction": "tab:green", "viscous": "tab:purple"}
    for model, run in runs.items():
        samples = db.execute(
            "SELECT t_s, dissipated_impact_J, dissipated_friction_J, dissipated_viscous_J FROM samples "
            "WHERE run_id = ? ORDER BY t_s", (run,)).fetchall()
        t = [s[0] for s in samples]
        for k, mechanism in enumerate(("impact", "friction", "viscous")):
            ax_e.plot(t, [1e3 * s[k + 1] for s in samples], color=colors[mechanism],
                      linestyle="-" if model == "soft" else "--", label=f"{mechanism} ({model})")
    ax_e.set_xlabel("t (s)")
    ax_e.set_ylabel("energy dissipated (mJ)")
    ax_e.legend(ncol=2, fontsize="small")

    fig.tight_layout()
    out = args.out or f"comparison-{args.comparison}.png"
    fig.savefig(out, dpi=110)
    print(out)


if __name__ == "__main__":
    main()
