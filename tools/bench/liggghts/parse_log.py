#!/usr/bin/env python3
"""Extract the measured-phase numbers from a LIGGGHTS shake log.
usage: parse_log.py LOG  -> prints: natoms steps loop_s throughput mean_contacts neighs builds"""
import re, sys
txt = open(sys.argv[1]).read()
meas = txt.split("BENCH_PHASE measure", 1)[1]
m = re.search(r"Loop time of ([0-9.eE+-]+) on \d+ procs for (\d+) steps with (\d+) atoms", meas)
loop, steps, natoms = float(m.group(1)), int(m.group(2)), int(m.group(3))
body = meas[:m.start()]
hdr = None; rows = []
for line in body.splitlines():
    f = line.split()
    if f and f[0] == "Step":
        hdr = f; continue
    if hdr and len(f) == len(hdr):
        try: rows.append([float(x) for x in f])
        except ValueError: pass
ic = [h[:8] for h in hdr].index("ncontact")
vals = [r[ic] for r in rows[1:]]          # skip the setup line (state before the measured steps)
neighs = re.search(r"Total # of neighbors = (\d+)", meas).group(1)
builds = re.search(r"Neighbor list builds = (\d+)", meas).group(1)
print(natoms, steps, f"{loop:.3f}", f"{natoms*steps/loop:.4e}", f"{sum(vals)/len(vals):.1f}", neighs, builds)
