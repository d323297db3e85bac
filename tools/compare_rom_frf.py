#!/usr/bin/env python3
"""The reduced model against the full simulation (docs/characterisation.md): for each force
level of a stored [frf] study, the ROM's prediction (pdamp rom, from a stored
characterisation or a table file) for the same host over the same frequencies, overlaid in
one figure, and per level the resonance frequency and the peak amplitude of both with their
errors.

The full simulation's peak is the vertex of the parabola through its highest point and its
two neighbours (the grid's step would otherwise bound the frequency's resolution); the ROM's
is the highest solution a stepped sine holds in the curve's direction (up or down, the
ROM's sweep_up or sweep_down branch), on a grid ten times finer.

usage: tools/compare_rom_frf.py --frf-db FRF.sqlite --frf-study ID (--char-db CHAR.sqlite --char-study ID | --table FILE)
                                [--pdamp build/ci/src/pdamp] [--out FILE.png] [--model hard]
       tools/compare_rom_frf.py --case FRF.sqlite ID TABLE [--case ...] [--pdamp ...] [--out FILE.png] [--model hard]
           one panel per case (an [frf] study and the table file to predict it with), two a row
"""
import argparse
import csv
import io
import os
import sqlite3
import subprocess
import tempfile

from plot_common import fail, pyplot, save

PROGRAM = "compare_rom_frf"


def host_of(db, study):
    """(M, K, C) of the study's base scenario as its first run resolved it."""
    text = db.execute("SELECT r.scenario_text FROM runs r JOIN study_point_runs l USING (run_id) "
                      "WHERE l.study_id = ? LIMIT 1", (study,)).fetchone()
    if text is None:
        fail(PROGRAM, f"study {study} has no run")
    values, section = {}, ""
    for line in text[0].splitlines():
        if line.startswith("["):
            section = line.strip("[]")
        elif " = " in line:
            key, value = line.split(" = ", 1)
            values[f"{section}.{key}"] = value
    return tuple(float(values[k]) for k in ("host.mass_kg", "host.stiffness_N_m", "host.damping_N_s_m"))


def frf_curves(db, study, model):
    """{(level, direction): [(f, X/(F0/K), settled)]} of the curves with particles, completed
    points only, by frequency."""
    curves = {}
    for level, direction, f, x, settled in db.execute(
            "SELECT level, direction, frequency_hz, normalised_amplitude, settled FROM study_frf WHERE study_id = ? "
            "AND status = 'completed' AND NOT host_alone AND mode = 'force' AND model = ? "
            "ORDER BY level, direction DESC, frequency_hz", (study, model)):
        curves.setdefault((level, direction), []).append((f, x, settled))
    return curves


def parabola_peak(points):
    """(f, X) of the vertex through the highest point and its neighbours (the point itself at an end)."""
    k = max(range(len(points)), key=lambda i: points[i][1])
    if k == 0 or k == len(points) - 1:
        return points[k][0], points[k][1]
    (f0, y0), (f1, y1), (f2, y2) = [(p[0], p[1]) for p in points[k - 1:k + 2]]
    denominator = (f0 - f1) * (f0 - f2) * (f1 - f2)
    a = (f2 * (y1 - y0) + f1 * (y0 - y2) + f0 * (y2 - y1)) / denominator
    b = (f2 * f2 * (y0 - y1) + f1 * f1 * (y2 - y0) + f0 * f0 * (y1 - y2)) / denominator
    c = y0 - a * f0 * f0 - b * f0
    vertex = -b / (2 * a)
    return vertex, c - b * b / (4 * a)


def rom_curve(pdamp, table, host, level, f_start, f_stop, count):
    """Rows of pdamp rom's prediction (CSV) for a force level; `table`: pdamp rom's options naming it."""
    mass, stiffness, damping = host
    command = [pdamp, "rom"] + table + [
               "--mass", repr(mass), "--stiffness", repr(stiffness), "--damping", repr(damping), "--force",
               repr(level), "--freq", f"{f_start!r}:{f_stop!r}:{count}", "--quiet"]
    with tempfile.TemporaryDirectory() as folder:
        out = os.path.join(folder, "prediction.csv")
        result = subprocess.run(command + ["--out", out], capture_output=True, text=True)
        if result.returncode != 0:
            fail(PROGRAM, f"{' '.join(command)}: {result.stderr.strip()}", 1)
        with open(out) as text:
            lines = [line for line in text if not line.startswith("#")]
    return list(csv.DictReader(io.StringIO("".join(lines))))


