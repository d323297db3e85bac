#!/usr/bin/env python3
"""Draws a stored study (pdamp study run) as one PNG or SVG: a point metric against a
swept key, one curve per model (and per value of the section's other swept keys), one
panel per sweep section. Only completed points are drawn. Reads the store with Python's
sqlite3; `pdamp study plot` runs this script with Debian's /usr/bin/python3.

usage: tools/plot_study.py --study ID [--db pdamp.sqlite] [--metric psi_peak] [--x KEY] [--out FILE.png|.svg]
       (default x: the section's key with the most values; default out: study-ID.png)
"""
import argparse

from plot_common import fail as fail_with, open_study, pyplot, save

METRICS = {
    "psi_peak": "peak specific damping capacity psi",
    "psi_peak_gamma": "Gamma at the psi peak",
    "dissipated_total_J": "energy dissipated (J)",
    "dissipated_impact_J": "energy dissipated by impact (J)",
    "dissipated_friction_J": "energy dissipated by friction (J)",
    "dissipated_viscous_J": "energy dissipated by the host damper (J)",
    "final_amplitude_m": "amplitude of the last cycle (m)",
    "cycles": "cycles",
    "energy_balance_rel_err": "energy balance error (relative)",
    "wall_time_s": "wall time (s)",
}


def fail(message, code=2):
    fail_with("plot_study", message, code)


def load(db, study):
    """Points of the study: {point: (section, {key: (value, number)})}, and completed metrics."""
    points = {}
    for point, section in db.execute("SELECT point, section FROM study_points WHERE study_id = ? ORDER BY point",
                                     (study,)):
        points[point] = (section, {})
    for point, key, value, number in db.execute(
            "SELECT point, key, value, number FROM study_point_values WHERE study_id = ?", (study,)):
        points[point][1][key] = (value, number)
    return points


def swept_keys(points):
    """Keys with more than one value among the points, most values first."""
    values = {}
    for _, keys in points.values():
        for key, (value, _) in keys.items():
            values.setdefault(key, set()).add(value)
    return sorted((k for k, v in values.items() if len(v) > 1), key=lambda k: (-len(values[k]), k))


def follows(points, key, x):
    """True if every value of x comes with one value of key."""
    seen = {}
    for _, keys in points.values():
        seen.setdefault(keys[x][0], set()).add(keys[key][0])
    return all(len(values) == 1 for values in seen.values())


def draw_section(ax, section, points, metric_rows, metric, x_key):
    swept = swept_keys(points)
    if not swept:
        ax.set_title(f"[{section}]: one point, nothing swept")
        return
    x = x_key if x_key in swept else swept[0]
    # A key that takes one value for each value of x (zipped with it) moves along the curve;
    # the other swept keys give one curve per value.
    others = [k for k in swept if k != x and not follows(points, k, x)]
    numeric = all(keys[x][1] is not None for _, keys in points.values())
    categories = []
    for _, keys in points.values():
        if keys[x][0] not in categories:
            categories.append(keys[x][0])
    curves = {}  # (values of the other keys, model) -> [(x, y)]
    for (point, model), y in metric_rows.items():
        if point not in points:
            continue
        keys = points[point][1]
        position = keys[x][1] if numeric else categories.index(keys[x][0])
        curves.setdefault((tuple(keys[k][0] for k in others), model), []).append((position, y))
    # One colour for each value of the other keys, one line style for each model.
    colours = {values: f"C{i}" for i, values in enumerate(sorted({values for values, _ in curves}))}
    for (values, model), xy in sorted(curves.items()):
        xy.sort()
        label = ", ".join([model] + [f"{k} = {v}" for k, v in zip(others, values)])
        ax.plot([p for p, _ in xy], [y for _, y in xy], marker="o", label=label, color=colours[values],
                linestyle="-" if model == "soft" else "--")
    if numeric:
        xs = [keys[x][1] for _, keys in points.values()]
        if min(xs) > 0 and max(xs) / min(xs) > 100:
            ax.set_xscale("log")
    else:
        ax.set_xticks(range(len(categories)))
        ax.set_xticklabels(categories)
    ax.set_xlabel(x)
    ax.set_ylabel(METRICS[metric])
    ax.set_title(f"[{section}]")
    if curves:
        ax.legend(fontsize="small")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--db", default="pdamp.sqlite")
    parser.add_argument("--study", type=int, required=True)
    parser.add_argument("--metric", default="psi_peak")
    parser.add_argument("--x")
    parser.add_argument("--out")
    args = parser.parse_args()
    if args.metric not in METRICS:
        fail(f"--metric '{args.metric}' is not a metric; choose one of {', '.join(METRICS)}")
    plt = pyplot("plot_study")
    db, (name, models) = open_study("plot_study", args.db, args.study, "name, models")
    points = load(db, args.study)
    metric_rows = {(point, model): y for point, model, y in db.execute(
        f"SELECT point, model, {args.metric} FROM study_results WHERE study_id = ? AND status = 'completed' "
        f"AND {args.metric} IS NOT NULL", (args.study,))}
    sections = []
    for section, _ in points.values():
        if section not in sections:
            sections.append(section)
    if args.x and not any(args.x in swept_keys({p: v for p, v in points.items() if v[0] == s}) for s in sections):
        fail(f"--x '{args.x}' is not swept in study {args.study}")

    fig, axes = plt.subplots(len(sections), 1, figsize=(8, 4.5 * len(sections)), squeeze=False)
    fig.suptitle(f"study {args.study} '{name}' ({models}): {args.metric}")
    for ax, section in zip(axes[:, 0], sections):
        draw_section(ax, section, {p: v for p, v in points.items() if v[0] == section}, metric_rows, args.metric,
                     args.x)
    save(fig, args.out, args.study)


if __name__ == "__main__":
    main()
