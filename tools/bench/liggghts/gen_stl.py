#!/usr/bin/env python3
"""Write an ASCII STL of a closed vertical cylinder (lateral wall + bottom + top caps).

usage: gen_stl.py D H out.stl [facet_size]
Axis = z, bottom at z=0, top at z=H (SI units, metres).
The polygon vertices are placed at radius R/cos(pi/n) so that the flat facets
lie at distance R from the axis (the same wall position as the primitive
zcylinder of radius R)."""
import math, sys

def ring(r, n, z, phase=0.0):
    return [(r*math.cos(2*math.pi*(i+phase)/n), r*math.sin(2*math.pi*(i+phase)/n), z) for i in range(n)]

def stitch(a, b):
    """triangulate the band between two closed rings a (inner) and b (outer) with different point counts"""
    tris = []
    na, nb = len(a), len(b)
    ang = lambda p: math.atan2(p[1], p[0]) % (2*math.pi)
    ia = ib = 0
    # walk both rings in order of angle
    while ia < na or ib < nb:
        pa0, pa1 = a[ia % na], a[(ia+1) % na]
        pb0, pb1 = b[ib % nb], b[(ib+1) % nb]
        ta = (ia+1)/na if na else 2
        tb = (ib+1)/nb
        if ib >= nb or (ia < na and ta <= tb):
            tris.append((pa0, pa1, pb0)); ia += 1
        else:
            tris.append((pa0, pb1, pb0)); ib += 1
    return tris

def cap(R, n, z, fs):
    K = max(1, round(R/fs))
    tris = []
    centre = (0.0, 0.0, z)
    rings = []
    for k in range(1, K+1):
        nk = n if k == K else max(6, round(n*k/K))
        rings.append(ring(R*k/K if k < K else R, nk, z))
    # innermost: fan
    r0 = rings[0]
    for i in range(len(r0)):
        tris.append((centre, r0[i], r0[(i+1) % len(r0)]))
    for k in range(len(rings)-1):
        tris += stitch(rings[k], rings[k+1])
    return tris

def main():
    D, H, out = float(sys.argv[1]), float(sys.argv[2]), sys.argv[3]
    fs = float(sys.argv[4]) if len(sys.argv) > 4 else 0.5e-3
    R = 0.5*D
    n = max(16, 8*math.ceil(2*math.pi*R/fs/8))
    Rv = R/math.cos(math.pi/n)
    nz = max(1, round(H/(2*fs)))
    tris = []
    for j in range(nz):
        lo, hi = ring(Rv, n, H*j/nz), ring(Rv, n, H*(j+1)/nz)
        for i in range(n):
            i1 = (i+1) % n
            tris.append((lo[i], lo[i1], hi[i1]))
            tris.append((lo[i], hi[i1], hi[i]))
    tris += cap(Rv, n, 0.0, 2*fs)
    tris += cap(Rv, n, H, 2*fs)
    with open(out, "w") as f:
        f.write("solid cylinder\n")
        for t in tris:
            (ax, ay, az), (bx, by, bz), (cx, cy, cz) = t
            ux, uy, uz = bx-ax, by-ay, bz-az
            vx, vy, vz = cx-ax, cy-ay, cz-az
            nx, ny, nz_ = uy*vz-uz*vy, uz*vx-ux*vz, ux*vy-uy*vx
            l = math.sqrt(nx*nx+ny*ny+nz_*nz_) or 1.0
            f.write(f" facet normal {nx/l:.6e} {ny/l:.6e} {nz_/l:.6e}\n  outer loop\n")
            for p in t:
                f.write(f"   vertex {p[0]:.9e} {p[1]:.9e} {p[2]:.9e}\n")
            f.write("  endloop\n endfacet\n")
        f.write("endsolid cylinder\n")
    print(f"{out}: n_around={n} n_z={nz} triangles={len(tris)}")

if __name__ == "__main__":
    main()
