#!/usr/bin/env python3
"""How much of a bed is in contact: for each snapshot of a run (pdamp run --snapshots), the
share of spheres that overlap another sphere, the side wall or a cap, and the sphere pairs
in contact. What a hybrid model (the soft law for lasting contacts, free flight
event-driven) would have to time-step; docs/hard-engine.md, "The hybrid's bound".

Usage: tools/contact_share.py SNAPSHOT_FOLDER   (the folder of one run's .vtp files)
Needs Debian's python3-vtk9 and numpy.
"""
import glob
import os
import sys

import numpy as np
from vtk.util.numpy_support import vtk_to_numpy

from render_snapshot import read


def frame(spheres_path):
    """The share of spheres touching anything, and the sphere pairs in contact."""
    spheres = read(spheres_path)
    x = vtk_to_numpy(spheres.GetPoints().GetData()).astype(float)
    r = vtk_to_numpy(spheres.GetPointData().GetArray("radius_m")).astype(float)
    # The cavity is drawn at the host's position: its bounds give the radius and the caps.
    xmin, xmax, _, _, zmin, zmax = read(spheres_path.replace("spheres_", "cavity_")).GetBounds()
    cavity_radius = 0.5 * (xmax - xmin)
    distance = np.sqrt(((x[:, None, :] - x[None, :, :]) ** 2).sum(-1))
    touching = distance < r[:, None] + r[None, :]
    np.fill_diagonal(touching, False)
    wall = (np.hypot(x[:, 0], x[:, 1]) + r > cavity_radius) | (x[:, 2] - r < zmin) | (x[:, 2] + r > zmax)
    return (touching.any(axis=1) | wall).mean(), touching.sum() // 2


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__.split("\n\n")[1])
    folder = sys.argv[1]
    paths = sorted(glob.glob(os.path.join(folder, "spheres_*.vtp")))
    if not paths:
        sys.exit(f"contact_share.py: no spheres_*.vtp in '{folder}' (give the folder of one run's snapshots)")
    shares, pairs = zip(*(frame(p) for p in paths))
    shares = np.array(shares)
    print(f"{len(paths)} snapshots: share of spheres touching mean {shares.mean():.3f}, "
          f"min {shares.min():.3f}, max {shares.max():.3f}; sphere pairs in contact mean {np.mean(pairs):.0f}")


if __name__ == "__main__":
    main()