def draw_case(ax, case, pdamp, model):
    """One study against its ROM in `ax`; prints the per-level table."""
    db = sqlite3.connect(f"file:{case['frf_db']}?mode=ro", uri=True)
    host = host_of(db, case["study"])
    curves = frf_curves(db, case["study"], model)
    if not curves:
        fail(PROGRAM, f"study {case['study']} of {case['frf_db']} has no completed curve of the {model} model "
             "under a force", 1)
    print(f"{case['frf_db']}, study {case['study']}; ROM: {case['source']}")
    print("level_N  sweep  f_res_full_Hz  f_res_rom_Hz  f_error  peak_full  peak_rom  peak_error  full_unsettled")
    levels = sorted({level for level, _ in curves})
    for (level, direction), points in sorted(curves.items(), key=lambda c: (c[0][0], c[0][1] != "up")):
        f_start, f_stop = points[0][0], points[-1][0]
        rows = rom_curve(pdamp, case["table"], host, level, f_start, f_stop, 10 * (len(points) - 1) + 1)
        branch = [(float(r["frequency_hz"]), float(r["response_ratio"])) for r in rows
                  if r[f"sweep_{direction}"] == "1"]
        solutions = [(float(r["frequency_hz"]), float(r["response_ratio"]), r["stability"]) for r in rows
                     if r["response_ratio"]]
        flagged = sorted({flag for r in rows for flag in r["flags"].split(";") if flag})
        f_full, x_full = parabola_peak(points)
        f_rom, x_rom = max(branch, key=lambda p: p[1])
        unsettled = sum(1 for p in points if not p[2])
        print(f"{level:<8g} {direction:<6} {f_full:<14.3f} {f_rom:<13.3f} {(f_rom - f_full) / f_full:<+8.2%} "
              f"{x_full:<10.3f} {x_rom:<9.3f} {(x_rom - x_full) / x_full:<+11.1%} {unsettled}"
              + (f"  (ROM flags: {', '.join(flagged)})" if flagged else ""))
        colour = f"C{levels.index(level)}"
        line = "-" if direction == "up" else ":"
        ax.plot([p[0] for p in points], [p[1] for p in points], linestyle="none",
                marker="o" if direction == "up" else "v", color=colour,
                label=f"full simulation, {level:g} N, {direction}")
        unsettled_points = [p for p in points if not p[2]]
        ax.plot([p[0] for p in unsettled_points], [p[1] for p in unsettled_points], linestyle="none", marker="o",
                markersize=10, markerfacecolor="none", markeredgecolor="red")
        ax.plot([p[0] for p in branch], [p[1] for p in branch], color=colour, linestyle=line,
                label=f"ROM, {level:g} N (sweep {direction})")
        unstable = [s for s in solutions if s[2] != "stable"]
        ax.plot([s[0] for s in unstable], [s[1] for s in unstable], linestyle="none", marker=".", color=colour,
                alpha=0.5)
        ax.plot([f_full], [x_full], marker="+", markersize=14, color=colour)
    ax.plot([], [], linestyle="none", marker="o", markerfacecolor="none", markeredgecolor="red", label="not settled")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("|X| / (F0/K)")
    ax.set_title(f"ROM ({case['source']}) against the full simulation (FRF study {case['study']}),\n"
                 f"M = {host[0]:g} kg, K = {host[1]:g} N/m, C = {host[2]:g} N s/m", fontsize="small")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="x-small")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frf-db")
    parser.add_argument("--frf-study", type=int)
    parser.add_argument("--char-db")
    parser.add_argument("--char-study", type=int)
    parser.add_argument("--table", help="a damper table file instead of a stored characterisation")
    parser.add_argument("--case", nargs=3, action="append", metavar=("FRF_DB", "FRF_STUDY", "TABLE"),
                        help="an [frf] study and the table file that predicts it: one panel each")
    parser.add_argument("--model", default="hard")
    parser.add_argument("--pdamp", default="build/ci/src/pdamp")
    parser.add_argument("--out")
    args = parser.parse_args()
    cases = []
    for frf_db, study, table in args.case or []:
        if not study.isdigit():
            fail(PROGRAM, f"--case {frf_db} {study} {table}: the study id '{study}' is not a whole number")
        cases.append({"frf_db": frf_db, "study": int(study), "table": ["--table", table], "source": table})
    if args.frf_db or args.frf_study is not None:
        if not (args.frf_db and args.frf_study is not None):
            fail(PROGRAM, "give --frf-db and --frf-study together")
        if bool(args.table) == bool(args.char_db and args.char_study):
            fail(PROGRAM, "give --char-db and --char-study (a stored characterisation), or --table FILE")
        table = ["--table", args.table] if args.table else ["--study", str(args.char_study), "--db", args.char_db,
                                                            "--model", args.model]
        cases.insert(0, {"frf_db": args.frf_db, "study": args.frf_study, "table": table,
                         "source": args.table or f"characterisation {args.char_study}"})
    if not cases:
        fail(PROGRAM, "give --frf-db and --frf-study with a table, or one --case or more")
    plt = pyplot(PROGRAM)
    columns = min(2, len(cases))
    rows = (len(cases) + columns - 1) // columns
    fig, axes = plt.subplots(rows, columns, figsize=(9 * columns, 6 * rows), squeeze=False)
    for ax, case in zip(axes.flat, cases):
        draw_case(ax, case, args.pdamp, args.model)
    for ax in list(axes.flat)[len(cases):]:
        ax.set_visible(False)
    save(fig, args.out, cases[0]["study"])


if __name__ == "__main__":
    main()
