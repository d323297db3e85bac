#!/usr/bin/env python3
"""Draws a stored characterisation ([characterise], pdamp study run) as one PNG or SVG: the
bed's apparent mass m_app/m_p and equivalent damping c_eq/(m_p w) against Gamma, one curve
per frequency (hard solid with circles, soft dashed with squares; the empty container
dotted), and the fractions of the cycle the bed touches the floor and the lid. Points that
did not settle are circled in red. Only completed points are drawn. Reads the store's
study_characterisation view; `pdamp study plot` runs this script with /usr/bin/python3.

usage: tools/plot_characterisation.py --study ID [--db pdamp.sqlite] [--out FILE.png|.svg]
"""
import argparse

from plot_common import fail, open_study, pyplot, save

PROGRAM = "plot_characterisation"


def curves(db, study):
    """{curve: (model, empty, frequency, [row...])}, rows along the amplitude axis."""
    found = {}
    for row in db.execute(
            "SELECT curve, model, empty, frequency_hz, gamma, apparent_mass_ratio, damping_ratio, "
            "floor_contact_fraction, lid_contact_fraction, settled FROM study_characterisation "
            "WHERE study_id = ? AND status = 'completed' ORDER BY curve, step", (study,)):
        curve, model, empty, frequency = row[:4]
        found.setdefault(curve, (model, empty, frequency, []))[3].append(row[4:])
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--db", default="pdamp.sqlite")
    parser.add_argument("--study", type=int, required=True)
    parser.add_argument("--out")
    args = parser.parse_args()
    plt = pyplot(PROGRAM)
    db, (name,) = open_study(PROGRAM, args.db, args.study)
    found = curves(db, args.study)
    if not found:
        fail(PROGRAM, f"study {args.study} has no completed characterisation point to draw", 1)
    frequencies = sorted({c[2] for c in found.values()})
    colour = {f: f"C{i}" for i, f in enumerate(frequencies)}

    fig, ((mass, damping), (floor, lid)) = plt.subplots(2, 2, figsize=(13, 9), sharex=True)
    fig.suptitle(f"study {args.study} '{name}': the damper driven with z = A sin(2 pi f t)")
    panels = ((mass, 1), (damping, 2), (floor, 3), (lid, 4))
    for curve, (model, empty, frequency, rows) in sorted(found.items()):
        style = dict(color=colour[frequency], linestyle=":" if empty else "-" if model == "hard" else "--",
                     marker="o" if model == "hard" else "s", markersize=4)
        label = f"{model}{' empty' if empty else ''}, {frequency:g} Hz"
        gamma = [r[0] for r in rows]
        for ax, column in panels:
            ax.plot(gamma, [r[column] if r[column] is not None else 0.0 for r in rows],
                    label=label if ax is mass else None, **style)
            unsettled = [r for r in rows if not r[5]]
            ax.plot([r[0] for r in unsettled], [r[column] or 0.0 for r in unsettled], linestyle="none", marker="o",
                    markersize=9, markerfacecolor="none", markeredgecolor="red")
    mass.plot([], [], linestyle="none", marker="o", markerfacecolor="none", markeredgecolor="red", label="not settled")
    mass.set_ylabel("apparent mass m_app / m_p")
    damping.set_ylabel("equivalent damping c_eq / (m_p w)")
    floor.set_ylabel("fraction of the cycle touching the floor")
    lid.set_ylabel("fraction of the cycle touching the lid")
    for ax, _ in panels:
        ax.set_xscale("log")
        ax.grid(True, alpha=0.3)
    for ax in (floor, lid):
        ax.set_xlabel("Gamma = A w^2 / g")
    mass.legend(fontsize="x-small", ncol=2)
    save(fig, args.out, args.study)


if __name__ == "__main__":
    main()
