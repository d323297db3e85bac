#!/usr/bin/env python3
"""Draws a stored frequency-response study ([frf], pdamp study run) as one PNG or SVG:
the normalised amplitude |X/(F0/K)| (or X/Y under base motion) and the phase against the
frequency, one curve per model, level, direction and combination of the [frf] section's
grid keys (the host alone dashed, points that did not settle circled in red), and the bed's
apparent mass m_app/m_p and equivalent damping c_eq against Gamma. Only completed points are drawn. Reads the store's study_frf view with
Python's sqlite3; `pdamp study plot` runs this script with Debian's /usr/bin/python3.

usage: tools/plot_frf.py --study ID [--db pdamp.sqlite] [--out FILE.png|.svg]
"""
import argparse
import math

from plot_common import fail, open_study, pyplot, save

PROGRAM = "plot_frf"


def curves(db, study):
    """{curve: (model, direction, host_alone, mode, level, grid, [row...])}, rows by step."""
    found = {}
    for row in db.execute(
            "SELECT curve, model, direction, host_alone, mode, level, grid, frequency_hz, normalised_amplitude, "
            "phase_rad, gamma, apparent_mass_ratio, equivalent_damping_N_s_m, settled FROM study_frf "
            "WHERE study_id = ? AND status = 'completed' ORDER BY curve, step", (study,)):
        found.setdefault(row[0], (*row[1:7], []))[6].append(row[7:])
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--db", default="pdamp.sqlite")
    parser.add_argument("--study", type=int, required=True)
    parser.add_argument("--out")
    args = parser.parse_args()
    plt = pyplot(PROGRAM)
    db, row = open_study(PROGRAM, args.db, args.study)
    found = curves(db, args.study)
    if not found:
        fail(PROGRAM, f"study {args.study} has no completed frequency-response point to draw", 1)
    # A colour per level and grid combination; the host alone black, or by its grid values.
    kinds = sorted({(c[5], c[4]) for c in found.values() if not c[2]})
    colour = {kind: f"C{i % 10}" for i, kind in enumerate(kinds)}
    alone_grids = sorted({c[5] for c in found.values() if c[2]})
    alone_colour = {grid: "black" if len(alone_grids) == 1 else f"C{i % 10}" for i, grid in enumerate(alone_grids)}
    base = any(c[3] == "base" for c in found.values())
    unit = "m" if base else "N"

    fig, ((amp, phase), (mass, damping)) = plt.subplots(2, 2, figsize=(13, 9))
    fig.suptitle(f"study {args.study} '{row[0]}': stepped-sine frequency response")
    for curve, (model, direction, alone, mode, level, grid, rows) in sorted(found.items()):
        f = [r[0] for r in rows]
        style = dict(color=alone_colour[grid], linestyle="--", marker=None, linewidth=1) if alone else dict(
            color=colour[(grid, level)], linestyle="-" if direction == "up" else ":",
            marker="o" if model == "hard" else "s", markersize=3 if direction == "up" else 5,
            markerfacecolor="none" if direction == "down" else None)
        label = "host alone" if alone else f"{model}, {level:g} {unit}, {direction}"
        if grid:
            label += f" ({grid})"
        amp.plot(f, [r[1] for r in rows], label=label, **style)
        phase.plot(f, [math.degrees(r[2]) for r in rows], **style)
        unsettled = [r for r in rows if not r[6]]
        for ax, y in ((amp, lambda r: r[1]), (phase, lambda r: math.degrees(r[2]))):
            ax.plot([r[0] for r in unsettled], [y(r) for r in unsettled], linestyle="none", marker="o", markersize=9,
                    markerfacecolor="none", markeredgecolor="red")
        if not alone:
            g = [r[3] for r in rows]
            mass.plot(g, [r[4] for r in rows], linestyle="none", **{k: v for k, v in style.items() if k != "linestyle"})
            damping.plot(g, [r[5] for r in rows], linestyle="none",
                         **{k: v for k, v in style.items() if k != "linestyle"})
    amp.plot([], [], linestyle="none", marker="o", markerfacecolor="none", markeredgecolor="red", label="not settled")
    amp.set_ylabel("X/Y" if base else "|X/(F0/K)|")
    amp.set_yscale("log")
    phase.set_ylabel("phase of the host (deg; < 0: it lags)")
    for ax in (amp, phase):
        ax.set_xlabel("frequency (Hz)")
        ax.grid(True, alpha=0.3)
    mass.set_ylabel("apparent mass m_app / m_p")
    damping.set_ylabel("equivalent damping c_eq (N s/m)")
    for ax in (mass, damping):
        ax.set_xlabel("Gamma = X w^2 / g")
        ax.set_xscale("log")
        ax.grid(True, alpha=0.3)
    amp.legend(fontsize="x-small", ncol=2)
    save(fig, args.out, args.study)


if __name__ == "__main__":
    main()
